"""Lines of the terminal summary laid out by hand, so that no code, name or number is split.

Fixed lines never wrap (a token wider than the line stands on a line of its own, whole); free
text (descriptions, warnings) is cut to the line with an ellipsis, or wraps under ``--all``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from rich.text import Text

if TYPE_CHECKING:
    from collections.abc import Sequence

ELLIPSIS = "…"


def fixed(text: str | Text = "", style: str = "") -> Text:
    """A line that is never wrapped nor cropped: made to fit by its builder."""
    line = text.copy() if isinstance(text, Text) else Text(text, style=style)
    line.no_wrap = True
    line.overflow = "ignore"
    return line


def cut(text: str, room: int) -> str:
    """Free text on one line of ``room`` columns, shortened with an ellipsis when longer."""
    if len(text) <= room:
        return text
    return text[: max(room - 1, 0)].rstrip() + ELLIPSIS


def free(text: str, width: int, *, indent: int, style: str = "", whole: bool) -> Text:
    """Free text under ``indent`` spaces: cut to one line, or (``whole``) wrapped as it is."""
    if whole:
        return Text(" " * indent + text, style=style)
    return fixed(Text(" " * indent + cut(text, width - indent), style=style))


Piece = tuple[str, str, bool]
"""Text, its style, and whether it is kept whole on one line (a time, a name)."""


def piece(text: str, style: str = "", *, whole: bool = False) -> Piece:
    """A piece of a line laid out by :func:`words`."""
    return (text, style, whole)


def words(pieces: Sequence[Piece], width: int, *, indent: int = 0) -> list[Text]:
    """Pieces laid out on lines of ``width`` under ``indent`` spaces, broken only at spaces
    (never inside a piece kept whole): a word wider than the line stands whole on a line of
    its own."""
    lines: list[Text] = []
    line = Text(" " * indent)
    bare, glue = True, False
    for text, style, whole in pieces:
        split = [text.strip(" ")] if whole else text.split(" ")
        glue = glue and not text.startswith(" ")
        for word in split:
            if not word:
                glue = False
                continue
            gap = "" if bare or glue else " "
            if not bare and not glue and len(line) + 1 + len(word) > width:
                lines.append(fixed(line))
                line, gap = Text(" " * indent), ""
            line.append(gap)
            line.append(word, style=style)
            bare, glue = False, False
        glue = bool(text) and not text.endswith(" ")
    if not bare:
        lines.append(fixed(line))
    return lines


def listing(
    head: Text,
    items: Sequence[str],
    width: int,
    *,
    separator: str = ", ",
    everything: bool = False,
) -> Text:
    """``head`` then as many ``items`` as fit in ``width`` (at least one), then ``+N more``;
    every item whole. ``everything``: all items (the line may then be long)."""
    line = head.copy()
    for number, item in enumerate(items):
        rest = len(items) - number - 1
        more = f"{separator}+{rest} more" if rest else ""
        lead = separator if number else ""
        fits = len(line) + len(lead) + len(item) + len(more) <= width
        if number and not fits and not everything:
            line.append(f"{separator}+{len(items) - number} more")
            break
        line.append(lead)
        line.append(item)
    return fixed(line)
