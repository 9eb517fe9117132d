"""``medkit-replay follow``: replay a recording while it is written, printing each change live.

When the recording is finished, or on Ctrl-C / SIGTERM, writes the same reports as ``analyze``.
"""

from __future__ import annotations

import signal
import sys
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, TextIO

import click

from medkit_replay.commands import config_option
from medkit_replay.commands.reports import (
    ALL_OPTION,
    prepare_reports,
    report_options,
    summary_stream,
    write_reports,
)
from medkit_replay.commands.streams import discard_stdout
from medkit_replay.errors import InputError
from medkit_replay.model import POLL_DEFAULT_S, POLL_MAX_S, POLL_MIN_S
from medkit_replay.outputs.console import echo

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator

    from medkit_replay.commands.reports import ReportTargets
    from medkit_replay.inputs.follow import Follow
    from medkit_replay.model import FaultEvent, Transition
    from medkit_replay.result import Result

STOP_SIGNALS = ("SIGINT", "SIGTERM", "SIGHUP")


@click.command()
@click.argument("recording", type=click.Path(path_type=Path))
@config_option()
@report_options
@click.option(
    "--poll",
    "poll_s",
    type=click.FloatRange(POLL_MIN_S, POLL_MAX_S),
    default=POLL_DEFAULT_S,
    show_default=True,
    help=f"Seconds between two looks at the recording ({POLL_MIN_S:g} to {POLL_MAX_S:g}).",
)
@click.option(
    "--idle-timeout",
    "idle_timeout_s",
    type=click.FloatRange(min=0, min_open=True),
    default=None,
    help="Stop following (and write the reports) when nothing new arrived for this many "
    "seconds; by default a recording that never finishes is followed until Ctrl-C.",
)
@click.option("--quiet", is_flag=True, help="No live lines, no human summary.")
@ALL_OPTION
def follow(
    recording: Path,
    configs: tuple[Path, ...],
    reports: ReportTargets,
    poll_s: float,
    idle_timeout_s: float | None,
    quiet: bool,
    everything: bool,
) -> None:
    """Replay RECORDING while it is being written, printing each status change and FaultEvent.

    RECORDING is a rosbag2 directory (MCAP or sqlite3 storage in WAL mode, split files) or a
    bare .mcap / .db3 file. The recording is only read, never locked or changed. When it is
    finished (metadata.yaml written; a bare MCAP's footer), or on Ctrl-C / SIGTERM, the
    reports are written as by 'analyze' (for a finished recording, the very same bytes).
    Exit status: 0 the reports are written; 2 bad usage, a recording that cannot be followed,
    an invalid config, or an output over the recording.

    \b
    Examples:
      medkit-replay follow field_test/ --config robot_params.yaml --json report.json
      medkit-replay follow run.mcap --html report.html --idle-timeout 60
    """
    # Imported here, so that --help and the other commands start without them.
    from medkit_replay.inputs.follow import Follow  # noqa: PLC0415

    prepared = prepare_reports([recording], configs, reports)
    control = Follow(poll_s=poll_s, idle_timeout_s=idle_timeout_s)
    stream = summary_stream(reports.json_out)
    with _stop_on_signals(control):
        _wait_to_appear(recording, control)
        echo(f"following {recording} (every {control.poll_s:g} s; Ctrl-C writes the report)\n",
             sys.stderr)  # fmt: skip
        result = _replay_following(recording, configs, control, None if quiet else stream)
    ending = (
        "the recording is finished"
        if control.finished
        else f"following stopped ({control.stopped or 'interrupted'})"
    )
    echo(f"medkit-replay: {ending}; writing the reports\n", sys.stderr)
    for note in control.notes:
        echo(f"medkit-replay: note: {note}\n", sys.stderr)
    write_reports(result, prepared, quiet=quiet, everything=everything)


def _replay_following(
    recording: Path, configs: tuple[Path, ...], control: Follow, stream: TextIO | None
) -> Result:
    """Replay the recording as it is written; when a file read was replaced or cut, say so
    and replay again from its start (the report is then the new file's, with a warning)."""
    from medkit_replay.inputs.watch import FollowRestart  # noqa: PLC0415
    from medkit_replay.pipeline import replay  # noqa: PLC0415

    live, live_start = (None, None) if stream is None else _printer(stream)
    while True:
        try:
            result = replay(
                [recording], list(configs), follow=control, live=live, live_start=live_start
            )
        except FollowRestart as restart:
            echo(f"medkit-replay: {restart.reason}; replaying it from its start\n", sys.stderr)
            control.restart(restart.reason)
            _wait_to_appear(recording, control)
            continue
        # Added here, not by the input: a report replayed once more as it stands (recorded
        # ReportFault calls that came late) says it too.
        said = tuple(
            f"{reason} while it was followed; this report is a replay of what the path held "
            "then, from its start"
            for reason in control.restarts
        )
        return replace(result, warnings=(*said, *result.warnings)) if said else result


def _wait_to_appear(recording: Path, control: Follow) -> None:
    """Wait for a recording not created yet (the recorder may start after us)."""
    from medkit_replay.inputs.follow import FollowStopped  # noqa: PLC0415

    said = False
    while not recording.exists():
        if not said:
            echo(f"waiting for {recording} to appear\n", sys.stderr)
            said = True
        try:
            control.wait()
        except FollowStopped:
            raise InputError("input not found", path=str(recording)) from None


def _printer(
    stream: TextIO,
) -> tuple[Callable[[Transition | FaultEvent], None], Callable[[int], None]]:
    """Writes each record's line at once, its time counted from the recording's start (said
    in a header line when known); a reader that went away ends the lines quietly."""
    from medkit_replay.outputs.live import live_line, start_line  # noqa: PLC0415

    gone = False
    origin: list[int] = []

    def write(line: str) -> None:
        nonlocal gone
        if gone:
            return
        try:
            stream.write(line + "\n")
            stream.flush()
        except BrokenPipeError:
            gone = True
            if stream is sys.stdout:
                discard_stdout()

    def start(origin_ns: int) -> None:
        origin[:] = [origin_ns]
        write(start_line(origin_ns))

    def show(record: Transition | FaultEvent) -> None:
        write(live_line(record, origin[0] if origin else None))

    return show, start


@contextmanager
def _stop_on_signals(control: Follow) -> Iterator[None]:
    """Ctrl-C, SIGTERM and SIGHUP end the following (the reports are then written); a second
    one interrupts at once."""

    def stop(signum: int, _frame: object) -> None:
        if control.stop_reason is not None:
            raise KeyboardInterrupt
        control.request_stop(f"interrupted by {signal.Signals(signum).name}")

    saved: dict[int, object] = {}
    for name in STOP_SIGNALS:
        signum = getattr(signal, name, None)
        if signum is not None:
            saved[signum] = signal.signal(signum, stop)
    try:
        yield
    finally:
        for signum, handler in saved.items():
            signal.signal(signum, handler)  # type: ignore[arg-type]  # what signal() returned
