"""The codes a replay saw, and the nearest of them to a code it did not (difflib).

Reads only the Result.
"""

from __future__ import annotations

import difflib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from medkit_replay.result import Result

NEAREST = 5
"""Codes offered when the one asked for never appeared."""


def known_codes(result: Result) -> list[str]:
    """Every fault code the replay saw (faults, reports, clears), in byte order."""
    codes = {fault.fault_code for fault in result.faults}
    codes.update(report.fault_code for report in result.reports)
    codes.update(clear.fault_code for clear in result.clears)
    return sorted(codes, key=lambda c: c.encode("utf-8", "surrogatepass"))


def nearest_codes(code: str, known: list[str], count: int = NEAREST) -> list[str]:
    """The ``count`` known codes most like ``code``, most alike first (ties in byte order)."""
    ratio = {
        other: difflib.SequenceMatcher(None, code.upper(), other.upper()).ratio() for other in known
    }
    ranked = sorted(known, key=lambda c: (-ratio[c], c.encode("utf-8", "surrogatepass")))
    return ranked[:count]
