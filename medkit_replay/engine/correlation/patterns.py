"""Wildcard matching of fault codes as upstream's correlation PatternMatcher does it.

`*` matches any run of characters; every other character is literal; matches are anchored.
"""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING

from medkit_replay.wildcards import compile_wildcard

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Mapping, Sequence

# Upstream turns `*` into std::regex `.*`, and `.` there matches neither CR nor LF.
_STAR_EXCLUDES = "\n\r"


@lru_cache(maxsize=4096)
def _matcher(pattern: str) -> Callable[[str], bool]:
    return compile_wildcard(pattern, star_excludes=_STAR_EXCLUDES).matches


def matches_wildcard(code: str, pattern: str) -> bool:
    """True when ``code`` matches ``pattern`` (correlation.md §4)."""
    if "*" not in pattern:
        return code == pattern
    return _matcher(pattern)(code)


def matches_any(code: str, patterns: Iterable[str]) -> bool:
    """True when ``code`` matches any of ``patterns``."""
    return any(matches_wildcard(code, pattern) for pattern in patterns)


class PatternMatcher:
    """Named pattern groups from the correlation config's ``patterns`` map."""

    def __init__(self, patterns: Mapping[str, Sequence[str]]) -> None:
        self._patterns = {pid: tuple(codes) for pid, codes in patterns.items()}

    def matches(self, code: str, pattern_id: str) -> bool:
        """True when ``code`` matches any code of the named pattern; unknown ids never match."""
        codes = self._patterns.get(pattern_id)
        return codes is not None and matches_any(code, codes)

    def find_matching_patterns(self, code: str) -> list[str]:
        """Ids of every pattern ``code`` matches, in ascending id order."""
        return [pid for pid in sorted(self._patterns) if self.matches(code, pid)]
