"""Whole-string wildcard matching in linear-ish time, for correlation patterns and budget globs.

Two or more stars never reach a backtracking regex: the segments between them are placed
leftmost, left to right. Pure, outside the engine so that budget checks need not load it.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache

# Why leftmost placement is exact: a segment placed at its earliest possible start leaves the
# next star at least as much room as any later placement would. With a star that may not span
# some characters (correlation's CR/LF), the earliest occurrence is also never worse: the
# text a later occurrence's star would skip already lies in a stretch free of them (the
# overlapping case follows from the segment's periodicity).


@dataclass(frozen=True, slots=True)
class _Segment:
    """Text between two stars; ``holes`` are the offsets a one-character wildcard fills.

    ``anchor`` is the segment's longest hole-free run (at ``anchor_at``), searched with str.find.
    """

    text: str
    holes: frozenset[int]
    anchor: str
    anchor_at: int

    @classmethod
    def of(cls, text: str, one: str | None) -> _Segment:
        holes = frozenset(k for k, ch in enumerate(text) if ch == one)
        best, best_at, run_at = "", 0, 0
        for k in range(len(text) + 1):
            if k == len(text) or k in holes:
                if k - run_at > len(best):
                    best, best_at = text[run_at:k], run_at
                run_at = k + 1
        return cls(text, holes, best, best_at)

    def at(self, code: str, start: int) -> bool:
        """Whether the segment matches ``code`` at ``start`` (which leaves room for it)."""
        if not self.holes:
            return code.startswith(self.text, start)
        holes = self.holes
        return all(ch == code[start + k] for k, ch in enumerate(self.text) if k not in holes)

    def find(self, code: str, start: int, last_start: int) -> int:
        """The first offset in ``[start, last_start]`` where the segment matches, or -1."""
        if last_start < start:
            return -1
        if not self.holes:
            return code.find(self.text, start, last_start + len(self.text))
        anchor, offset = self.anchor, self.anchor_at
        if not anchor:  # only holes: any position with room will do
            return start
        pos = start
        while pos <= last_start:
            hit = code.find(anchor, pos + offset, last_start + offset + len(anchor))
            if hit < 0:
                return -1
            if self.at(code, hit - offset):
                return hit - offset
            pos = hit - offset + 1
        return -1


@dataclass(frozen=True, slots=True)
class Wildcard:
    """A compiled pattern: ``*`` spans any run not holding a ``star_excludes`` character.

    ``one`` (when set) is the character standing for exactly one character of any kind.
    """

    segments: tuple[_Segment, ...]
    starred: bool
    star_excludes: str
    regex: re.Pattern[str] | None
    """The same pattern as a regex, when it has at most one star: then backtracking is
    bounded by the code's length times the pattern's, and the regex engine is faster."""

    def matches(self, code: str) -> bool:
        """Whether the whole ``code`` matches."""
        if self.regex is not None:
            return self.regex.fullmatch(code) is not None
        segments = self.segments
        first = segments[0]
        if not self.starred:
            return len(code) == len(first.text) and first.at(code, 0)
        last = segments[-1]
        size = len(code)
        tail_at = size - len(last.text)
        if tail_at < len(first.text) or not first.at(code, 0) or not last.at(code, tail_at):
            return False
        pos = len(first.text)
        for segment in segments[1:-1]:
            limit = self._star_end(code, pos, tail_at)
            hit = segment.find(code, pos, min(limit, tail_at - len(segment.text)))
            if hit < 0:
                return False
            pos = hit + len(segment.text)
        return self._star_end(code, pos, tail_at) >= tail_at

    def _star_end(self, code: str, start: int, stop: int) -> int:
        """How far a star starting at ``start`` can reach (at most ``stop``)."""
        end = stop
        for ch in self.star_excludes:
            hit = code.find(ch, start, end)
            if hit >= 0:
                end = hit
        return end


def compile_wildcard(pattern: str, *, one: str | None = None, star_excludes: str = "") -> Wildcard:
    """Compile ``pattern``: ``*`` any run (without ``star_excludes``), ``one`` one character."""
    return _compile(pattern, one, star_excludes)


@lru_cache(maxsize=4096)
def _compile(pattern: str, one: str | None, star_excludes: str) -> Wildcard:
    pieces = pattern.split("*")
    segments = tuple(
        _Segment.of(piece, one)
        for index, piece in enumerate(pieces)
        if piece or index in (0, len(pieces) - 1)
    )
    regex = None
    if len(pieces) <= 2:
        star = f"[^{re.escape(star_excludes)}]*" if star_excludes else ".*"
        parts = (star if c == "*" else "." if c == one else re.escape(c) for c in pattern)
        regex = re.compile("".join(parts), re.DOTALL)
    return Wildcard(segments, len(pieces) > 1, star_excludes, regex)
