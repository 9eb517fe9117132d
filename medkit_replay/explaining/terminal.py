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
from medkit_replay.outputs.summary_lines import Beside, Flow, Piece, fixed, piece
from medkit_replay.outputs.times import EPOCH_FLOOR_NS, clock_time, start_text
from medkit_replay.result import release_line
from medkit_replay.text import clip, printable, seconds

if TYPE_CHECKING:
    from rich.console import RenderableType

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


def _beside_times(entries: list[Entry]) -> Beside:
    """The story's lines beside their times (seconds right-aligned, then the clock time),
    details indented under their line."""
    at = max((len(t) for t, _, _ in entries), default=0)
    clock = max((len(c) for _, c, _ in entries), default=0)
    rows = []
    for t, c, (line, *details) in entries:
        lead = Text(f"{t:>{at}} ")
        if clock:
            lead.append(f"{c:<{clock}}", style="dim")
            lead.append(" ")
        rows.append((lead, [Flow(line), *(Flow(detail, indent=2) for detail in details)]))
    return Beside(rows, least=20)


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
    parts += [Text(""), _beside_times(entries), Text("")]
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
