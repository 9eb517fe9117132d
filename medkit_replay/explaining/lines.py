"""A story's entries and their lines as styled parts: our words and recorded text kept apart.

A part's role names what it holds (a status, a source, recorded text); only a renderer styles it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

Part = tuple[str, str]
"""Text and its role (``plain``, ``dim``, ``kind``, ``status:CONFIRMED``, ``source``...)."""
Line = tuple[Part, ...]

EntryKind = Literal[
    "report",
    "repeat",
    "held",
    "correlation",
    "transition",
    "event",
    "event_withheld",
    "clear",
    "capture",
    "recording",
]
"""What a story entry tells; ``repeat`` stands for reports in a row that did the same."""
JSON = str | int | float | bool | None | list["JSON"] | dict[str, "JSON"]


@dataclass(frozen=True, slots=True, kw_only=True)
class Entry:
    """One step of the story.

    Attributes:
        t_ns: bag time (absolute ns) it happened at.
        kind: what it tells (:data:`EntryKind`).
        line: its sentence, in styled parts.
        details: further lines (the recorded message, a near miss...).
        fields: the same facts as JSON values (``--json``).
    """

    t_ns: int
    kind: EntryKind
    line: Line
    details: tuple[Line, ...] = ()
    fields: dict[str, JSON] = field(default_factory=dict)


def part(text: str, role: str) -> Part:
    """One piece of a line."""
    return (text, role)


def join(lines: list[Line], separator: str) -> Line:
    """Lines run together into one, ``separator`` between them."""
    out: list[Part] = []
    for number, line in enumerate(lines):
        if number:
            out.append(part(separator, "dim"))
        out.extend(line)
    return tuple(out)


def plain(line: Line) -> str:
    """A line's text without styles (recorded text as it is: escaping is the renderer's job)."""
    return "".join(text for text, _ in line)
