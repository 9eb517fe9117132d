"""``medkit-replay analyze``: replay recordings and write the report in every format asked for.

Outputs are refused before the replay when they would land on an input or a config file, and
the evidence folder when it is, holds or lies inside one.
"""

from __future__ import annotations

import sys
from contextlib import nullcontext
from pathlib import Path
from typing import TYPE_CHECKING

import click

from medkit_replay.commands import (
    config_option,
    foreign_clips,
    input_argument,
    local_paths,
    path_option,
    say_written,
    stacked,
    writing,
)
from medkit_replay.commands.streams import standard_output
from medkit_replay.outputs import OUTPUTS, FileOutput

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from medkit_replay.outputs.json_report import EncodedAhead
    from medkit_replay.result import Result


_REPORT_OPTIONS = (
    click.option(
        "--json",
        "json_out",
        type=str,
        default=None,
        metavar="FILE|-",
        help="Write the JSON report here ('-': standard output; FILE.gz or FILE.zst compressed).",
    ),
    path_option(
        "--csv", "csv_dir", kind="any", help="Write every report table as CSV into this directory."
    ),
    path_option(
        "--parquet",
        "parquet_dir",
        kind="any",
        help="Write every report table as Parquet into this directory (needs the 'parquet' extra).",
    ),
    path_option(
        "--mcap",
        "mcap_out",
        help="Write the replayed FaultEvents and status changes as an MCAP recording.",
    ),
    path_option(
        "--html",
        "html_out",
        help="Write a self-contained HTML report (fault timeline, counter traces, correlation).",
    ),
)

report_options = stacked(*_REPORT_OPTIONS)
"""The options naming the report files ``analyze`` (and ``follow``) write."""


ALL_OPTION = click.option(
    "--all",
    "everything",
    is_flag=True,
    help="Print the whole summary (by default it is cut to some 60 lines, worst faults first).",
)
"""The option that prints the summary uncut (``analyze`` and ``follow``)."""


@click.command()
@input_argument("inputs")
@config_option()
@report_options
@path_option(
    "--graph",
    "graph_file",
    help="The robot's node graph (YAML node -> publishers/subscribers, or `ros2 node info` "
    "text): entity-default freeze frames and entity-scoped recordings need it.",
)
@path_option(
    "--evidence",
    "evidence_dir",
    kind="folder",
    help="Write each black-box recording (snapshots.rosbag.enabled) here as a rosbag2 folder "
    "(a folder there is replaced only when an earlier run wrote it: .medkit-replay-clip).",
)
@click.option(
    "--evidence-all",
    is_flag=True,
    help="With --evidence: also write the recordings the live manager would have deleted.",
)
@click.option("--quiet", is_flag=True, help="No human summary, no progress bar.")
@ALL_OPTION
def analyze(
    inputs: tuple[Path | str, ...],
    configs: tuple[Path, ...],
    json_out: str | None,
    csv_dir: Path | None,
    parquet_dir: Path | None,
    mcap_out: Path | None,
    html_out: Path | None,
    graph_file: Path | None,
    evidence_dir: Path | None,
    evidence_all: bool,
    quiet: bool,
    everything: bool,
) -> None:
    """Replay INPUT... (merged as one recording) and report what the fault manager concluded.

    Exit status: 0 done; 2 bad usage, an input that does not exist or cannot be read, an
    invalid config, or an output over an input.

    \b
    Examples:
      medkit-replay analyze mission/ --config robot_params.yaml --json report.json
      medkit-replay analyze run.jsonl --json - --quiet
      medkit-replay analyze bag/ --html report.html
      medkit-replay analyze mission/ --mcap replayed.mcap --parquet tables/
      medkit-replay analyze mission/ --config capture.yaml --graph graph.txt --evidence clips/
      medkit-replay analyze s3://fleet-bags/robot7/mission_0412/ --config robot_params.yaml
    """
    # Imported here, so that --help and the other commands start without them.
    from medkit_replay.evidence import EvidenceOptions, load_graph  # noqa: PLC0415
    from medkit_replay.outputs.json_ahead import JsonAhead  # noqa: PLC0415
    from medkit_replay.pipeline import replay  # noqa: PLC0415

    if evidence_all and evidence_dir is None:
        raise click.UsageError("--evidence-all needs --evidence DIR")
    targets = {"--csv": csv_dir, "--parquet": parquet_dir, "--mcap": mcap_out, "--html": html_out}
    # The node graph is read like a config: no output may land on it.
    read = (*inputs, graph_file) if graph_file is not None else inputs
    chosen, writers = prepare_reports(read, configs, json_out, targets, evidence_dir)
    evidence = EvidenceOptions(
        graph=load_graph(graph_file) if graph_file is not None else None,
        directory=evidence_dir,
        everything=evidence_all,
    )
    bar = None
    if not quiet:  # rich (bar and summary) is loaded only for people to read
        from medkit_replay.outputs.console import progress_bar  # noqa: PLC0415

        bar = progress_bar(sys.stderr)
    # The report's long lists are encoded by a helper process while the replay runs.
    with JsonAhead() if json_out is not None else nullcontext() as ahead:
        with bar if bar is not None else nullcontext():
            result = replay(
                list(inputs), list(configs), progress=bar, evidence=evidence, spill_listener=ahead
            )
        if ahead is not None:
            ahead.finish()
        write_reports(
            result, json_out, chosen, writers, quiet=quiet, ahead=ahead, everything=everything
        )
    if result.evidence_refused:
        raise foreign_clips(result.evidence_refused, outputs=True)


def prepare_reports(
    inputs: Sequence[Path | str],
    configs: Sequence[Path],
    json_out: str | None,
    targets: dict[str, Path | None],
    evidence_dir: Path | None = None,
) -> tuple[list[tuple[FileOutput, Path]], list[Callable[[Result, Path], object]]]:
    """The outputs asked for (by option) and their writers, refused before any replay when an
    optional dependency is missing, a path would land on an input or a config file (or a file
    a config names), or the evidence folder is, holds or lies inside one of them."""
    from medkit_replay.config.referenced import config_files  # noqa: PLC0415
    from medkit_replay.evidence.folder import refuse_folder_overlap  # noqa: PLC0415
    from medkit_replay.outputs.atomic import refuse_overlap  # noqa: PLC0415

    chosen = [
        (output, target) for output in OUTPUTS if (target := targets[output.option]) is not None
    ]
    writers = [output.load() for output, _ in chosen]  # a missing extra is said before the replay
    read = [*local_paths(inputs), *config_files(configs)]
    refuse_overlap(read, _output_paths(json_out, chosen))
    if evidence_dir is not None:
        refuse_folder_overlap(evidence_dir, read)
    return chosen, writers


def write_reports(
    result: Result,
    json_out: str | None,
    chosen: list[tuple[FileOutput, Path]],
    writers: list[Callable[[Result, Path], object]],
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

    def job(output: FileOutput, target: Path, writer: Callable[[Result, Path], object]) -> Job:
        def write() -> None:
            with writing(output.label, target):
                if output.files is None:  # a file: its folder is made, as --csv makes its own
                    target.parent.mkdir(parents=True, exist_ok=True)
                writer(result, target)

        return output.label, write

    pairs = zip(chosen, writers, strict=True)
    jobs = [job(output, target, writer) for (output, target), writer in pairs]
    summary = sys.stderr if json_out == "-" else sys.stdout
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
                Path(json_out).parent.mkdir(parents=True, exist_ok=True)
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
