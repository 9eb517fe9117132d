"""Renders a :class:`~medkit_replay.diffing.compare.ReportDiff` for people, as rich text.

The only diffing module that imports rich: a headline, then one row per difference.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

from rich.console import Group
from rich.text import Text

from medkit_replay.model import NS_PER_SEC
from medkit_replay.outputs.console import plain_text
from medkit_replay.outputs.summary_lines import fixed, piece, words
from medkit_replay.text import seconds

if TYPE_CHECKING:
    from rich.console import Console, ConsoleOptions, RenderableType, RenderResult

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


Row = tuple[str, str, str, str, str]
"""A mark, its style, what differs, the baseline's side and the current's."""


class _Rows:
    """Rows of differences laid out by hand, every code, name and number whole: aligned columns
    sized to their content when a row fits the line; otherwise the row's mark and what, then
    each side on its own lines below, broken at spaces only."""

    def __init__(self, rows: list[Row], what_width: int, every: list[Row], *, header: bool = False):
        self.rows, self.what_width, self.header = rows, what_width, header
        self.every = every  # the rows of every subject, which share the columns

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        width = options.max_width
        what = self.what_width
        room = max(width - (1 + 1 + what + 1 + 1), 2)
        olds = max([len("baseline"), *(len(row[3]) for row in self.every)])
        news = max([len("current"), *(len(row[4]) for row in self.every)])
        old_size = min(olds, max(room - 1 - news, room // 2))
        new_size = max(room - 1 - old_size, len("current"))
        if self.header:
            head = f"  {'':1} {'what':<{what}} {'baseline':<{old_size}} current"
            yield fixed(head.rstrip(), "bold")
        for mark, style, said, old, new in self.rows:
            lead = Text("  ")
            lead.append(mark, style=style)
            lead.append(f" {said:<{what}} " if len(said) <= what else f" {said} ")
            if len(said) <= what and len(old) <= old_size and len(new) <= new_size:
                line = lead.copy()
                line.append(f"{old:<{old_size}} {new}")
                line.rstrip()
                yield fixed(line)
                continue
            lead.rstrip()
            yield fixed(lead)
            for label, text in (("baseline: ", old), ("current:  ", new)):
                yield from words([piece(label), piece(text)], width, indent=6, hang=16)


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
    every: list[Row] = [("", "", what, old, new) for _, what, old, new in rows]
    what_width = min(max(len("what"), *(len(row[1]) for row in rows)), MAX_WHAT)
    parts += [
        Text(""),
        Text(f"{LEGEND}; times in s from the baseline recording's start", style="dim"),
        _Rows([], what_width, every, header=True),
    ]
    previous: tuple[str, str] | None = None
    table: list[Row] = []
    for difference, what, old, new in rows:
        subject = (difference.subject_key, difference.subject)
        if subject != previous:
            if previous is not None:
                parts.append(_Rows(table, what_width, every))
                table = []
            prefix = "cluster " if difference.subject_key == "cluster_id" else ""
            parts.append(fixed(prefix + _show(difference.subject), "bold"))
            previous = subject
        mark, style = _MARKS[difference.kind.rsplit("_", 1)[1]]
        table.append((mark, style, what, old, new))
    parts.append(_Rows(table, what_width, every))
    if len(diff.differences) > MAX_ROWS:
        more = len(diff.differences) - MAX_ROWS
        parts.append(Text(f"... and {more} more (the JSON output lists all)", style="dim"))
    return Group(*parts)


def render_diff(diff: ReportDiff, width: int = 100) -> str:
    """The human output as plain text (no ANSI codes) laid out for ``width`` columns."""
    return plain_text(diff_renderable(diff), width, crop=False)
