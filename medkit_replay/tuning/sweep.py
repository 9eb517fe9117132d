"""A whole sweep: the grid checked, jobs planned and run (processes or Dask), rows streamed to
the tables in a fixed order, totals and ranking at the end.

Rows are written as jobs finish, in job order (a job that finishes early waits in a small
buffer), so memory stays flat however many rows the sweep makes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from operator import attrgetter
from pathlib import Path
from typing import TYPE_CHECKING, Any

from medkit_replay.config.params import load_parameters
from medkit_replay.fleet.cluster import run_jobs_on_dask
from medkit_replay.fleet.workers import run_jobs
from medkit_replay.outputs.atomic import write_text_atomic
from medkit_replay.tuning.grid import check_names, make_grid, variant_config, variant_yaml
from medkit_replay.tuning.metrics import CODE_COLUMNS, RUN_COLUMNS, CodeRow, RunRow
from medkit_replay.tuning.ranking import (
    CODE_TOTAL_COLUMNS,
    VARIANT_COLUMNS,
    CodeTotal,
    Totals,
    VariantTotal,
)
from medkit_replay.tuning.run import SweepJob, SweepPart, failed_part, sweep_job
from medkit_replay.tuning.tables import TableWriter, column_kinds

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from medkit_replay.checks import Budget
    from medkit_replay.model import Loss
    from medkit_replay.tuning.grid import Variant, Vary

TABLES = ("runs", "run_codes", "variants", "codes")
"""The tables of ``--out DIR``, each as .csv and .parquet."""
VARIANTS_FOLDER = "variants"
"""Under ``--out``: one parameter file per variant, to give ``analyze`` after the base configs."""


@dataclass(frozen=True, slots=True)
class Grid:
    """The checked grid of a sweep and what reading its configs said."""

    varies: tuple[Vary, ...]
    variants: tuple[Variant, ...]
    warnings: tuple[str, ...]
    releases: dict[str, str]
    """The ros2_medkit release each variant models, by variant id."""

    @property
    def release_names(self) -> list[str]:
        """The releases the variants model, in grid order."""
        return list(dict.fromkeys(self.releases[v.id] for v in self.variants))


def checked_grid(configs: Sequence[Path], varies: Sequence[Vary]) -> Grid:
    """Build the grid and read every variant's config as its replays will. A warning every
    variant gives (one about a base config) is kept once; the others after their variant's id.

    Raises:
        ConfigError: a bad name or value (naming its ``--vary``), or a bad base config.
    """
    base = load_parameters(configs)
    variants = make_grid(varies)
    check_names(base, varies, variants)
    said: list[tuple[str, ...]] = []
    releases: dict[str, str] = {}
    for variant in variants:
        config = variant_config(base, variant)
        releases[variant.id] = config.manager.release.name
        said.append(config.warnings)
    shared = set(said[0]).intersection(*said[1:])
    warnings = [w for w in said[0] if w in shared]
    for variant, own in zip(variants, said, strict=True):
        warnings += [f"{variant.id}: {w}" for w in own if w not in shared]
    return Grid(tuple(varies), tuple(variants), tuple(dict.fromkeys(warnings)), releases)


def plan_jobs(
    inputs: Sequence[Path | str],
    configs: Sequence[Path],
    variants: Sequence[Variant],
    budget: Budget | None,
    workers: int,
) -> list[SweepJob]:
    """Jobs in input order, each input's variants split in as many shares as keep ``workers``
    busy (each share reads the input once per bridge setting)."""
    shares = max(1, min(len(variants), math.ceil(workers / max(len(inputs), 1))))
    size = math.ceil(len(variants) / shares)
    absolute = tuple(str(Path(c).absolute()) for c in configs)
    return [
        SweepJob(
            path if isinstance(path, str) else str(path.absolute()),
            str(path),
            absolute,
            tuple(variants[at : at + size]),
            budget,
        )
        for path in inputs
        for at in range(0, len(variants), size)
    ]


class _Ordered:
    """Takes parts as jobs finish and hands them on in job order."""

    def __init__(self, take: Callable[[SweepPart], None]) -> None:
        self.take = take
        self.waiting: dict[int, SweepPart] = {}
        self.next = 0

    def __call__(self, index: int, part: SweepPart) -> None:
        self.waiting[index] = part
        while self.next in self.waiting:
            self.take(self.waiting.pop(self.next))
            self.next += 1


MAX_OVER_KEPT = 100
"""Distinct (input, budget failures) pairs a sweep keeps for its summary; runs.csv has all."""


@dataclass(frozen=True, slots=True)
class Outcome:
    """What a sweep leaves for the summary and the page.

    Attributes:
        over: (input, budget failures, variants) for the first MAX_OVER_KEPT distinct ways an
            input failed the budget, with how many variants failed it so.
    """

    variants: tuple[VariantTotal, ...]
    codes: tuple[CodeTotal, ...]
    failed: tuple[RunRow, ...]
    over: tuple[tuple[str, str, int], ...] = ()
    lost: tuple[Loss, ...] = ()
    """What damage cost each input read only in part, in input order."""


def _columns(grid: Grid, names: Sequence[str]) -> list[str]:
    """The variant's id, then one column per varied parameter, then the row's own fields."""
    return [names[0], *(v.key for v in grid.varies), *names[1:]]


def run_sweep(
    plan: Sequence[SweepJob],
    grid: Grid,
    out_dir: Path | None,
    *,
    jobs: int = 1,
    dask_address: str | None = None,
    timeout: float | None = None,
    parquet: bool = False,
    on_done: Callable[[int, SweepPart], None] | None = None,
) -> Outcome:
    """Run the planned jobs (``plan_jobs``) and write the tables to ``out_dir`` (if given).

    ``jobs`` worker processes (1: this process), or ``dask_address``'s cluster, run them;
    ``on_done`` is told of each job as it ends.

    Raises:
        MedkitReplayError: the Dask scheduler cannot be reached; OSError: a table cannot be
            written.
    """
    settings = {
        v.id: [vary.cell(s) for vary, s in zip(grid.varies, v.settings, strict=True)]
        for v in grid.variants
    }
    totals = Totals(grid.variants, grid.releases)
    failed: list[RunRow] = []
    over: dict[tuple[str, str], int] = {}
    lost: dict[str, Loss] = {}
    writers: list[TableWriter] = []

    def open_writers() -> None:
        # Opened with the first rows (pyarrow, when the tables have Parquet, loads then).
        if out_dir is not None and not writers:
            for name, columns, record in (
                ("runs", RUN_COLUMNS, RunRow),
                ("run_codes", CODE_COLUMNS, CodeRow),
            ):
                writers.append(
                    TableWriter(
                        out_dir, name, _columns(grid, columns), _kinds(grid, record), parquet
                    )
                )

    run_values = attrgetter(*RUN_COLUMNS)
    code_values = attrgetter(*CODE_COLUMNS)

    def take(part: SweepPart) -> None:
        open_writers()
        if part.lost is not None:  # an input's several jobs each say it
            lost.setdefault(part.lost.input, part.lost)
        for row in part.runs:
            totals.add_run(row)
            if row.error:
                failed.append(row)
            key = (row.input, row.budget_failures)
            if row.budget == "fail" and (key in over or len(over) < MAX_OVER_KEPT):
                over[key] = over.get(key, 0) + 1
            if writers:
                values = run_values(row)
                writers[0].write((values[0], *settings[row.variant], *values[1:]))
        for code in part.codes:
            totals.add_code(code)
            if writers:
                values = code_values(code)
                writers[1].write((values[0], *settings[code.variant], *values[1:]))

    ordered = _Ordered(take)

    def done(index: int, part: SweepPart) -> None:
        ordered(index, part)
        if on_done is not None:
            on_done(index, part)

    try:
        if dask_address is not None:
            run_jobs_on_dask(
                dask_address, plan, sweep_job, _failed_job, timeout=timeout, on_done=done
            )
        else:
            run_jobs(plan, sweep_job, _failed_job, jobs=jobs, timeout=timeout, on_done=done)
        open_writers()
        variant_totals = totals.variant_totals()
        code_totals = tuple(totals.code_totals())
        if out_dir is not None:
            _write_totals(out_dir, grid, variant_totals, code_totals, settings, parquet)
    except BaseException as err:
        for writer in writers:
            writer.__exit__(type(err), err, err.__traceback__)
        raise
    for writer in writers:
        writer.__exit__(None, None, None)
    kept = tuple((path, why, n) for (path, why), n in over.items())
    return Outcome(tuple(variant_totals), code_totals, tuple(failed), kept, tuple(lost.values()))


def _kinds(grid: Grid, record: type[Any]) -> dict[str, str]:
    return {**column_kinds(record), **{v.key: v.kind for v in grid.varies}}


def _failed_job(job: SweepJob, problem: str) -> SweepPart:
    return failed_part(job, problem)


def _write_totals(
    out_dir: Path,
    grid: Grid,
    variants: Sequence[VariantTotal],
    codes: Sequence[CodeTotal],
    settings: dict[str, list[object]],
    parquet: bool,
) -> None:
    """The variants table (ranked, best first) and the codes table; a parameter file per
    variant under ``variants/``."""
    variant_columns = ["rank", "variant", *(v.key for v in grid.varies), *VARIANT_COLUMNS[2:]]
    with TableWriter(
        out_dir, "variants", variant_columns, _kinds(grid, VariantTotal), parquet
    ) as writer:
        variant_values = attrgetter(*VARIANT_COLUMNS)
        for total in variants:
            values = variant_values(total)
            writer.write((values[0], values[1], *settings[total.variant], *values[2:]))
    with TableWriter(
        out_dir, "codes", _columns(grid, CODE_TOTAL_COLUMNS), _kinds(grid, CodeTotal), parquet
    ) as writer:
        code_values = attrgetter(*CODE_TOTAL_COLUMNS)
        for code in codes:
            values = code_values(code)
            writer.write((values[0], *settings[code.variant], *values[1:]))
    folder = out_dir / VARIANTS_FOLDER
    folder.mkdir(exist_ok=True)
    for variant in grid.variants:
        write_text_atomic(folder / f"{variant.id}.yaml", variant_yaml(variant, folder))
