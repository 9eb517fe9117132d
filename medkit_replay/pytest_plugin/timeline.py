"""A fault's timeline for failure messages: its status changes and FaultEvents as a text table.

Times are in seconds from the recording's start; runs of ``fault_updated`` events are one row,
long timelines keep their head and tail, recorded text is shown on one line.
"""

from __future__ import annotations

import itertools
import re
from dataclasses import dataclass
from typing import TYPE_CHECKING

from medkit_replay.text import seconds

if TYPE_CHECKING:
    from collections.abc import Sequence

    from medkit_replay.model import FaultEvent, Transition
    from medkit_replay.result import Result

MAX_TIMELINE_ROWS = 40
"""Rows of a fault timeline shown in a failure (runs of ``fault_updated`` count as one)."""


def recording_start_ns(result: Result) -> int:
    """The recording's first log time (its inputs' starts, else the first message read); 0 when
    nothing was read. ``within`` windows are in seconds from here."""
    start, _ = result.span()
    return start if start is not None else 0


@dataclass(slots=True)
class _Row:
    t_ns: int
    change: str = ""
    cause: str = ""
    source: str = ""
    event: str = ""
    mark: str = ""
    last_t_ns: int | None = None
    repeats: int = 1


def clean(text: object) -> str:
    """Recorded text on one line, control characters escaped."""
    return re.sub(
        r"[\x00-\x1f\x7f-\x9f]",
        lambda m: " " if m.group() in "\n\r\t" else f"\\x{ord(m.group()):02x}",
        str(text),
    )


def _rows(
    transitions: Sequence[Transition], events: Sequence[FaultEvent], marked: set[int]
) -> list[_Row]:
    """One row per instant and status change; an event at the same instant shares its row."""
    items: list[tuple[int, int, Transition | None, FaultEvent | None]] = [
        (t.t_ns, 0, t, None) for t in transitions
    ]
    items += [(e.t_ns, 1, None, e) for e in events]
    items.sort(key=lambda item: (item[0], item[1]))
    rows: list[_Row] = []
    for t_ns, group in itertools.groupby(items, key=lambda item: item[0]):
        members = list(group)
        changes = [m[2] for m in members if m[2] is not None]
        published = [m[3] for m in members if m[3] is not None]
        for change, event in itertools.zip_longest(changes, published):
            row = _Row(t_ns)
            if change is not None:
                origin = change.from_status or "(new)"
                row.change = f"{origin} -> {change.to_status}"
                row.cause = change.cause
                row.source = clean(change.source_id or "")
                row.mark = "!" if id(change) in marked else ""
            if event is not None:
                row.event = event.event_type
            rows.append(row)
    return _collapse(rows)


def _collapse(rows: list[_Row]) -> list[_Row]:
    """Runs of rows holding only a ``fault_updated`` event become one row."""
    collapsed: list[_Row] = []
    for row in rows:
        last = collapsed[-1] if collapsed else None
        if (
            last is not None
            and not row.change
            and not last.change
            and row.event == last.event == "fault_updated"
        ):
            last.repeats += 1
            last.last_t_ns = row.t_ns
            continue
        collapsed.append(row)
    return collapsed


def fault_timeline(result: Result, fault_code: str, *, marked: Sequence[Transition] = ()) -> str:
    """One fault's status changes and FaultEvents as a small text table, indented for a failure
    message (times in s from the recording's start); ``marked`` transitions get a ``!``."""
    origin = recording_start_ns(result)
    transitions = [t for t in result.transitions if t.fault_code == fault_code]
    events = [e for e in result.events if e.fault.fault_code == fault_code]
    head = (
        f"timeline of {clean(fault_code)} (t in s from the recording's start): "
        f"{len(transitions)} status change(s), {len(events)} event(s)"
    )
    if not transitions and not events:
        return "  " + head
    rows = _rows(transitions, events, {id(t) for t in marked})
    table = [("", "t", "status change", "cause", "source", "event")]
    shown = rows
    if len(rows) > MAX_TIMELINE_ROWS:
        half = MAX_TIMELINE_ROWS // 2
        shown = [
            *rows[:half],
            _Row(0, change=f"... {len(rows) - 2 * half} rows ..."),
            *rows[-half:],
        ]
    for row in shown:
        if row.change.startswith("... "):
            table.append(("", "", row.change, "", "", ""))
            continue
        t = seconds(row.t_ns - origin)
        event = row.event
        if row.repeats > 1 and row.last_t_ns is not None:
            t += f"-{seconds(row.last_t_ns - origin)}"
            event += f" x{row.repeats}"
        table.append((row.mark, t, row.change, row.cause, row.source, event))
    widths = [max(len(line[i]) for line in table) for i in range(len(table[0]))]
    lines = ["  " + head]
    for line in table:
        cells = [line[0].ljust(widths[0]), line[1].rjust(widths[1])]
        cells += [cell.ljust(width) for cell, width in zip(line[2:], widths[2:], strict=True)]
        lines.append("    " + "  ".join(cells).rstrip())
    return "\n".join(lines)
