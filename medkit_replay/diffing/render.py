"""Renders a :class:`~medkit_replay.diffing.compare.ReportDiff` for people, as rich text.

The only diffing module that imports rich: a headline, then one row per difference.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

from rich import box
from rich.console import Group
from rich.padding import Padding
from rich.table import Table
from rich.text import Text

from medkit_replay.model import NS_PER_SEC
from medkit_replay.outputs.console import plain_text
from medkit_replay.text import seconds

if TYPE_CHECKING:
    from rich.console import RenderableType

    from medkit_replay.diffing.compare import Difference, ReportDiff

MAX_ROWS = 500
"""Most differences drawn in the human output; the JSON has all of them."""
MAX_WHAT = 34

_KIND_TEXT: dict[str, str] = {
    "fault_added": "fault added",
    "fault_removed": "fault removed",
    "fault_changed": "fault changed",
    "transition_shifted": "transition shifted",
    "transition_missing": "transition missing",
    "transition_extra": "transition extra",
    "event_shifted": "event shifted",
    "event_missing": "event missing",
    "event_extra": "event extra",
    "cluster_added": "cluster added",
    "cluster_removed": "cluster removed",
    "cluster_changed": "cluster changed",
}
_MARKS = {
    "added": ("+", "green"),
    "extra": ("+", "green"),
    "removed": ("-", "red"),
    "missing": ("-", "red"),
    "changed": ("~", "yellow"),
    "shifted": ("~", "yellow"),
}
"""Per kind's last word: the mark at the start of its row, and the mark's colour."""
LEGEND = "- only in the baseline, + only in the current, ~ changed or shifted"


def _show(value: object) -> str:
    """Recorded text made safe for a terminal: control and bidirectional characters escaped."""
    out: list[str] = []
    for char in str(value):
        point = ord(char)
        if char in "\n\r\t":
            out.append(" ")
        elif point < 0x20 or 0x7F <= point <= 0x9F:
            out.append(f"\\x{point:02x}")
        elif point in (0x200E, 0x200F) or 0x202A <= point <= 0x202E or 0x2066 <= point <= 0x2069:
            out.append(f"\\u{point:04x}")
        else:
            out.append(char)
    return "".join(out)


def _value(value: object) -> str:
    if value is None:
        return "null"
    if isinstance(value, list):
        return "[" + ", ".join(_show(v) for v in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    return _show(value)


def _seconds(ns: int) -> str:
    return f"{ns / NS_PER_SEC:+.3f} s"


class _Clock:
    def __init__(self, origin_ns: int | None) -> None:
        self.origin_ns = origin_ns or 0

    def at(self, t_ns: object) -> str:
        if not isinstance(t_ns, int):
            return "-"
        return f"{seconds(t_ns - self.origin_ns)} s"


def _what(difference: Difference) -> str:
    """What differs: a fault field, a status change, an event, the fault or cluster itself."""
    detail = difference.detail
    if difference.kind.startswith("event_"):
        return f"event {_show(detail.get('event_type'))}"
    if difference.kind.startswith("transition_"):
        origin = detail.get("from_status")
        text = f"{_show(origin) if origin is not None else '(new)'} -> {_show(detail['to_status'])}"
        cause = detail.get("cause")
        return text if cause == "report" else f"{text} ({_show(cause)})"
    if "field" in detail:
        return _show(detail["field"])
    return "cluster" if difference.subject_key == "cluster_id" else "fault"


def _presence(difference: Difference) -> str:
    """A fault by its status, a cluster by its members."""
    item = difference.detail.get("current") or difference.detail.get("baseline")
    if not isinstance(item, Mapping):
        return "present"
    if difference.subject_key == "cluster_id":
        return f"present: {_value(item.get('fault_codes'))}"
    return _value(item.get("status"))


def _cells(difference: Difference, clock: _Clock) -> tuple[str, str]:
    detail = difference.detail
    if "baseline_t_ns" in detail:
        old_t, new_t = detail["baseline_t_ns"], detail["current_t_ns"]
        current = clock.at(new_t)
        shift = detail.get("shift_ns")
        if isinstance(shift, int):
            current += f" ({_seconds(shift)})"
        return clock.at(old_t), current
    if "field" in detail:
        return _value(detail.get("baseline")), _value(detail.get("current"))
    if difference.kind.endswith("_added"):
        return "absent", _presence(difference)
    return _presence(difference), "absent"


def _headline(diff: ReportDiff) -> Text:
    tolerance = f"time tolerance {seconds(diff.time_tolerance_ns)} s"
    if diff.equal:
        return Text.assemble(("reports are equal", "bold green"), f" ({tolerance})")
    counts = [(k, n) for k, n in diff.counts().items() if n]
    parts = ", ".join(f"{_KIND_TEXT[k]}: {n}" for k, n in counts)
    total = len(diff.differences)
    noun = "difference" if total == 1 else "differences"
    return Text.assemble(("reports differ", "bold red"), f": {total} {noun} ({parts}; {tolerance})")


def _rows_table(what_width: int, *, header: bool = False) -> Table:
    """One subject's rows; every such table has the same column widths, so they align."""
    table = Table(
        box=box.SIMPLE_HEAD,
        show_header=header,
        show_edge=False,
        pad_edge=False,
        padding=(0, 1),
        expand=True,
    )
    table.add_column("", width=1, no_wrap=True)
    table.add_column("what", width=what_width, overflow="fold")
    table.add_column("baseline", ratio=1, overflow="fold")
    table.add_column("current", ratio=1, overflow="fold")
    return table


def diff_renderable(diff: ReportDiff) -> Group:
    """The diff for people: a headline, then per fault (or cluster) one row per difference."""
    parts: list[RenderableType] = [
        Text.assemble(  # paths whole on one line, to copy them
            (label, "bold"), _show(name), no_wrap=True, overflow="ignore"
        )
        for label, name in (("baseline: ", diff.baseline_name), ("current:  ", diff.current_name))
    ]
    parts += [  # one line each, however narrow the output
        Text(_show(warning), style="bold yellow", no_wrap=True, overflow="ignore")
        for warning in diff.warnings
    ]
    parts.append(_headline(diff))
    if diff.equal:
        return Group(*parts)
    clock = _Clock(diff.origin_ns)
    rows = [(d, _what(d), *_cells(d, clock)) for d in diff.differences[:MAX_ROWS]]
    what_width = min(max(len("what"), *(len(row[1]) for row in rows)), MAX_WHAT)
    parts += [
        Text(""),
        Text(f"{LEGEND}; times in s from the baseline recording's start", style="dim"),
        Padding(_rows_table(what_width, header=True), (0, 0, 0, 2)),
    ]
    previous: tuple[str, str] | None = None
    table = _rows_table(what_width)
    for difference, what, old, new in rows:
        subject = (difference.subject_key, difference.subject)
        if subject != previous:
            if previous is not None:
                parts.append(Padding(table, (0, 0, 0, 2)))
                table = _rows_table(what_width)
            prefix = "cluster " if difference.subject_key == "cluster_id" else ""
            parts.append(Text(prefix + _show(difference.subject), style="bold"))
            previous = subject
        mark, style = _MARKS[difference.kind.rsplit("_", 1)[1]]
        table.add_row(Text(mark, style=style), Text(what), Text(old), Text(new))
    parts.append(Padding(table, (0, 0, 0, 2)))
    if len(diff.differences) > MAX_ROWS:
        more = len(diff.differences) - MAX_ROWS
        parts.append(Text(f"... and {more} more (the JSON output lists all)", style="dim"))
    return Group(*parts)


def render_diff(diff: ReportDiff, width: int = 100) -> str:
    """The human output as plain text (no ANSI codes) laid out for ``width`` columns."""
    return plain_text(diff_renderable(diff), width, crop=False)
