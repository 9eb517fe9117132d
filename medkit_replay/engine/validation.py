"""Request validation with the reason texts upstream's fault manager logs.

Pure: checks strings and integers, returns the first failure's text or None.
"""

from __future__ import annotations

import re
from functools import lru_cache

_ALLOWED_PUNCTUATION = frozenset("_-.")


@lru_cache(maxsize=8)
def _well_formed(max_length: int) -> re.Pattern[str]:
    """Codes of allowed characters, 1 to ``max_length`` of them (the common case, tried first)."""
    return re.compile(rf"[A-Za-z0-9_.\-]{{1,{max_length}}}")


@lru_cache(maxsize=65536)
def fault_code_error(fault_code: str, max_length: int) -> str | None:
    """Why ``fault_code`` is invalid (fault-manager.md §1.3, upstream's order), or None.

    ``max_length`` is the release's longest code (``Release.max_fault_code_length``).
    """
    if _well_formed(max_length).fullmatch(fault_code) is not None:
        return "fault_code cannot contain '..'" if ".." in fault_code else None
    if not fault_code:
        return "fault_code cannot be empty"
    if len(fault_code.encode("utf-8")) > max_length:
        return f"fault_code exceeds maximum length of {max_length}"
    for char in fault_code:
        if not ((char.isascii() and char.isalnum()) or char in _ALLOWED_PUNCTUATION):
            return (
                f"fault_code contains invalid character '{char}'. "
                "Only alphanumeric, underscore, hyphen, and dot are allowed"
            )
    if ".." in fault_code:
        return "fault_code cannot contain '..'"
    return None


def report_error(
    fault_code: str, event_type: int, severity: int, source_id: str, max_length: int
) -> str | None:
    """Why a ReportFault request is rejected, or None when it is accepted."""
    reason = fault_code_error(fault_code, max_length)
    if reason is not None:
        return reason
    if event_type not in (0, 1):
        return f"invalid event_type {event_type}"
    if event_type == 0 and severity > 3:
        return f"invalid severity {severity} for FAILED event"
    if not source_id:
        return "source_id cannot be empty"
    return None
