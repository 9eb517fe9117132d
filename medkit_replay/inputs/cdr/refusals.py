"""How a generated CDR decoder says no: a payload that does not fit, a definition not covered.

Worded as rosbags words its own refusals, so a warning reads the same whichever decoder ran.
"""

from __future__ import annotations

import struct


class UnsupportedError(Exception):
    """The definition uses something the generator does not cover; rosbags decodes it."""


class RejectedError(Exception):
    """A payload that does not fit the definition (a check rosbags makes too)."""


REFUSALS = (RejectedError, struct.error, IndexError, UnicodeDecodeError, ValueError)
"""What a generated decoder raises on bytes that do not fit: its own checks, a read past the
end (struct, indexing), text that is not UTF-8, and numpy's buffer too small for an array.
Anything else it raises is a bug in the generated code."""


NOT_PLAIN = "Invalid or unsupported CDR encapsulation."


def string_refusal(raw: bytes, p: int, length: int) -> str:
    """Why the string at ``p`` is refused, worded (and placed in the CDR body) as rosbags does."""
    end = p + 4 + length
    if length < 1 or end > len(raw):
        return f"Invalid string length {length} at offset {p - 4}."
    return f"Missing string terminator at offset {end - 5}."


def sequence_refusal(size: int, p: int) -> str:
    """Why a sequence count read before ``p`` is refused, worded as rosbags does."""
    return f"Invalid sequence length {size} at offset {p - 4}."
