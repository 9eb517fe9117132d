"""``medkit-replay analyze``: replay recordings and write the report in every format asked for.

Outputs are refused before the replay when they would land on an input or a config file, and
the evidence folder when it is, holds or lies inside one.
"""

from __future__ import annotations

import sys
from contextlib import nullcontext
from typing import TYPE_CHECKING

import click

from medkit_replay.commands import config_option, foreign_clips, input_argument, path_option
from medkit_replay.commands.reports import (
    ALL_OPTION,
    prepare_reports,
    report_options,
    write_reports,
)

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.commands.reports import ReportTargets


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
    reports: ReportTargets,
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
    # The node graph is read like a config: no output may land on it.
    read = (*inputs, graph_file) if graph_file is not None else inputs
    prepared = prepare_reports(read, configs, reports, evidence_dir)
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
    with JsonAhead() if reports.json_out is not None else nullcontext() as ahead:
        with bar if bar is not None else nullcontext():
            result = replay(
                list(inputs), list(configs), progress=bar, evidence=evidence, spill_listener=ahead
            )
        if ahead is not None:
            ahead.finish()
        write_reports(result, prepared, quiet=quiet, ahead=ahead, everything=everything)
    if result.evidence_refused:
        raise foreign_clips(result.evidence_refused, outputs=True)
