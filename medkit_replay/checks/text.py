"""Text from recordings and configs made safe for one line of a terminal, a log or an XML file.

Fault codes, cluster ids, paths and warnings are untrusted: nothing they hold may move a
cursor, recolour a terminal, reorder text or end a line where a reader does not expect it.
"""

from __future__ import annotations

import re

_UNPRINTABLE = re.compile(r"[\x00-\x1f\x7f-\x9f\u2028\u2029\u200e\u200f\u202a-\u202e\u2066-\u2069]")
_NOT_XML = re.compile("[^\t\n\r\x20-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")


def _escape_char(char: str) -> str:
    return f"\\x{ord(char):02x}" if ord(char) < 0x100 else f"\\u{ord(char):04x}"


def printable(text: str) -> str:
    """One line: line breaks and tabs become spaces, other control and bidirectional-override
    characters are shown as escapes (``\\x1b``)."""

    def replace(match: re.Match[str]) -> str:
        char = match.group()
        return " " if char in "\n\r\t" else _escape_char(char)

    return _UNPRINTABLE.sub(replace, text)


def xml_text(text: str) -> str:
    """Text XML 1.0 can hold: characters it forbids (NUL, ESC, lone surrogates) as escapes."""
    return _NOT_XML.sub(lambda m: _escape_char(m.group()), text)
