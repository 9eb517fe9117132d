"""Bag time for people, one format everywhere: seconds from the recording's start, with the
start's UTC date in a header and, where it helps, the time of day (display only, never in results).
"""

from __future__ import annotations

from datetime import UTC, datetime

from medkit_replay.text import seconds

__all__ = ["EPOCH_FLOOR_NS", "clock_time", "from_start", "start_text", "utc_date"]

EPOCH_FLOOR_NS = 10**18
"""Bag times from here on (2001-09-09) are shown as UTC dates; smaller ones are script times."""


def from_start(t_ns: int, origin_ns: int) -> str:
    """Seconds since the recording's start: ``65.751 s``."""
    return f"{seconds(t_ns - origin_ns)} s"


def _utc(t_ns: int, form: str) -> str | None:
    """A clock-like bag time in UTC to the millisecond; None for a script's own seconds."""
    if t_ns < EPOCH_FLOOR_NS:
        return None
    try:
        moment = datetime.fromtimestamp(t_ns // 10**9, tz=UTC)
    except (OverflowError, ValueError, OSError):  # beyond what a date can show
        return None
    return f"{moment.strftime(form)}.{(t_ns % 10**9) // 10**6:03d}"


def clock_time(t_ns: int) -> str:
    """Absolute bag time: ``HH:MM:SS.mmm`` UTC for clock times, ``t=S`` for script times."""
    return _utc(t_ns, "%H:%M:%S") or f"t={seconds(t_ns)}"


def utc_date(t_ns: int) -> str | None:
    """A clock-like bag time as ``2024-05-01 12:00:00.000 UTC``; None when it is not one."""
    stamp = _utc(t_ns, "%Y-%m-%d %H:%M:%S")
    return f"{stamp} UTC" if stamp else None


def start_text(t_ns: int, *, whole_beyond: bool = False) -> str:
    """The recording's start as a date (UTC), or a script's own time; ``whole_beyond``: a
    clock-like time past what a date can show (year 10000) in whole seconds, ``t = 1,000 s``."""
    date = utc_date(t_ns)
    if date is not None:
        return date
    if whole_beyond and t_ns >= EPOCH_FLOOR_NS:
        return f"t = {t_ns // 10**9:,} s"
    return f"t = {seconds(t_ns)} s"
