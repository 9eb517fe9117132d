"""The frame the fleet and sweep pages share with ``analyze``'s report: its stylesheet (package
data in html_assets/), a page head and foot, fact cards, and tables that scroll in their own box.

No clock, no network: the same arguments give the same text. Callers escape what they pass in.
"""

from __future__ import annotations

from importlib import resources
from typing import TYPE_CHECKING

from medkit_replay.outputs.html_tables import esc

if TYPE_CHECKING:
    from collections.abc import Iterable, Mapping, Sequence

SORT_SCRIPT = """
document.querySelectorAll("table.sortable").forEach(function (table) {
  table.querySelectorAll("th").forEach(function (th, column) {
    th.addEventListener("click", function () {
      var ascending = !th.classList.contains("asc");
      table.querySelectorAll("th").forEach(function (h) {
        h.classList.remove("asc", "desc"); h.removeAttribute("aria-sort");
      });
      th.classList.add(ascending ? "asc" : "desc");
      th.setAttribute("aria-sort", ascending ? "ascending" : "descending");
      var body = table.tBodies[0];
      var rows = Array.prototype.slice.call(body.rows);
      function key(row) {
        var cell = row.cells[column];
        var v = cell.getAttribute("data-v");
        return v === null ? cell.textContent : v;
      }
      rows.sort(function (a, b) {
        var x = key(a), y = key(b);
        if (x === "" || y === "") { return (x === "") - (y === ""); }
        var nx = Number(x), ny = Number(y);
        var c = (!isNaN(nx) && !isNaN(ny)) ? nx - ny : (x < y ? -1 : x > y ? 1 : 0);
        return ascending ? c : -c;
      });
      rows.forEach(function (row) { body.appendChild(row); });
    });
  });
});
"""
"""Sorts a ``table.sortable`` by the column whose heading is clicked (``data-v`` keys first)."""

_PAGE_STYLE = """
tr.failed td { background: #fdecea; }
.fail { color: #b42318; font-weight: 600; } .pass { color: #2b8a57; }
.table-wrap { background: var(--panel); border: 1px solid var(--line); }
.table-wrap table.data { border: 0; }
table.data td[data-v], table.data th.num { text-align: right; }
"""
"""What the fleet and sweep pages add to analyze's stylesheet."""


def asset(name: str) -> str:
    """One file of the report's assets (``report.css``, ``report.js``) as text."""
    return (resources.files("medkit_replay.outputs") / "html_assets" / name).read_text("utf-8")


def page_start(title: str, sub: str, extra_style: str = "") -> str:
    """The page up to its first section: head (analyze's stylesheet, then ``extra_style``),
    ``title`` as the window's title and the heading, and one line under it (``sub``, already
    HTML)."""
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        '<meta name="referrer" content="no-referrer">'
        f"<title>{esc(title)}</title><style>{asset('report.css')}{_PAGE_STYLE}{extra_style}"
        f'</style></head><body><main><header class="top"><h1>{esc(title)}</h1>'
        f'<p class="sub">{sub}</p></header>\n'
    )


def page_end() -> str:
    """The rest of the page: the sorting script."""
    return f"</main><script>{SORT_SCRIPT}</script></body></html>\n"


def cards(facts: Mapping[str, int]) -> str:
    """Figures as analyze's cards (a label above a number)."""
    body = "".join(
        f'<div class="card"><div class="k">{esc(key)}</div><div class="v">{value:,}</div></div>'
        for key, value in facts.items()
    )
    return f'<section class="cards">{body}</section>\n'


def scrolling_table(
    table_id: str,
    headers: Sequence[str],
    rows: Iterable[str],
    numeric: frozenset[str] = frozenset(),
) -> str:
    """A sortable table (rows already HTML) in a box that scrolls both ways: it never widens the
    page, however many columns or however long the text."""
    head = "".join(
        f'<th{" class=num" if name in numeric else ""} title="sort by {esc(name)}">{esc(name)}</th>'
        for name in headers
    )
    body = "\n".join(rows)
    return (
        f'<div class="table-wrap"><table id="{esc(table_id)}" class="data sortable">\n'
        f"<thead><tr>{head}</tr></thead>\n<tbody>\n{body}\n</tbody>\n</table></div>"
    )
