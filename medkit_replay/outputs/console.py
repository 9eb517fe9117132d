"""rich consoles for what medkit-replay prints: recorded text shown literally, widths made usable.

Every human output (summary, diff, fleet summary) is drawn or turned into plain text here.
"""

from __future__ import annotations

import io
import sys
from typing import TYPE_CHECKING, TextIO

if TYPE_CHECKING:
    from rich.console import Console, RenderableType

    from medkit_replay.outputs.progress import ProgressBar

DEFAULT_WIDTH = 80
"""Columns used when the detected width is unusable (``COLUMNS=0``)."""
WIDTH_RANGE = (60, 1000)
"""Narrowest and widest layouts (``COLUMNS=1`` would print a letter per line; the summary is
laid out for 60 columns and more)."""


def usable_width(detected: int) -> int:
    """A width to lay output out for: DEFAULT_WIDTH for 0 or less (``COLUMNS=0``), else
    ``detected`` brought into WIDTH_RANGE."""
    if detected <= 0:
        return DEFAULT_WIDTH
    return min(max(detected, WIDTH_RANGE[0]), WIDTH_RANGE[1])


def literal_console(
    stream: TextIO,
    *,
    width: int | None = None,
    force_terminal: bool | None = None,
    colour: bool = True,
) -> Console:
    """A console with no markup, emoji or highlighting of plain strings, so that recorded text
    prints as it is; terminal, colour and width detected unless given (a detected width that is
    not usable becomes one that is: see :func:`usable_width`); no colour at all without
    ``colour``."""
    from rich.console import Console  # noqa: PLC0415  # rich only when something is drawn

    console = Console(
        file=stream,
        width=width,
        force_terminal=force_terminal,
        color_system="auto" if colour else None,
        no_color=None if colour else True,
        markup=False,
        emoji=False,
        highlight=False,
    )
    if width is None:
        console.width = usable_width(console.width)
    return console


def bar_terminal(stream: TextIO, *, quiet: bool = False) -> bool:
    """Whether a progress bar may be drawn on ``stream``: not ``quiet``, and a terminal that is
    not dumb (a bar in a pipe or a log file would only be noise)."""
    if quiet:
        return False
    isatty = getattr(stream, "isatty", None)
    if isatty is None or not isatty():
        return False
    from rich.console import Console  # noqa: PLC0415  # rich only when something is drawn

    console = Console(file=stream)
    return console.is_terminal and not console.is_dumb_terminal


def progress_bar(stream: TextIO, *, quiet: bool = False) -> ProgressBar | None:
    """A progress bar on ``stream``, or None under ``--quiet`` or when it is not a terminal
    (rich's progress machinery is loaded only for a bar that is drawn)."""
    if not bar_terminal(stream, quiet=quiet):
        return None
    from medkit_replay.outputs.progress import ProgressBar  # noqa: PLC0415

    return ProgressBar(stream)


def plain_text(renderable: RenderableType, width: int, *, crop: bool = True) -> str:
    """``renderable`` as plain text (no ANSI codes) laid out for ``width`` columns."""
    buffer = io.StringIO()
    console = literal_console(buffer, width=width, force_terminal=False, colour=False)
    console.print(renderable, crop=crop)
    return strip_trailing(buffer.getvalue())


def strip_trailing(text: str) -> str:
    """Drop the spaces rich pads lines with (they only clutter logs and files)."""
    return "\n".join(line.rstrip(" ") for line in text.split("\n"))


def draw(console: Console, renderable: RenderableType, *, crop: bool = True) -> None:
    """Print on a terminal as rich does; elsewhere the same text without padding spaces.
    ``crop=False`` keeps a line wider than the console whole (a long code on its own line)."""
    if console.is_terminal:
        console.print(renderable, crop=crop)
        return
    console.file.write(drawn(console, renderable, crop=crop))


def drawn(console: Console, renderable: RenderableType, *, crop: bool = True) -> str:
    """What :func:`draw` would print, as text to print later (plain unless on a terminal).

    Laid out by a twin of ``console`` on a string (same width, terminal or not, colours): rich
    writes to a console's stream even while capturing, and this must not touch it.
    """
    twin = literal_console(io.StringIO(), width=console.width, force_terminal=console.is_terminal)
    with twin.capture() as capture:
        twin.print(renderable, crop=crop)
    text = capture.get()
    return text if console.is_terminal else strip_trailing(text)


def echo(text: str, stream: TextIO | None = None) -> None:
    """Write text to a stream (standard output by default)."""
    print(text, end="", file=stream or sys.stdout)


def warn(message: str) -> None:
    """A warning an output writer has about what it wrote, on standard error (one line)."""
    sys.stderr.write(f"medkit-replay: warning: {message}\n")
