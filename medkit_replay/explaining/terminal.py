"""A fault's story drawn for people: colour on a terminal, plain text in a pipe or a file.

Every part that comes from a recording or a config is escaped (text.py) and cut, never parsed
as markup; our own words are styled by their role.
"""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, TextIO

from rich.console import Group
from rich.text import Text

from medkit_replay.outputs.console import draw, literal_console, plain_text
from medkit_replay.outputs.summary_lines import Flow, Piece, fixed, piece, words
from medkit_replay.outputs.times import EPOCH_FLOOR_NS, clock_time, start_text
from medkit_replay.result import release_line
from medkit_replay.text import clip, printable, seconds

if TYPE_CHECKING:
    from rich.console import Console, ConsoleOptions, RenderableType, RenderResult

    from medkit_replay.explaining.lines import Line
    from medkit_replay.explaining.story import Story

MAX_PART = 300
"""Characters of one recorded text shown (the JSON holds it whole)."""
STYLES = {
    "kind": "bold",
    "dim": "dim",
    "failed": "red",
    "passed": "green",
    "severity": "yellow",
    "source": "cyan",
    "topic": "cyan",
    "counter": "bold",
    "reject": "bold red",
    "held": "yellow",
    "muted": "magenta",
    "near": "bold yellow",
    "event": "bold blue",
    "code": "bold",
    "cluster": "blue",
    "text": "italic",
    "status:CONFIRMED": "bold red",
    "status:HEALED": "green",
    "status:CLEARED": "cyan",
    "status:PREFAILED": "yellow",
    "status:PREPASSED": "dim",
}


def styled(line: Line) -> Text:
    """A line as rich Text: every part escaped and cut, styled by its role, never markup."""
    text = Text()
    for value, role in line:
        text.append(printable(clip(value, MAX_PART)), style=STYLES.get(role, ""))
    return text


def _pieces(line: Line) -> list[Piece]:
    """A line as pieces of :func:`words`: broken at spaces only, never inside a code."""
    return [piece(printable(clip(value, MAX_PART)), STYLES.get(role, "")) for value, role in line]


Entry = tuple[str, str, list[list[Piece]]]
"""Seconds from the start, the clock time, the line then its details."""


class _Entries:
    """The story's lines beside their times, every code, name and number whole: a line is
    broken at spaces only (a word wider than the line whole on a line of its own)."""

    def __init__(self, entries: list[Entry]):
        self.entries = entries

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        at = max((len(t) for t, _, _ in self.entries), default=0)
        clock = max((len(c) for _, c, _ in self.entries), default=0)
        lead = at + 1 + (clock + 1 if clock else 0)
        room = max(options.max_width - lead, 20)
        for t, c, lines in self.entries:
            for number, pieces in enumerate(lines):
                laid = words(pieces, room, indent=2 if number else 0)
                for index, body in enumerate(laid):
                    line = Text()
                    if number == 0 and index == 0:
                        line.append(f"{t:>{at}} ")
                        if clock:
                            line.append(f"{c:<{clock}}", style="dim")
                            line.append(" ")
                    else:
                        line.append(" " * lead)
                    line.append_text(body)
                    line.rstrip()
                    yield fixed(line)


def story_renderable(story: Story) -> Group:
    """The whole story as one rich renderable."""
    clock = "; clock times UTC" if story.origin_ns >= EPOCH_FLOOR_NS else ""
    head = [
        piece(printable(clip(story.fault_code, MAX_PART)) + ":", "bold", whole=True),
        piece(f" its story in bag time (s from the start, {start_text(story.origin_ns)}{clock})"),
    ]
    parts: list[RenderableType] = [Flow(head)]
    for path in story.inputs:
        parts.append(fixed(f"  {printable(clip(path, MAX_PART))}", "dim"))
    parts.append(Text(release_line([story.upstream_release]), style="dim"))
    if story.at_ns is not None:
        parts.append(
            Text(f"stopped at {seconds(story.at_ns - story.origin_ns)} s (--at)", style="bold")
        )
    parts += [Flow(_pieces(line)) for line in story.header]
    entries = [
        (
            seconds(entry.t_ns - story.origin_ns),
            clock_time(entry.t_ns),
            [_pieces(entry.line), *(_pieces(detail) for detail in entry.details)],
        )
        for entry in story.entries
    ]
    parts += [Text(""), _Entries(entries), Text("")]
    parts += [Flow(_pieces(line)) for line in story.state]
    return Group(*parts)


def render_story(story: Story, width: int = 100) -> str:
    """The story as plain text laid out for ``width`` columns."""
    return plain_text(story_renderable(story), width, crop=False)


def print_story(story: Story, stream: TextIO | None = None) -> None:
    """Draw the story on ``stream`` (standard output by default): colour and the terminal's
    width on a terminal, plain text otherwise (``NO_COLOR``/``FORCE_COLOR`` honoured)."""
    console = literal_console(stream or sys.stdout)
    draw(console, story_renderable(story), crop=False)
