"""One line per status change or FaultEvent, printed as a followed recording is replayed.

Seconds from the recording's start and the time of day (display only), fault code, from -> to,
cause and source; recorded text is escaped (text.printable).
"""

from __future__ import annotations

from medkit_replay.model import FaultEvent, Transition
from medkit_replay.outputs.times import EPOCH_FLOOR_NS, clock_time, from_start, start_text
from medkit_replay.text import clip, printable

MAX_SHOWN = 120
"""Longest fault code or source shown on a line (characters)."""


def bag_time(t_ns: int, origin_ns: int | None) -> str:
    """``65.751 s 09:27:58.798``: seconds from the start, then the time of day (UTC) for
    clock times; only the time of day while the start is not known yet."""
    if origin_ns is None:
        return clock_time(t_ns)
    if t_ns < EPOCH_FLOOR_NS:
        return from_start(t_ns, origin_ns)
    return f"{from_start(t_ns, origin_ns)} {clock_time(t_ns)}"


def start_line(origin_ns: int) -> str:
    """The header the lines' times count from."""
    clock = "; then the time of day, UTC" if origin_ns >= EPOCH_FLOOR_NS else ""
    return f"recording starts {start_text(origin_ns)}: times are s from the start{clock}"


def _shown(text: str) -> str:
    return printable(clip(text, MAX_SHOWN))


def live_line(record: Transition | FaultEvent, origin_ns: int | None = None) -> str:
    """The line for one record (no newline); ``origin_ns``: the recording's start."""
    when = bag_time(record.t_ns, origin_ns)
    if isinstance(record, Transition):
        source = f", source {_shown(record.source_id)}" if record.source_id else ""
        return (
            f"{when}  {_shown(record.fault_code)}  "
            f"{record.from_status or '-'} -> {record.to_status}  ({record.cause}{source})"
        )
    fault = record.fault
    sources = ", ".join(_shown(s) for s in fault.reporting_sources[:3])
    more = f" +{len(fault.reporting_sources) - 3}" if len(fault.reporting_sources) > 3 else ""
    cleared = (
        f", auto-cleared {', '.join(_shown(c) for c in record.auto_cleared_codes)}"
        if record.auto_cleared_codes
        else ""
    )
    return (
        f"{when}  {_shown(fault.fault_code)}  event {record.event_type} "
        f"(status {fault.status}, sources {sources or '-'}{more}{cleared})"
    )
