"""Lines of a story as styled parts: our words and recorded text kept apart until drawn.

A part's role names what it holds (a status, a source, recorded text); only a renderer styles it.
"""

from __future__ import annotations

Part = tuple[str, str]
"""Text and its role (``plain``, ``dim``, ``kind``, ``status:CONFIRMED``, ``source``...)."""
Line = tuple[Part, ...]


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
