"""One line per status change or FaultEvent, printed as a followed recording is replayed.

Bag time, fault code, from -> to, cause and source; recorded text is escaped (text.printable).
"""

from __future__ import annotations

from datetime import UTC, datetime

from medkit_replay.model import FaultEvent, Transition
from medkit_replay.outputs.terminal import EPOCH_FLOOR_NS
from medkit_replay.text import clip, printable, seconds

MAX_SHOWN = 120
"""Longest fault code or source shown on a line (characters)."""


def bag_time(t_ns: int) -> str:
    """A bag time as UTC date and time to the millisecond, or seconds when not epoch-like."""
    if t_ns >= EPOCH_FLOOR_NS:
        try:
            moment = datetime.fromtimestamp(t_ns // 10**9, tz=UTC)
        except (OverflowError, ValueError, OSError):
            return f"t={seconds(t_ns)}"
        return f"{moment:%Y-%m-%d %H:%M:%S}.{(t_ns % 10**9) // 10**6:03d}"
    return f"t={seconds(t_ns)}"


def _shown(text: str) -> str:
    return printable(clip(text, MAX_SHOWN))


def live_line(record: Transition | FaultEvent) -> str:
    """The line for one record (no newline)."""
    if isinstance(record, Transition):
        source = f", source {_shown(record.source_id)}" if record.source_id else ""
        return (
            f"{bag_time(record.t_ns)}  {_shown(record.fault_code)}  "
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
        f"{bag_time(record.t_ns)}  {_shown(fault.fault_code)}  event {record.event_type} "
        f"(status {fault.status}, sources {sources or '-'}{more}{cleared})"
    )
