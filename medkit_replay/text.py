"""Text from recordings and configs made safe for one line of a terminal, a log or an XML file.

Fault codes, cluster ids, paths and warnings are untrusted: nothing they hold may move a
cursor, recolour a terminal, reorder text (bidirectional controls, the Arabic letter mark
U+061C) or end a line where a reader does not expect it (U+2028, U+2029).
"""

from __future__ import annotations

import difflib
import re
from typing import TYPE_CHECKING

from medkit_replay.model import NS_PER_SEC, SEVERITY_NAMES

if TYPE_CHECKING:
    from collections.abc import Sequence

_BIDI = "\u061c\u200e\u200f\u202a-\u202e\u2066-\u2069"
_UNPRINTABLE = re.compile(f"[\\x00-\\x1f\\x7f-\\x9f\\u2028\\u2029{_BIDI}\\ud800-\\udfff]")
# Besides what XML 1.0 forbids (NUL, ESC, lone surrogates): C1 controls, line and paragraph
# separators and bidirectional controls, which XML allows but a CI page would act on.
_NOT_XML = re.compile(
    f"[^\t\n\r\x20-\x7e\xa0-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]|[\u2028\u2029{_BIDI}]"
)


def _escape_char(char: str) -> str:
    return f"\\x{ord(char):02x}" if ord(char) < 0x100 else f"\\u{ord(char):04x}"


def printable(text: str) -> str:
    """One line: line breaks and tabs become spaces, other control and bidirectional-override
    characters, line and paragraph separators and lone surrogates are shown as escapes
    (``\\x1b``, ``\\u202e``)."""

    def replace(match: re.Match[str]) -> str:
        char = match.group()
        return " " if char in "\n\r\t" else _escape_char(char)

    return _UNPRINTABLE.sub(replace, text)


def xml_text(text: str) -> str:
    """Text XML 1.0 can hold, and a CI page shows as it is: characters XML forbids (NUL, ESC,
    lone surrogates), C1 controls, U+2028, U+2029 and bidirectional controls as escapes."""
    return _NOT_XML.sub(lambda m: _escape_char(m.group()), text)


WARNING_CAP = 500
"""Characters of one warning shown on a terminal, a page or a CI annotation (the JSON report
holds it whole): a recording can put megabytes into one."""


def clip(text: str, limit: int) -> str:
    """At most ``limit`` characters of ``text``; a longer text is cut and ends with an ellipsis
    and how many characters were left out (``abc... (+9,997 characters)``, ASCII for any
    terminal)."""
    if len(text) <= limit:
        return text
    return f"{text[:limit]}... (+{len(text) - limit:,} characters)"


def seconds(ns: float) -> str:
    """Nanoseconds as seconds with millisecond digits (``12.345``), as every output shows time."""
    return f"{ns / NS_PER_SEC:.3f}"


def severity_name(severity: int) -> str:
    """``INFO``, ``WARN``, ``ERROR``, ``CRITICAL``; any other number as itself."""
    return SEVERITY_NAMES[severity] if 0 <= severity < len(SEVERITY_NAMES) else str(severity)


def closest(name: str, known: Sequence[str], cutoff: float = 0.6) -> str | None:
    """The known name ``name`` most likely misspells: one differing only in case, else the
    nearest by difflib's ratio when at least ``cutoff``; None when none is near."""
    folded = [k for k in known if k.lower() == name.lower()]
    close = folded or difflib.get_close_matches(name, known, n=1, cutoff=cutoff)
    return close[0] if close else None


def name_hint(meant: str | None, known: Sequence[str]) -> str:
    """The hint after an unknown name: ``did you mean 'x'?`` for the ``meant`` name (as
    :func:`closest` found it), else the ``known`` names."""
    return f"did you mean '{meant}'?" if meant else f"expected one of: {', '.join(known)}"


def one_line(exc: BaseException | str, limit: int | None = None, *, or_name: bool = False) -> str:
    """An exception's text (or a text) on one line: every run of whitespace, line breaks
    included, becomes one space; cut to ``limit`` characters when given. With ``or_name``, an
    exception without text is shown by its type's name (``TimeoutError``)."""
    text = " ".join(str(exc).split())[:limit]
    if not text and or_name and isinstance(exc, BaseException):
        return type(exc).__name__
    return text
