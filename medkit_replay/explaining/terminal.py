"""A fault's story drawn for people: colour on a terminal, plain text in a pipe or a file.

Every part that comes from a recording or a config is escaped (text.py) and cut, never parsed
as markup; our own words are styled by their role.
"""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, TextIO

from rich.console import Group
from rich.table import Table
from rich.text import Text

from medkit_replay.outputs.console import draw, literal_console, plain_text
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


def story_renderable(story: Story) -> Group:
    """The whole story as one rich renderable."""
    head = Text()
    head.append(printable(clip(story.fault_code, MAX_PART)), style="bold")
    clock = "; clock times UTC" if story.origin_ns >= EPOCH_FLOOR_NS else ""
    head.append(f": its story in bag time (s from the start, {start_text(story.origin_ns)}{clock})")
    parts: list[RenderableType] = [head]
    for path in story.inputs:
        parts.append(Text(f"  {printable(clip(path, MAX_PART))}", style="dim"))
    parts.append(Text(release_line([story.upstream_release]), style="dim"))
    if story.at_ns is not None:
        parts.append(
            Text(f"stopped at {seconds(story.at_ns - story.origin_ns)} s (--at)", style="bold")
        )
    parts += [styled(line) for line in story.header]
    grid = Table.grid(padding=(0, 1))
    grid.add_column(justify="right", no_wrap=True)
    grid.add_column(no_wrap=True, style="dim")
    grid.add_column(overflow="fold")
    for entry in story.entries:
        body = styled(entry.line)
        for detail in entry.details:
            body.append("\n  ")
            body.append_text(styled(detail))
        grid.add_row(seconds(entry.t_ns - story.origin_ns), clock_time(entry.t_ns), body)
    parts += [Text(""), grid, Text("")]
    parts += [styled(line) for line in story.state]
    return Group(*parts)


def render_story(story: Story, width: int = 100) -> str:
    """The story as plain text laid out for ``width`` columns."""
    return plain_text(story_renderable(story), width)


def print_story(story: Story, stream: TextIO | None = None) -> None:
    """Draw the story on ``stream`` (standard output by default): colour and the terminal's
    width on a terminal, plain text otherwise (``NO_COLOR``/``FORCE_COLOR`` honoured)."""
    console = literal_console(stream or sys.stdout)
    draw(console, story_renderable(story))
