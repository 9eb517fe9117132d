"""The report files ``analyze`` and ``follow`` write: their five options, gathered as one value,
checked before the replay (nothing may land on what it reads) and written after it."""

from __future__ import annotations

import functools
import sys
from contextlib import nullcontext
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

import click

from medkit_replay.commands import local_paths, path_option, say_written, stacked, writing
from medkit_replay.commands.streams import standard_output
from medkit_replay.outputs import OUTPUTS, FileOutput

if TYPE_CHECKING:
    from collections.abc import Callable, Mapping, Sequence

    from medkit_replay.outputs.json_report import EncodedAhead
    from medkit_replay.result import Result

    Writer = Callable[[Result, Path], object]


@dataclass(frozen=True, slots=True)
class ReportTargets:
    """Where the reports go, as the options said: ``json_out`` a path or ``-`` (standard
    output), and each file output's path by its option (None when not asked for)."""

    json_out: str | None
    paths: Mapping[str, Path | None]


def _dest(option: str) -> str:
    return f"report_{option.removeprefix('--')}"


def report_options(command: Callable[..., None]) -> Callable[..., None]:
    """The ``--json``, ``--csv``, ``--parquet``, ``--mcap`` and ``--html`` options, handed to
    ``command`` as one ``reports: ReportTargets`` argument."""

    @functools.wraps(command)
    def with_targets(*args: Any, report_json: str | None, **kwargs: Any) -> None:
        paths = {output.option: kwargs.pop(_dest(output.option)) for output in OUTPUTS}
        command(*args, reports=ReportTargets(report_json, paths), **kwargs)

    json_option = click.option(
        "--json",
        "report_json",
        type=str,
        default=None,
        metavar="FILE|-",
        help="Write the JSON report here ('-': standard output; FILE.gz or FILE.zst compressed).",
    )
    file_options = (
        path_option(
            output.option,
            _dest(output.option),
            kind="file" if output.files is None else "any",
            help=output.help,
        )
        for output in OUTPUTS
    )
    return stacked(json_option, *file_options)(with_targets)


ALL_OPTION = click.option(
    "--all",
    "everything",
    is_flag=True,
    help="Print the whole summary (by default it is cut to some 60 lines, worst faults first).",
)
"""The option that prints the summary uncut (``analyze`` and ``follow``)."""


@dataclass(frozen=True, slots=True)
class Reports:
    """The reports asked for, checked, with their writers loaded: ready for a result."""

    json_out: str | None
    chosen: list[tuple[FileOutput, Path]]
    writers: list[Writer]


def prepare_reports(
    inputs: Sequence[Path | str],
    configs: Sequence[Path],
    targets: ReportTargets,
    evidence_dir: Path | None = None,
) -> Reports:
    """The outputs asked for and their writers, refused before any replay when an optional
    dependency is missing, a path would land on an input or a config file (or a file a config
    names), or the evidence folder is, holds or lies inside one of them."""
    from medkit_replay.config.referenced import config_files  # noqa: PLC0415
    from medkit_replay.evidence.folder import refuse_folder_overlap  # noqa: PLC0415
    from medkit_replay.outputs.atomic import refuse_overlap  # noqa: PLC0415

    chosen = [
        (output, target)
        for output in OUTPUTS
        if (target := targets.paths[output.option]) is not None
    ]
    writers = [output.load() for output, _ in chosen]  # a missing extra is said before the replay
    read = [*local_paths(inputs), *config_files(configs)]
    refuse_overlap(read, _output_paths(targets.json_out, chosen))
    if evidence_dir is not None:
        refuse_folder_overlap(evidence_dir, read)
    return Reports(targets.json_out, chosen, writers)


def summary_stream(json_out: str | None) -> TextIO:
    """Where people's text goes: standard error when the JSON report takes standard output."""
    return sys.stderr if json_out == "-" else sys.stdout


def write_reports(
    result: Result,
    reports: Reports,
    *,
    quiet: bool,
    ahead: EncodedAhead | None = None,
    everything: bool = False,
) -> None:
    """Write the JSON report and every chosen output, then the human summary (unless quiet;
    uncut with ``everything``).

    ``ahead`` may hold batches of the report's long lists already encoded."""
    from medkit_replay.outputs.forked import Forked, Job  # noqa: PLC0415
    from medkit_replay.outputs.report_file import write_report, write_report_stdout  # noqa: PLC0415

    def job(output: FileOutput, target: Path, writer: Writer) -> Job:
        def write() -> None:
            with writing(output.label, target):
                writer(result, target)

        return output.label, write

    json_out, chosen = reports.json_out, reports.chosen
    pairs = zip(chosen, reports.writers, strict=True)
    jobs = [job(output, target, writer) for (output, target), writer in pairs]
    summary = summary_stream(json_out)
    text = None
    # With a JSON report to write as well, the other outputs are written meanwhile by a child
    # (one it leaves undone, killed, is written here after the report).
    targets = [path for _, path in _output_paths(None, chosen)]
    with Forked(jobs, targets) if json_out is not None and chosen else nullcontext():
        if not quiet:  # drawn now, while the children work; printed once all is written
            from medkit_replay.outputs.terminal import summary_text  # noqa: PLC0415

            text = summary_text(result, summary, everything=everything)
        if json_out == "-":
            with standard_output("the report"):
                write_report_stdout(result, ahead)
        elif json_out is not None:
            with writing("report", json_out):
                write_report(result, Path(json_out), ahead)
    if json_out is None or not chosen:
        for _, write in jobs:
            write()
    if text is not None:
        if summary is sys.stderr:
            summary.write(text)
        else:
            with standard_output("the summary"):
                summary.write(text)
    written: list[str | Path] = [json_out] if json_out is not None and json_out != "-" else []
    say_written([*written, *(target for _, target in chosen)], quiet=quiet)


def _output_paths(
    json_out: str | None, chosen: list[tuple[FileOutput, Path]]
) -> list[tuple[str, Path]]:
    """Every path an output would write, with the option that names it."""
    paths: list[tuple[str, Path]] = []
    if json_out is not None and json_out != "-":
        paths.append(("--json", Path(json_out)))
    for output, target in chosen:
        paths.append((output.option, target))
        if output.files is not None:
            paths.extend((output.option, path) for path in output.files(target))
    return paths
