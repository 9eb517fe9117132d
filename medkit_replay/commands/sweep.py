"""``medkit-replay sweep INPUT... --vary NODE.PARAM=V1,V2``: what-if runs over a grid of settings.

Thin: checks the grid (:mod:`medkit_replay.tuning.grid`), runs it
(:mod:`medkit_replay.tuning.sweep`), prints the ranking and writes the page.
"""

from __future__ import annotations

import importlib.util
import sys
from contextlib import nullcontext
from pathlib import Path

import click

from medkit_replay.commands import (
    allow_empty_option,
    check_executor,
    config_option,
    count_option,
    executor_options,
    exit_on_failure,
    input_argument,
    local_paths,
    make_folder,
    optional_budget,
    path_option,
    say_written,
    strict_option,
    writing,
)
from medkit_replay.commands.streams import standard_output
from medkit_replay.outputs.console import warn


@click.command()
@input_argument("inputs")
@config_option("ROS 2 parameter file under every variant (repeatable; later files override).")
@click.option(
    "--vary",
    "varies",
    multiple=True,
    required=True,
    metavar="NODE.PARAM=V1,V2,...",
    help="A parameter and its values (repeatable: the grid is every combination).",
)
@path_option(
    "--budget", help="Fault budget YAML checked on every variant x input (the budget columns)."
)
@allow_empty_option()
@executor_options("Kill a job (one input, a share of the grid) that takes longer; its rows say so.")
@path_option(
    "--out",
    "out_dir",
    kind="folder",
    help="Folder for the tables (runs, run_codes, variants, codes; CSV and Parquet) and a "
    "parameter file per variant (variants/v01.yaml...).",
)
@path_option(
    "--html",
    "html_path",
    help="Write a self-contained HTML page: trade-offs across variants, codes over the grid.",
)
@count_option(
    "--max-runs",
    help="Replays (variants x recordings) run at most (default 20,000): a larger sweep is "
    "refused before it starts.",
)
@click.option("--quiet", is_flag=True, help="No summary, no progress bar.")
@strict_option()
def sweep(
    inputs: tuple[Path | str, ...],
    configs: tuple[Path, ...],
    varies: tuple[str, ...],
    budget: Path | None,
    allow_empty: bool,
    jobs: int | None,
    dask_address: str | None,
    timeout: float | None,
    out_dir: Path | None,
    html_path: Path | None,
    max_runs: int | None,
    quiet: bool,
    strict: bool,
) -> None:
    """Replay INPUT... once per variant of a grid of settings and rank the variants.

    The grid is every combination of the --vary values, each over the layered --config files;
    any parameter of any node may vary, file-valued ones too (paths relative to the current
    folder). Each input is read once per worker and bridge setting, its requests fed to every
    variant. Exit status: 0 done, also when an input cannot be read; 1 with --budget, when a
    variant is over budget on some input, an input cannot be read or replayed nothing (unless
    --allow-empty), or (with --strict) was read only in part; 2 bad usage, an invalid config
    or grid.

    \b
    Examples:
      medkit-replay sweep missions/ --config robot.yaml \\
          --vary fault_manager.confirmation_threshold=-1,-3,-5 \\
          --vary fault_manager.healing_threshold=1,3 --out sweep-out --html sweep.html
      medkit-replay sweep run.mcap \\
          --vary fault_manager.correlation.config_file=rules_a.yaml,rules_b.yaml
    """
    from medkit_replay.config.referenced import config_files  # noqa: PLC0415
    from medkit_replay.fleet.discover import discover_some  # noqa: PLC0415
    from medkit_replay.fleet.progress import fleet_progress  # noqa: PLC0415
    from medkit_replay.fleet.workers import default_jobs  # noqa: PLC0415
    from medkit_replay.outputs.atomic import refuse_overlap  # noqa: PLC0415
    from medkit_replay.tuning.grid import check_runs, parse_vary  # noqa: PLC0415
    from medkit_replay.tuning.sweep import (  # noqa: PLC0415
        TABLES,
        VARIANTS_FOLDER,
        checked_grid,
        plan_jobs,
        run_sweep,
    )
    from medkit_replay.tuning.terminal import print_summary, summary_renderables  # noqa: PLC0415

    check_executor(dask_address, jobs, strict=strict, budget=budget, units="inputs")
    config_paths = config_files(configs)
    parsed = [parse_vary(spec) for spec in varies]
    recordings = discover_some(inputs)
    check_runs(parsed, len(recordings), max_runs)  # before a variant is built
    grid = checked_grid(configs, parsed)
    parsed_budget = optional_budget(budget, allow_empty=allow_empty)
    varied_files = [
        Path(str(s.value))
        for v in grid.variants
        for s in v.settings
        if s.name.endswith("config_file") and s.value
    ]
    protected = [*local_paths(inputs), *config_paths, *varied_files, *([budget] if budget else [])]
    outputs = [("--html", html_path)] if html_path is not None else []
    if out_dir is not None:
        outputs += [("--out", out_dir), ("--out", out_dir / VARIANTS_FOLDER)]
        outputs += [("--out", out_dir / f"{t}.{s}") for t in TABLES for s in ("csv", "parquet")]
    refuse_overlap(protected, outputs)
    parquet = False
    if out_dir is not None:
        parquet = _has_pyarrow()
        make_folder(out_dir, "the tables folder")
    for warning in grid.warnings:
        warn(warning)
    workers = 1 if dask_address is None and jobs == 1 else (jobs or default_jobs())
    plan = plan_jobs(recordings, configs, grid.variants, parsed_budget, workers)
    bar = fleet_progress(sys.stderr, len(plan), quiet=quiet)
    with writing("the sweep tables", out_dir), bar if bar is not None else nullcontext():
        outcome = run_sweep(
            plan,
            grid,
            out_dir,
            jobs=workers,
            dask_address=dask_address,
            timeout=timeout,
            parquet=parquet,
            on_done=bar,
        )
    if html_path is not None:
        from medkit_replay.tuning.page import write_page  # noqa: PLC0415  # only when asked

        with writing("the page", html_path):
            write_page(html_path, grid, outcome, len(recordings))
    if not quiet:
        with standard_output("the sweep summary"):
            parts = summary_renderables(
                outcome.variants,
                len(recordings),
                outcome.failed,
                out_dir,
                budget=parsed_budget is not None,
                over_budget=outcome.over,
            )
            print_summary(sys.stdout, parts)
    say_written([p for p in (html_path, out_dir) if p is not None], quiet=quiet)
    over = any(t.budget_failed or t.failed_runs for t in outcome.variants)
    exit_on_failure(over, budget=parsed_budget, strict=strict, losses=outcome.lost)


def _has_pyarrow() -> bool:
    """Whether pyarrow can be imported (not importing it yet); without it the tables are CSV
    only, said once."""
    if importlib.util.find_spec("pyarrow") is not None:
        return True
    from medkit_replay.outputs.parquet import EXTRA_HINT  # noqa: PLC0415  # pandas: only here

    warn(f"pyarrow is not installed: tables written as CSV only ({EXTRA_HINT})")
    return False
