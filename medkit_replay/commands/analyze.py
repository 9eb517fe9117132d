"""``medkit-replay analyze``: replay recordings and write the report in every format asked for.

Outputs are refused before the replay when they would land on an input or a config file.
"""

from __future__ import annotations

import sys
from contextlib import nullcontext
from pathlib import Path

import click

from medkit_replay.commands import config_option, input_argument, local_paths
from medkit_replay.commands.streams import standard_output
from medkit_replay.config.referenced import config_files
from medkit_replay.errors import MedkitReplayError
from medkit_replay.outputs import OUTPUTS, FileOutput
from medkit_replay.outputs.atomic import atomic_text, refuse_overlap
from medkit_replay.outputs.json_report import write_json
from medkit_replay.outputs.progress import progress_bar
from medkit_replay.outputs.terminal import print_summary
from medkit_replay.pipeline import replay


@click.command()
@input_argument("inputs")
@config_option()
@click.option(
    "--json",
    "json_out",
    type=str,
    default=None,
    help="Write the JSON report here ('-' for standard output).",
)
@click.option(
    "--csv",
    "csv_dir",
    type=click.Path(path_type=Path),
    default=None,
    help="Write every report table as CSV into this directory.",
)
@click.option(
    "--parquet",
    "parquet_dir",
    type=click.Path(path_type=Path),
    default=None,
    help="Write every report table as Parquet into this directory (needs the 'parquet' extra).",
)
@click.option(
    "--mcap",
    "mcap_out",
    type=click.Path(path_type=Path, dir_okay=False),
    default=None,
    help="Write the replayed FaultEvents and status changes as an MCAP recording.",
)
@click.option(
    "--html",
    "html_out",
    type=click.Path(path_type=Path, dir_okay=False),
    default=None,
    help="Write a self-contained HTML report (fault timeline, counter traces, correlation).",
)
@click.option("--quiet", is_flag=True, help="No human summary, no progress bar.")
def analyze(
    inputs: tuple[Path | str, ...],
    configs: tuple[Path, ...],
    json_out: str | None,
    csv_dir: Path | None,
    parquet_dir: Path | None,
    mcap_out: Path | None,
    html_out: Path | None,
    quiet: bool,
) -> None:
    """Replay INPUT... (merged as one recording) and report what the fault manager concluded.

    \b
    Examples:
      medkit-replay analyze mission/ --config robot_params.yaml --json report.json
      medkit-replay analyze run.jsonl --json - --quiet
      medkit-replay analyze bag/ --html report.html
      medkit-replay analyze mission/ --mcap replayed.mcap --parquet tables/
      medkit-replay analyze s3://fleet-bags/robot7/mission_0412/ --config robot_params.yaml
    """
    targets = {"--csv": csv_dir, "--parquet": parquet_dir, "--mcap": mcap_out, "--html": html_out}
    chosen = [
        (output, target) for output in OUTPUTS if (target := targets[output.option]) is not None
    ]
    writers = [output.load() for output, _ in chosen]  # a missing extra is said before the replay
    refuse_overlap([*local_paths(inputs), *config_files(configs)], _output_paths(json_out, chosen))
    bar = progress_bar(sys.stderr, quiet=quiet)
    with bar if bar is not None else nullcontext():
        result = replay(list(inputs), list(configs), progress=bar)
    if json_out == "-":
        with standard_output("the report"):
            write_json(result, sys.stdout)
    elif json_out is not None:
        try:
            with atomic_text(Path(json_out)) as stream:
                write_json(result, stream)
        except OSError as err:
            raise MedkitReplayError(
                f"cannot write report: {err.strerror or err}", path=json_out
            ) from None
    for (output, target), writer in zip(chosen, writers, strict=True):
        try:
            writer(result, target)
        except OSError as err:
            raise MedkitReplayError(
                f"cannot write {output.label}: {err.strerror or err}", path=str(target)
            ) from None
    if not quiet:
        if json_out == "-":
            print_summary(result, sys.stderr)
        else:
            with standard_output("the summary"):
                print_summary(result, sys.stdout)


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
