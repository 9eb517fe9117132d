"""Lines of the terminal outputs laid out by hand, so that no code, name or number is split.

One implementation for every human output: analyze's summary, fleet's and sweep's tables
(:func:`table`, :class:`Rows`), check's verdicts, diff's rows and explain's story
(:func:`words`, :class:`Flow`).

Fixed lines never wrap (a token wider than the line stands on a line of its own, whole); free
text (descriptions, warnings) is cut to the line with an ellipsis, or wraps under ``--all``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from rich.text import Text

if TYPE_CHECKING:
    from collections.abc import Sequence

    from rich.console import Console, ConsoleOptions, RenderResult

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


def words(
    pieces: Sequence[Piece], width: int, *, indent: int = 0, hang: int | None = None
) -> list[Text]:
    """Pieces laid out on lines of ``width`` under ``indent`` spaces (``hang`` spaces after
    the first line, if given), broken only at spaces (never inside a piece kept whole): a word
    wider than the line stands whole on a line of its own."""
    lines: list[Text] = []
    line = Text(" " * indent)
    if hang is not None:
        indent = hang
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


Cell = tuple[str, str]
"""A table cell: its text and its style."""


def cell(text: str, style: str = "") -> Cell:
    """A cell of :func:`table`."""
    return (text, style)


def table(
    heads: Sequence[str],
    rows: Sequence[Sequence[Cell]],
    width: int,
    *,
    right: frozenset[int] = frozenset(),
    wide: int = 0,
    below: Sequence[str] = (),
) -> list[Text]:
    """Rows laid out by hand, every cell whole: each column as wide as its widest cell, column
    ``wide`` (a code, a path) giving way to the line; a cell of it wider than its column stands
    alone on a line above its row (as the summary's fault codes do). ``right``: the columns
    justified right (numbers); ``below``: free text under each row (broken at spaces only)."""
    sizes = [max([len(head), *(len(row[n][0]) for row in rows)]) for n, head in enumerate(heads)]
    rest = sum(2 + size for number, size in enumerate(sizes) if number != wide)
    room = max(width - rest, len(heads[wide]))
    fit = [len(row[wide][0]) for row in rows if len(row[wide][0]) <= room]
    sizes[wide] = max([len(heads[wide]), *fit])

    def line(cells: Sequence[Cell], *, bold: bool = False) -> Text:
        out = Text()
        for number, (text, style) in enumerate(cells):
            if number:
                out.append("  ")
            size = sizes[number]
            shown = "" if number == wide and len(text) > size else text
            padded = f"{shown:>{size}}" if number in right else f"{shown:<{size}}"
            out.append(padded, style="bold" if bold else style)
        out.rstrip()
        return fixed(out)

    lines = [line([(head, "") for head in heads], bold=True)]
    for number, row in enumerate(rows):
        text, style = row[wide]
        if len(text) > sizes[wide]:
            lines.append(fixed(text, style or "bold"))
        if len(text) <= sizes[wide] or any(t for n, (t, _) in enumerate(row) if n != wide):
            lines.append(line(row))
        if number < len(below) and below[number]:
            lines += words([piece(below[number], "dim")], width, indent=4)
    return lines


class Flow:
    """:func:`words` laid out when drawn, for the width of the console it is drawn on."""

    def __init__(self, pieces: Sequence[Piece], *, indent: int = 0, hang: int | None = None):
        self.pieces, self.indent, self.hang = list(pieces), indent, hang

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        yield from words(self.pieces, options.max_width, indent=self.indent, hang=self.hang)


def flow(text: str, style: str = "", *, indent: int = 0, hang: int | None = None) -> Flow:
    """Text broken only at spaces when drawn (a word wider than the line whole on its own)."""
    return Flow([piece(text, style)], indent=indent, hang=hang)


class Beside:
    """Rows of a lead (a mark, a time; every lead as wide) with lines laid out beside it by
    :func:`words` when drawn: the lead on a row's first line, spaces of its width under it."""

    def __init__(self, rows: Sequence[tuple[Text, Sequence[Flow]]], *, least: int = 1):
        self.rows, self.least = list(rows), least

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        lead = max((len(head) for head, _ in self.rows), default=0)
        room = max(options.max_width - lead, self.least)
        for head, lines in self.rows:
            first = True
            for said in lines:
                for text in words(said.pieces, room, indent=said.indent, hang=said.hang):
                    line = head.copy() if first else Text(" " * lead)
                    first = False
                    line.append_text(text)
                    line.rstrip()
                    yield fixed(line)


class Rows:
    """:func:`table` laid out when drawn, for the width of the console it is drawn on."""

    def __init__(
        self,
        heads: Sequence[str],
        rows: Sequence[Sequence[Cell]],
        *,
        right: frozenset[int] = frozenset(),
        title: str = "",
        wide: int = 0,
        below: Sequence[str] = (),
    ):
        self.heads, self.rows, self.right, self.title = list(heads), list(rows), right, title
        self.wide, self.below = wide, list(below)

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        if self.title:
            yield fixed(self.title, "italic")
        width = options.max_width
        yield from table(
            self.heads, self.rows, width, right=self.right, wide=self.wide, below=self.below
        )
