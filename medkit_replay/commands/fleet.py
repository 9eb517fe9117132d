"""``medkit-replay fleet INPUT_DIR...``: every recording under some folders, each its own run.

Thin: finds the recordings (:mod:`medkit_replay.fleet.discover`), runs them in processes
(:mod:`medkit_replay.fleet.workers`) or on a Dask cluster (:mod:`medkit_replay.fleet.cluster`),
writes the report (:mod:`medkit_replay.fleet.report`) and the summary
(:mod:`medkit_replay.fleet.terminal`).
"""

from __future__ import annotations

import sys
from contextlib import nullcontext
from pathlib import Path

import click

from medkit_replay.commands import (
    allow_empty_option,
    check_executor,
    config_option,
    executor_options,
    exit_on_failure,
    input_argument,
    local_paths,
    make_folder,
    optional_budget,
    path_option,
    strict_option,
    writing,
)
from medkit_replay.commands.streams import standard_output

DEFAULT_OUT = Path("fleet-report")


@click.command()
@input_argument("input_dirs")
@config_option(
    "ROS 2 parameter file for every run (repeatable; later files override earlier ones)."
)
@path_option("--budget", help="Fault budget YAML checked on every run (the budget column).")
@allow_empty_option()
@executor_options(
    "Kill a run that takes longer and report it as failed (runs in worker processes)."
)
@path_option(
    "--out",
    "out_dir",
    default=DEFAULT_OUT,
    show_default=True,
    kind="folder",
    help="Folder for runs.csv/.json, codes.csv/.json and index.html.",
)
@click.option("--quiet", is_flag=True, help="No summary, no progress bar.")
@strict_option()
def fleet(
    input_dirs: tuple[Path | str, ...],
    configs: tuple[Path, ...],
    budget: Path | None,
    allow_empty: bool,
    jobs: int | None,
    dask_address: str | None,
    timeout: float | None,
    out_dir: Path,
    quiet: bool,
    strict: bool,
) -> None:
    """Replay every recording under INPUT_DIR... as its own run and compare the runs.

    Recordings: rosbag2 folders, bare .mcap and .db3 files, ROS 1 .bag files, .jsonl scripts.
    A recording that cannot be replayed, times out or whose worker dies is reported in its
    row; the others still run. Exit status: 0 done, also when a recording cannot be read; 1 with
    --budget, when a run exceeds it, a recording cannot be read or replayed nothing (unless
    --allow-empty), or (with --strict) was read only in part; 2 bad usage, no recording found,
    an invalid config or budget.

    \b
    Examples:
      medkit-replay fleet missions/ --config robot_params.yaml --out fleet-report
      medkit-replay fleet missions/ --jobs 8 --timeout 600 --quiet
      medkit-replay fleet /shared/missions --dask tcp://scheduler:8786
      medkit-replay fleet s3://fleet-bags/2026-03/ --dask tcp://scheduler:8786
    """
    # Imported here, so that --help and the other commands start without them.
    from medkit_replay.config.params import load_parameters  # noqa: PLC0415
    from medkit_replay.config.referenced import config_files  # noqa: PLC0415
    from medkit_replay.config.release import release_of  # noqa: PLC0415
    from medkit_replay.fleet.cluster import run_on_dask  # noqa: PLC0415
    from medkit_replay.fleet.discover import discover_some  # noqa: PLC0415
    from medkit_replay.fleet.workers import run_all  # noqa: PLC0415
    from medkit_replay.outputs.atomic import refuse_overlap  # noqa: PLC0415

    check_executor(dask_address, jobs, strict=strict, budget=budget, units="runs")
    config_paths = config_files(configs)  # a bad config stops the fleet before it starts
    release = release_of(load_parameters(configs)).name
    parsed_budget = optional_budget(budget, allow_empty=allow_empty)
    from medkit_replay.fleet.report import (  # noqa: PLC0415  # pandas: only when it runs
        FILES,
        tabulated,
        write_texts,
    )
    from medkit_replay.fleet.terminal import fleet_progress, print_summary  # noqa: PLC0415

    protected = [*local_paths(input_dirs), *config_paths, *([budget] if budget is not None else [])]
    refuse_overlap(protected, [("--out", out_dir), *(("--out", out_dir / f) for f in FILES)])
    recordings = discover_some(input_dirs)
    make_folder(out_dir, "the report folder")
    bar = fleet_progress(sys.stderr, len(recordings), quiet=quiet)
    with bar if bar is not None else nullcontext():
        if dask_address is not None:
            runs = run_on_dask(
                dask_address,
                recordings,
                configs,
                budget=parsed_budget,
                timeout=timeout,
                on_done=bar,
            )
        else:
            runs = run_all(
                recordings, configs, budget=parsed_budget, jobs=jobs, timeout=timeout, on_done=bar
            )
    runs, texts = tabulated(runs)
    with writing("the fleet report", out_dir):
        write_texts(texts, out_dir)
    if not quiet:
        with standard_output("the fleet summary"):
            print_summary(runs, sys.stdout, out_dir, release)
    failed = any(not run.ok or run.budget == "fail" for run in runs)
    losses = (run.lost for run in runs if run.lost is not None)
    exit_on_failure(failed, budget=parsed_budget, strict=strict, losses=losses)
