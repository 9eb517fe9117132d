"""A fleet's outputs: CSV and JSON tables, a self-contained HTML page, the terminal summary and
the progress bar shown while the runs go.

Every file is a function of the run summaries only (no clock, no host name, no absolute path
that was not given), so the same fleet always gives the same bytes. Text that comes from a
recording or a path is escaped for HTML and shown literally on the terminal. Each file is
written to a temporary file and renamed into place; a run the tables cannot hold becomes a
failed row instead of costing the whole report.
"""

from __future__ import annotations

import html
import io
import json
import math
from dataclasses import replace
from typing import TYPE_CHECKING, TextIO

import pandas as pd
from rich import box
from rich.console import Console
from rich.padding import Padding
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.table import Table
from rich.text import Text

from medkit_replay.fleet.stats import codes_table, overview, runs_table
from medkit_replay.outputs.atomic import write_bytes_atomic
from medkit_replay.outputs.csv_safety import write_frame
from medkit_replay.text import clip, printable, xml_text
from medkit_replay.version import __version__

if TYPE_CHECKING:
    from collections.abc import Sequence
    from pathlib import Path
    from types import TracebackType
    from typing import Self

    from medkit_replay.fleet.run import RunSummary

FILES = ("runs.csv", "runs.json", "codes.csv", "codes.json", "index.html")
"""What ``write_report`` writes into its folder."""
MAX_RUN_ROWS = 40
"""Runs listed on the terminal; the files have all of them."""
MAX_CODE_ROWS = 20
"""Codes listed on the terminal."""
MAX_ERROR_ROWS = 20
"""Failed recordings listed on the terminal."""
MAX_CELL_CHARS = 2000
"""Characters of a text cell in index.html; longer text is cut, saying how much."""


def _csv_frame(frame: pd.DataFrame) -> pd.DataFrame:
    """The table with its list columns joined into text (``A:3; B:1``) for CSV."""
    flat = frame.copy()
    if "top_codes" in flat:
        flat["top_codes"] = [
            "; ".join(f"{item['fault_code']}:{item['failed_reports']}" for item in items)
            for items in frame["top_codes"]
        ]
    for column in ("confirmed_codes", "budget_failures"):
        if column in flat:
            flat[column] = ["; ".join(items) for items in frame[column]]
    return flat


def to_csv(frame: pd.DataFrame) -> str:
    """A fleet table as CSV text (list columns joined, missing values empty, text cells a
    spreadsheet would run as formulas neutralised: see outputs/csv_safety.py)."""
    buffer = io.StringIO()
    write_frame(_csv_frame(frame), buffer)
    return buffer.getvalue()


def to_json(frame: pd.DataFrame) -> str:
    """A fleet table as a JSON array of records (lists stay lists, missing values null)."""
    records = json.loads(frame.to_json(orient="records", double_precision=10))
    return json.dumps(records, indent=2, ensure_ascii=False) + "\n"


def _texts(runs: Sequence[RunSummary]) -> dict[str, str]:
    runs_frame = runs_table(runs)
    codes_frame = codes_table(runs)
    return {
        "runs.csv": to_csv(runs_frame),
        "runs.json": to_json(runs_frame),
        "codes.csv": to_csv(codes_frame),
        "codes.json": to_json(codes_frame),
        "index.html": render_html(runs, runs_frame, codes_frame),
    }


def _text(value: str) -> str:
    """Text every writer can encode: a lone surrogate (a file name that is not UTF-8) becomes
    its escape, ``\\udcff``; any other text stays as it is."""
    return value.encode("utf-8", "backslashreplace").decode("utf-8")


def _encodable(run: RunSummary) -> RunSummary:
    """The run with every text it holds made encodable (itself when it already is)."""
    return replace(
        run,
        path=_text(run.path),
        top_codes=tuple((_text(code), n) for code, n in run.top_codes),
        confirmed=tuple((_text(code), t) for code, t in run.confirmed),
        heals=tuple((_text(code), ns) for code, ns in run.heals),
        budget_failures=tuple(_text(name) for name in run.budget_failures),
        error=None if run.error is None else _text(run.error),
    )


def _untabulated(run: RunSummary, error: Exception) -> RunSummary:
    from medkit_replay.fleet.run import RunSummary  # noqa: PLC0415  # no cycle at import

    problem = " ".join(str(error).split())
    what = f"{type(error).__name__}: {problem}" if problem else type(error).__name__
    return RunSummary(path=run.path, kind=run.kind, error=f"{run.path}: cannot be reported: {what}")


def tabulated(runs: Sequence[RunSummary]) -> tuple[list[RunSummary], dict[str, str]]:
    """The report files' texts; a run they cannot hold (whatever the reason) is replaced by a
    failed row saying why, so one run never costs the report of the others."""
    kept = [_encodable(run) for run in runs]
    try:
        return kept, _texts(kept)
    except Exception:  # find the runs at fault, one at a time
        for index, run in enumerate(kept):
            try:
                _texts([run])
            except Exception as err:  # any of them: that run's failure
                kept[index] = _untabulated(run, err)
    return kept, _texts(kept)


def write_texts(texts: dict[str, str], out_dir: Path) -> list[Path]:
    """Write the report files (:func:`tabulated`'s texts) into ``out_dir``, each through a
    temporary file renamed into place.

    Returns:
        The files written, in FILES order.

    Raises:
        OSError: the folder cannot be created or a file cannot be written.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    for name in FILES:
        path = out_dir / name
        # A lone surrogate (a file name that is not UTF-8) is written as its escape.
        write_bytes_atomic(path, texts[name].encode("utf-8", "backslashreplace"))
        written.append(path)
    return written


def write_report(runs: Sequence[RunSummary], out_dir: Path) -> list[Path]:
    """Write the fleet table, the code statistics and the HTML page into ``out_dir`` (a run the
    tables cannot hold as a failed row, see :func:`tabulated`).

    Returns:
        The files written, in FILES order.

    Raises:
        OSError: the folder cannot be created or a file cannot be written.
    """
    return write_texts(tabulated(runs)[1], out_dir)


# --- HTML -------------------------------------------------------------------------------------

_STYLE = """
body { font: 14px/1.4 system-ui, sans-serif; margin: 1.5em; color: #222; }
h1 { font-size: 1.4em; } h2 { font-size: 1.15em; margin-top: 1.6em; }
table { border-collapse: collapse; margin-top: .5em; }
th, td { border: 1px solid #ccc; padding: .25em .5em; text-align: left; vertical-align: top; }
th { background: #f2f2f2; cursor: pointer; user-select: none; white-space: nowrap; }
th[aria-sort=ascending]::after { content: " \\25B2"; }
th[aria-sort=descending]::after { content: " \\25BC"; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
tr.failed td { background: #fdecea; }
.fail { color: #b00020; font-weight: bold; } .pass { color: #1b7f3b; }
dl { display: grid; grid-template-columns: max-content auto; gap: .1em 1em; }
dt { font-weight: bold; } dd { margin: 0; }
"""

_SCRIPT = """
document.querySelectorAll("table.sortable").forEach(function (table) {
  table.querySelectorAll("th").forEach(function (th, column) {
    th.addEventListener("click", function () {
      var ascending = th.getAttribute("aria-sort") !== "ascending";
      table.querySelectorAll("th").forEach(function (h) { h.removeAttribute("aria-sort"); });
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


def _is_missing(value: object) -> bool:
    if value is None or value is pd.NA:
        return True
    return isinstance(value, float) and math.isnan(value)


def _number_cell(value: object, digits: int | None = None) -> str:
    if _is_missing(value):
        return '<td class="num" data-v=""></td>'
    if digits is not None and isinstance(value, float):
        shown = f"{value:,.{digits}f}"
    elif isinstance(value, int):
        shown = f"{value:,}"
    else:
        shown = str(value)
    return f'<td class="num" data-v="{html.escape(str(value))}">{html.escape(shown)}</td>'


def _text_cell(value: object, css: str = "") -> str:
    # runs.json keeps the whole text
    text = "" if _is_missing(value) else clip(xml_text(str(value)), MAX_CELL_CHARS)
    attr = f' class="{html.escape(css)}"' if css else ""
    return f"<td{attr}>{html.escape(text)}</td>"


def _table(table_id: str, headers: Sequence[str], rows: Sequence[str]) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in headers)
    body = "\n".join(rows)
    return (
        f'<table id="{table_id}" class="sortable">\n<thead><tr>{head}</tr></thead>\n'
        f"<tbody>\n{body}\n</tbody>\n</table>"
    )


def _runs_rows(frame: pd.DataFrame) -> list[str]:
    rows: list[str] = []
    for record in frame.to_dict(orient="records"):
        error = record["error"]
        budget = record["budget"]
        top = "; ".join(f"{t['fault_code']}:{t['failed_reports']}" for t in record["top_codes"])
        cells = [
            _text_cell(record["path"]),
            _text_cell(record["kind"]),
            _number_cell(record["span_s"], 3),
            _number_cell(record["messages"]),
            _number_cell(record["confirmed"]),
            _number_cell(record["healed"]),
            _number_cell(record["cleared"]),
            _number_cell(record["prefailed"]),
            _number_cell(record["prepassed"]),
            _text_cell(top),
            _text_cell(budget, "" if _is_missing(budget) else str(budget)),
            _text_cell("; ".join(record["budget_failures"])),
            _text_cell(error),
        ]
        css = ' class="failed"' if not _is_missing(error) else ""
        rows.append(f"<tr{css}>" + "".join(cells) + "</tr>")
    return rows


def _codes_rows(frame: pd.DataFrame) -> list[str]:
    rows: list[str] = []
    for record in frame.to_dict(orient="records"):
        cells = [
            _text_cell(record["fault_code"]),
            _number_cell(record["runs_confirmed"]),
            _number_cell(record["share_of_runs"], 3),
            _number_cell(record["mean_first_confirmed_s"], 3),
            _number_cell(record["heals"]),
            _number_cell(record["mean_time_to_heal_s"], 3),
            _number_cell(record["median_time_to_heal_s"], 3),
        ]
        rows.append("<tr>" + "".join(cells) + "</tr>")
    return rows


def render_html(
    runs: Sequence[RunSummary], runs_frame: pd.DataFrame, codes_frame: pd.DataFrame
) -> str:
    """The fleet as one self-contained HTML page (inline style and script, nothing fetched)."""
    counts = overview(runs)
    facts = "".join(
        f"<dt>{html.escape(key.replace('_', ' '))}</dt><dd>{value:,}</dd>"
        for key, value in counts.items()
    )
    runs_html = _table(
        "runs",
        [
            "path",
            "kind",
            "span (s)",
            "messages",
            "confirmed",
            "healed",
            "cleared",
            "prefailed",
            "prepassed",
            "top codes",
            "budget",
            "rules failed",
            "error",
        ],
        _runs_rows(runs_frame),
    )
    codes_html = _table(
        "codes",
        [
            "fault code",
            "runs confirmed",
            "share of runs",
            "mean first confirmed (s)",
            "heals",
            "mean time to heal (s)",
            "median time to heal (s)",
        ],
        _codes_rows(codes_frame),
    )
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        "<title>medkit-replay fleet report</title>\n"
        f"<style>{_STYLE}</style>\n</head>\n<body>\n"
        "<h1>medkit-replay fleet report</h1>\n"
        f"<p>medkit-replay {html.escape(__version__)}; click a column heading to sort.</p>\n"
        f"<dl>{facts}</dl>\n"
        "<h2>Codes confirmed across runs</h2>\n"
        f"{codes_html}\n"
        "<h2>Runs</h2>\n"
        f"{runs_html}\n"
        f"<script>{_SCRIPT}</script>\n</body>\n</html>\n"
    )


# --- terminal ---------------------------------------------------------------------------------


def _seconds(value: float | None) -> str:
    return "" if value is None or _is_missing(value) else f"{value:,.1f}"


def _plural(count: int, word: str) -> str:
    return f"{count:,} {word}" + ("" if count == 1 else "s")


def _indented(text: Text) -> Padding:
    return Padding(text, (0, 0, 0, 2))


def summary_renderables(runs: Sequence[RunSummary], out_dir: Path | None) -> list[object]:
    """What the terminal summary shows, as rich renderables."""
    counts = overview(runs)
    head = Text()
    head.append("fleet: ", style="bold")
    head.append(f"{_plural(counts['runs'], 'recording')}, {counts['replayed']:,} replayed")
    if counts["failed"]:
        head.append(f", {counts['failed']:,} failed", style="bold red")
    head.append(
        f"; {_plural(counts['messages'], 'message')} read; "
        f"{counts['runs_with_confirmed']:,} with a confirmed fault"
    )
    parts: list[object] = [head]
    verdicts = {k.removeprefix("budget_"): v for k, v in counts.items() if k.startswith("budget_")}
    if verdicts:
        line = Text("budget: ", style="bold")
        for index, (verdict, number) in enumerate(verdicts.items()):
            line.append(", " if index else "")
            line.append(f"{number:,} {verdict}", style="bold red" if verdict == "fail" else "")
        parts.append(line)

    title = "runs (faults CONFIRMED, HEALED, CLEARED at the end)"
    table = Table(box=box.SIMPLE, title=title, title_justify="left", pad_edge=False)
    table.add_column("path", min_width=16, overflow="fold")
    for name in ("span s", "msgs", "conf", "heal", "clear"):
        table.add_column(name, justify="right", no_wrap=True, min_width=len(name))
    if verdicts:
        table.add_column("budget", no_wrap=True, min_width=len("budget"))
    for run in runs[:MAX_RUN_ROWS]:
        statuses = dict(run.faults_by_status)
        span = run.span_ns
        cells: list[Text | str] = [
            Text(printable(str(run.path)), style="" if run.ok else "red"),
            _seconds(span / 1e9 if span is not None else None),
            f"{run.messages:,}" if run.messages is not None else "",
            *(
                f"{statuses.get(s, 0):,}" if run.ok else ""
                for s in ("CONFIRMED", "HEALED", "CLEARED")
            ),
        ]
        if verdicts:
            cells.append(Text(run.budget or "", style="bold red" if run.budget == "fail" else ""))
        table.add_row(*cells)
    parts.append(table)
    if len(runs) > MAX_RUN_ROWS:
        parts.append(Text(f"... {len(runs) - MAX_RUN_ROWS:,} more runs in runs.csv", style="dim"))

    codes = codes_table(runs)
    if len(codes):
        code_table = Table(
            box=box.SIMPLE,
            title="codes confirmed across runs",
            title_justify="left",
            pad_edge=False,
        )
        widest = max(len(str(code)) for code in codes["fault_code"])
        code_table.add_column("fault code", overflow="fold", min_width=min(widest, 24))
        for name in ("runs", "share", "heals", "mean heal", "median heal"):
            code_table.add_column(name, justify="right", no_wrap=True, min_width=len(name))
        for record in codes.head(MAX_CODE_ROWS).to_dict(orient="records"):
            code_table.add_row(
                Text(printable(str(record["fault_code"]))),
                f"{record['runs_confirmed']:,}",
                f"{record['share_of_runs']:.0%}",
                f"{record['heals']:,}",
                _seconds(record["mean_time_to_heal_s"]),
                _seconds(record["median_time_to_heal_s"]),
            )
        parts.append(code_table)
        if len(codes) > MAX_CODE_ROWS:
            more = len(codes) - MAX_CODE_ROWS
            parts.append(Text(f"... {more:,} more codes in codes.csv", style="dim"))

    over = [run for run in runs if run.budget == "fail"]
    if over:
        parts.append(Text("over budget:", style="bold red"))
        for run in over[:MAX_ERROR_ROWS]:
            rules = "; ".join(run.budget_failures)
            parts.append(_indented(Text(f"{printable(str(run.path))}: {printable(str(rules))}")))
        if len(over) > MAX_ERROR_ROWS:
            more = len(over) - MAX_ERROR_ROWS
            parts.append(_indented(Text(f"... {more:,} more in runs.csv", style="dim")))
    failed = [run for run in runs if not run.ok]
    if failed:
        parts.append(Text("not replayed:", style="bold red"))
        for run in failed[:MAX_ERROR_ROWS]:
            error = run.error or ""
            shown = error if error.startswith(run.path) else f"{run.path}: {error}"
            parts.append(_indented(Text(printable(str(shown)))))
        if len(failed) > MAX_ERROR_ROWS:
            more = len(failed) - MAX_ERROR_ROWS
            parts.append(_indented(Text(f"... {more:,} more in runs.csv", style="dim")))
    if out_dir is not None:
        parts.append(Text(f"report: {printable(str(out_dir))}/ ({', '.join(FILES)})"))
    return parts


def _console(stream: TextIO, *, plain: bool) -> Console:
    if plain:
        return Console(
            file=stream,
            width=80,
            force_terminal=False,
            color_system=None,
            no_color=True,
            markup=False,
            emoji=False,
            highlight=False,
        )
    return Console(file=stream, markup=False, emoji=False, highlight=False)


def render_summary(runs: Sequence[RunSummary], out_dir: Path | None = None) -> str:
    """The terminal summary as plain text at 80 columns (what a file or a pipe receives)."""
    buffer = io.StringIO()
    console = _console(buffer, plain=True)
    for part in summary_renderables(runs, out_dir):
        console.print(part)
    return "\n".join(line.rstrip(" ") for line in buffer.getvalue().split("\n"))


def print_summary(runs: Sequence[RunSummary], stream: TextIO, out_dir: Path | None = None) -> None:
    """Draw the summary on ``stream``: rich on a terminal, plain 80-column text elsewhere."""
    console = _console(stream, plain=False)
    if console.is_terminal:
        for part in summary_renderables(runs, out_dir):
            console.print(part)
        return
    stream.write(render_summary(runs, out_dir))


# --- progress ---------------------------------------------------------------------------------


class FleetProgress:
    """A bar counting finished runs, on standard error; a context manager, and the
    ``on_done`` callback of the executors."""

    def __init__(self, stream: TextIO, total: int) -> None:
        console = Console(file=stream, highlight=False, emoji=False, markup=False)
        self._progress = Progress(
            TextColumn("{task.description}"),
            BarColumn(bar_width=30),
            MofNCompleteColumn(),
            TextColumn("{task.fields[failed]}"),
            TimeElapsedColumn(),
            TimeRemainingColumn(),
            console=console,
            transient=True,
            redirect_stdout=False,
            redirect_stderr=False,
            refresh_per_second=8,
        )
        self._task = self._progress.add_task("replaying", total=total, failed="")
        self._failed = 0

    def __enter__(self) -> Self:
        self._progress.start()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self._progress.stop()

    def __call__(self, index: int, run: RunSummary) -> None:
        """One more run finished."""
        self._failed += 0 if run.ok else 1
        failed = f"{self._failed} failed" if self._failed else ""
        self._progress.update(self._task, advance=1, failed=failed)


def fleet_progress(stream: TextIO, total: int, *, quiet: bool = False) -> FleetProgress | None:
    """A progress bar on ``stream``, or None under ``--quiet`` or when it is not a terminal."""
    if quiet:
        return None
    isatty = getattr(stream, "isatty", None)
    if isatty is None or not isatty():
        return None
    console = Console(file=stream)
    if not console.is_terminal or console.is_dumb_terminal:
        return None
    return FleetProgress(stream, total)
