"""``medkit-replay diff BASELINE CURRENT``: what changed between two reports, or since a baseline.

Thin: reads or replays both sides, hands the report dicts to :mod:`medkit_replay.diffing`, writes
its human and JSON output, rewrites the baseline on ``--update``.
"""

from __future__ import annotations

import json
import shutil
import sys
from contextlib import nullcontext
from pathlib import Path
from typing import TYPE_CHECKING, TextIO

import click

from medkit_replay.commands import (
    config_option,
    count_option,
    input_argument,
    local_paths,
    say_written,
    writing,
)
from medkit_replay.commands.streams import standard_output
from medkit_replay.errors import MedkitReplayError
from medkit_replay.files import MIB, REPORT_COMPRESSIONS, open_regular

if TYPE_CHECKING:
    from medkit_replay.diffing import ReportDiff
    from medkit_replay.result import Result


REPORT_SUFFIXES = (".json", *(f".json{suffix}" for suffix in REPORT_COMPRESSIONS))


def is_report_path(path: Path | str) -> bool:
    """A local ``.json`` file (or ``.json.gz``, ``.json.zst``) is read as a report; anything
    else is a recording or script to replay (a URL is a recording)."""
    return isinstance(path, Path) and path.name.lower().endswith(REPORT_SUFFIXES)


class _Side:
    """One side of the diff: a report read from a file, or a recording replayed now."""

    def __init__(
        self, path: Path | str, configs: tuple[Path, ...], *, quiet: bool, limit: int
    ) -> None:
        from medkit_replay.diffing import read_report  # noqa: PLC0415
        from medkit_replay.outputs.console import progress_bar  # noqa: PLC0415
        from medkit_replay.outputs.json_report import to_report  # noqa: PLC0415
        from medkit_replay.pipeline import replay  # noqa: PLC0415

        self.path = path
        self.result: Result | None = None
        if isinstance(path, Path) and is_report_path(path):
            self.report = read_report(path, limit)
            return
        bar = progress_bar(sys.stderr, quiet=quiet)
        with bar if bar is not None else nullcontext():
            self.result = replay([path], list(configs), progress=bar)
        self.report = to_report(self.result)

    @property
    def name(self) -> str:
        return str(self.path) if self.result is None else f"{self.path} (replayed now)"


def _write_baseline(baseline: Path, current: _Side, limit: int) -> None:
    """Replace the baseline with the current report, atomically (a crash leaves the old one),
    compressed as the baseline's name says; the baseline keeps its permission bits."""
    from medkit_replay.diffing.reports import report_bytes  # noqa: PLC0415
    from medkit_replay.files import report_compression  # noqa: PLC0415
    from medkit_replay.outputs.atomic import atomic_binary  # noqa: PLC0415
    from medkit_replay.outputs.json_report import write_json_bytes  # noqa: PLC0415
    from medkit_replay.outputs.report_file import compressed  # noqa: PLC0415

    try:
        with atomic_binary(baseline) as raw:
            if current.result is not None:
                with compressed(raw, report_compression(baseline)) as stream:
                    write_json_bytes(current.result, stream)
            elif report_compression(current.path) == report_compression(baseline):
                with open_regular(current.path) as source:  # its bytes as they are
                    shutil.copyfileobj(source, raw)
            else:
                assert isinstance(current.path, Path)  # read from a file: a URL is replayed
                text = report_bytes(current.path, limit)
                with compressed(raw, report_compression(baseline)) as stream:
                    stream.write(text)
    except OSError as err:
        raise MedkitReplayError(
            f"cannot update the baseline: {err.strerror or err}", path=str(baseline)
        ) from None


def _print(diff: ReportDiff, stream: TextIO, notes: list[str]) -> None:
    from rich.console import Console  # noqa: PLC0415
    from rich.text import Text  # noqa: PLC0415

    from medkit_replay.diffing import diff_renderable  # noqa: PLC0415

    console = Console(file=stream, markup=False, emoji=False, highlight=False)
    renderable = diff_renderable(diff)
    if console.is_terminal:
        console.print(renderable, crop=False)
        for note in notes:
            console.print(Text(note, style="bold"))
        return
    with console.capture() as capture:  # plain text, no padding, as the summary is written
        console.print(renderable, crop=False)
    text = "\n".join(line.rstrip(" ") for line in capture.get().split("\n"))
    stream.write(text + "".join(note + "\n" for note in notes))


@click.command()
@click.argument("baseline", type=click.Path(path_type=Path))
@input_argument("current", many=False)
@config_option("ROS 2 parameter file for a side that is replayed (repeatable).")
@click.option(
    "--time-tolerance",
    "time_tolerance",
    type=click.FloatRange(min=0.0),
    default=0.0,
    show_default=True,
    metavar="SEC",
    help="Events and transitions shifted by at most this many seconds of bag time are equal.",
)
@click.option(
    "--json",
    "json_out",
    type=str,
    default=None,
    metavar="FILE|-",
    help="Write the differences as JSON here ('-' for standard output).",
)
@click.option(
    "--update",
    is_flag=True,
    help="Rewrite BASELINE (a .json report) with the current report; exit 0.",
)
@count_option(
    "--max-report-mb",
    "max_report_mb",
    metavar="MB",
    help="Largest report read, plain or decompressed, in MiB (default 1024, or "
    "MEDKIT_REPLAY_MAX_REPORT_MB).",
)
@click.option("--quiet", is_flag=True, help="No human output, no progress bar.")
@click.pass_context
def diff(
    ctx: click.Context,
    baseline: Path,
    current: Path | str,
    configs: tuple[Path, ...],
    time_tolerance: float,
    json_out: str | None,
    update: bool,
    max_report_mb: int | None,
    quiet: bool,
) -> None:
    """Compare CURRENT with BASELINE: faults, status changes, FaultEvents and clusters.

    Each side is a JSON report (a .json file written by `analyze --json`) or a recording or
    script, replayed now with the --config files. Exit status: 0 equal; 1 different; 2 bad
    usage or input (not a report, a recording that cannot be read, an invalid config).

    \b
    Examples:
      medkit-replay diff baseline.json current.json
      medkit-replay diff baseline.json mission/ --config robot_params.yaml --time-tolerance 0.5
      medkit-replay diff baseline.json mission/ --config robot_params.yaml --update
    """
    # Imported here, so that --help and the other commands start without them.
    from medkit_replay.config.referenced import config_files  # noqa: PLC0415
    from medkit_replay.diffing import diff_reports, tolerance_ns  # noqa: PLC0415
    from medkit_replay.diffing.reports import report_size_limit  # noqa: PLC0415
    from medkit_replay.outputs.atomic import refuse_overlap, write_text_atomic  # noqa: PLC0415

    tolerance = tolerance_ns(time_tolerance)
    limit = report_size_limit(None if max_report_mb is None else max_report_mb * MIB)
    if json_out is not None and json_out != "-":
        refuse_overlap(
            [*local_paths([baseline, current]), *config_files(configs, check=False)],
            [("--json", Path(json_out))],
        )
    if update and not is_report_path(baseline):
        raise MedkitReplayError(
            "--update rewrites a baseline report: BASELINE must be a .json report",
            path=str(baseline),
        )
    notes: list[str] = []
    if configs and is_report_path(baseline) and is_report_path(current):
        notes.append("note: --config is not used: both sides are reports, nothing is replayed")
    new = _Side(current, configs, quiet=quiet, limit=limit)
    if update and not baseline.exists():
        _write_baseline(baseline, new, limit)
        if not quiet:
            out = sys.stderr if json_out == "-" else sys.stdout
            out.write(f"baseline created: {baseline}\n")
        return
    old = _Side(baseline, configs, quiet=quiet, limit=limit)
    result = diff_reports(
        old.report,
        new.report,
        time_tolerance_ns=tolerance,
        baseline_name=old.name,
        current_name=new.name,
    )
    if update:
        _write_baseline(baseline, new, limit)
        notes.append(f"baseline updated: {baseline}")
    document = result.to_json()
    if update:
        document["baseline_updated"] = True
    text = json.dumps(document, indent=2, ensure_ascii=True) + "\n"
    if json_out == "-":
        with standard_output("the diff"):
            sys.stdout.write(text)
    elif json_out is not None:
        with writing("diff", json_out):
            write_text_atomic(Path(json_out), text)
    if not quiet:
        if json_out == "-":
            _print(result, sys.stderr, notes)
        else:
            with standard_output("the diff"):
                _print(result, sys.stdout, notes)
    if json_out is not None and json_out != "-":
        say_written([json_out], quiet=quiet)
    if not result.equal and not update:
        ctx.exit(1)
