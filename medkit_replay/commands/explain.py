"""``medkit-replay explain INPUT... CODE``: one fault's story, from the one replay, in order.

Thin: replays with a FaultTrace for CODE, builds the story, draws it or writes its JSON.
"""

from __future__ import annotations

import math
import sys
from contextlib import nullcontext
from typing import TYPE_CHECKING

import click

from medkit_replay.commands import (
    config_option,
    count_option,
    input_argument,
    path_option,
)
from medkit_replay.commands.streams import standard_output
from medkit_replay.errors import MedkitReplayError
from medkit_replay.model import NS_PER_SEC
from medkit_replay.text import clip, printable

if TYPE_CHECKING:
    from pathlib import Path

MAX_CODE_SHOWN = 256
"""Characters of a code named in an error (the longest valid code, at 0.7.0)."""


class UnknownCodeError(MedkitReplayError):
    """The code asked for never appears in the recording (exit 2)."""


def _at_offset_ns(at: float | None, option: str = "--at") -> int | None:
    if at is None:
        return None
    if not math.isfinite(at):
        raise click.BadParameter(f"{at!r} is not a time in seconds", param_hint=f"'{option}'")
    return round(at * NS_PER_SEC)


@click.command()
@input_argument("inputs")
@click.argument("code", type=str)
@config_option()
@click.option(
    "--at",
    "at",
    type=float,
    default=None,
    metavar="SECONDS",
    help="Stop the story at this many seconds from the recording's start and show the fault's "
    "state then.",
)
@path_option(
    "--graph",
    "graph_file",
    help="The robot's node graph, as for 'analyze --graph': the freeze frames and recordings "
    "the story tells that use the faulting node's own topics need it.",
)
@click.option(
    "--from",
    "from_",
    type=float,
    default=None,
    metavar="SECONDS",
    help="Start the story at this many seconds from the recording's start (what came before "
    "is counted, not told).",
)
@count_option(
    "--limit",
    help="Tell at most this many reports, holds, decisions, status changes, events and clears "
    "(default 10,000); the rest are counted, not kept.",
)
@click.option("--json", "as_json", is_flag=True, help="Write the story as JSON records.")
@click.option("--quiet", is_flag=True, help="No progress bar.")
def explain(
    inputs: tuple[Path | str, ...],
    code: str,
    configs: tuple[Path, ...],
    at: float | None,
    graph_file: Path | None,
    from_: float | None,
    limit: int | None,
    as_json: bool,
    quiet: bool,
) -> None:
    """Tell the story of fault CODE in INPUT... (merged as one recording), in bag time.

    Every report that reached it (its bridge, topic and recorded message; accepted or why
    rejected; the debounce counter after it and the thresholds in force), the requests held
    before the manager, each status change and its cause, the events published or withheld,
    and every correlation decision. Exit status: 0 done; 2 bad usage, an input that cannot be
    read, an invalid config, or a code that never appears (naming the nearest ones).

    \b
    Examples:
      medkit-replay explain mission/ MOTOR_LEFT_OVERHEAT --config robot_params.yaml
      medkit-replay explain mission/ WIFI_SIGNAL_STRENGTH --config robot_params.yaml --at 57.3
      medkit-replay explain run.jsonl MOTOR_OVERHEAT --json > story.json
    """
    # The replay's machinery loads only when the command runs (``--help`` stays light).
    from medkit_replay.evidence import EvidenceOptions, load_graph  # noqa: PLC0415
    from medkit_replay.explaining import (  # noqa: PLC0415
        build_story,
        known_codes,
        nearest_codes,
        print_story,
        write_story_json,
    )
    from medkit_replay.outputs.console import progress_bar  # noqa: PLC0415
    from medkit_replay.pipeline import replay  # noqa: PLC0415
    from medkit_replay.trace import DEFAULT_STORY_LIMIT, FaultTrace  # noqa: PLC0415

    trace = FaultTrace(
        fault_code=code,
        at_offset_ns=_at_offset_ns(at),
        from_offset_ns=_at_offset_ns(from_, "--from"),
        limit=limit if limit is not None else DEFAULT_STORY_LIMIT,
    )
    bar = progress_bar(sys.stderr, quiet=quiet)
    with bar if bar is not None else nullcontext():
        result = replay(
            list(inputs),
            list(configs),
            progress=bar,
            trace=trace,
            evidence=EvidenceOptions(
                graph=load_graph(graph_file) if graph_file is not None else None
            ),
        )
    if not trace.seen:
        nearest = nearest_codes(code, known_codes(result))
        shown = ", ".join(printable(clip(c, MAX_CODE_SHOWN)) for c in nearest)
        raise UnknownCodeError(
            f"fault code '{printable(clip(code, MAX_CODE_SHOWN))}' never appears in the "
            "recording; "
            + (f"nearest codes: {shown}" if nearest else "no fault code appears at all")
        )
    story = build_story(result, trace)
    with standard_output("the story"):
        if as_json:
            write_story_json(story, sys.stdout)
        else:
            print_story(story, sys.stdout)
