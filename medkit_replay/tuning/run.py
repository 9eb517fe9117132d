"""One job of a sweep: one input replayed once per bridge setting, its requests fed to every
variant of a share of the grid, reduced to table rows.

``sweep_job`` is the per-job function in every executor (this process, worker processes, Dask);
it never raises for the input's sake: each row's ``error`` says why.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from medkit_replay.config.params import load_parameters
from medkit_replay.engine.manager import FaultManager
from medkit_replay.fleet.run import opened_recording, row_error, run_error
from medkit_replay.model import EngineOutput, Loss, total_loss
from medkit_replay.pipeline import replay_pass
from medkit_replay.pipeline.assemble import assemble_result
from medkit_replay.pipeline.routing import Router
from medkit_replay.pipeline.spooled import spooled_logs
from medkit_replay.tuning.fanout import FanOut
from medkit_replay.tuning.grid import variant_config
from medkit_replay.tuning.metrics import CodeRow, RunRow, Tally, run_row

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from medkit_replay.checks import Budget
    from medkit_replay.config.replay_options import ReplayOptions
    from medkit_replay.engine.manager import Row
    from medkit_replay.spool import Spool
    from medkit_replay.tuning.grid import Variant, VariantConfig


@dataclass(frozen=True, slots=True)
class SweepJob:
    """One input and the variants to run on it (plain, picklable).

    Attributes:
        path: the recording, as the job reads it (absolute on a cluster).
        label: how the rows name it (as it was given).
        configs: the base parameter files.
        variants: a share of the grid, in grid order.
        budget: checked on every variant with ``--budget``.
    """

    path: str
    label: str
    configs: tuple[str, ...]
    variants: tuple[Variant, ...]
    budget: Budget | None = None


@dataclass(frozen=True, slots=True)
class SweepPart:
    """A job's rows: one run row per variant, code rows variant by variant; what damage cost
    its input in total (None: nothing lost; not a column: ``--strict`` fails the sweep on it)."""

    runs: tuple[RunRow, ...]
    codes: tuple[CodeRow, ...]
    lost: Loss | None = None

    @property
    def ok(self) -> bool:
        """The input was replayed."""
        return not any(run.error for run in self.runs)


class _Variant:
    """One variant's manager, its tally and (with a budget) its spooled records."""

    def __init__(self, variant: Variant, config: VariantConfig, *, spooled: bool) -> None:
        self.variant = variant
        self.tally = Tally()
        report, event, transition = self.tally.sinks()
        self.logs: tuple[Spool[Any], ...] = ()
        if spooled:
            logs = spooled_logs()
            output = logs.output()
            self.logs = logs
            report = _tee(report, logs.reports.row_sink())
            event = _tee(event, logs.events.row_sink())
            transition = _tee(transition, logs.transitions.row_sink())
        else:
            output = EngineOutput()
        self.manager = FaultManager(config.manager, output)
        self.manager.set_row_sinks(report, event, transition)


def _tee(first: Callable[[Row], None], second: Callable[[Row], None]) -> Callable[[Row], None]:
    def both(row: Row) -> None:
        first(row)
        second(row)

    return both


def _groups(
    base_configs: Sequence[str], variants: Sequence[Variant]
) -> list[tuple[ReplayOptions, list[tuple[Variant, VariantConfig]]]]:
    """Variants grouped by their bridge settings (one pass over the recording each), in the
    order each setting first appears."""
    base = load_parameters(Path(c) for c in base_configs)
    groups: list[tuple[ReplayOptions, list[tuple[Variant, VariantConfig]]]] = []
    for variant in variants:
        config = variant_config(base, variant)
        for options, members in groups:
            if options == config.options:
                members.append((variant, config))
                break
        else:
            groups.append((config.options, [(variant, config)]))
    return groups


def _run_group(
    job: SweepJob,
    options: ReplayOptions,
    members: Sequence[tuple[Variant, VariantConfig]],
    losses: list[Loss],
) -> dict[int, tuple[RunRow, list[CodeRow]]]:
    spooled = job.budget is not None
    runs = [_Variant(variant, config, spooled=spooled) for variant, config in members]
    fan = FanOut([r.manager for r in runs])
    spools = [log for r in runs for log in r.logs[:3]]
    passed = replay_pass(
        [opened_recording(job.path)], Router(options), fan, fan.apply, fan.report_fields, spools
    )
    fan.finish()
    losses[:] = passed.losses  # the same damage whatever the bridge settings
    rows: dict[int, tuple[RunRow, list[CodeRow]]] = {}
    for run, timeline in zip(runs, fan.timelines, strict=True):
        variant_id = run.variant.id
        codes = run.tally.codes(run.manager, fan.last_ns, variant_id, job.label)
        row = run_row(
            run.manager, codes, passed.messages, variant_id, job.label, len(passed.warnings)
        )
        if job.budget is not None:
            from medkit_replay.checks import failed_rules  # noqa: PLC0415  # only with a budget

            events, transitions, reports, clears = run.logs
            result = assemble_result(
                run.manager,
                timeline,
                run.manager.output,
                passed.summaries,
                passed.messages,
                [],
                None,
                (events, transitions, reports, clears),
                {},
                passed.consumed,
            )
            failures = failed_rules(job.budget, result)
            row = replace(
                row, budget="fail" if failures else "pass", budget_failures=";".join(failures)
            )
        rows[run.variant.index] = (row, codes)
    return rows


def sweep_job(job: SweepJob) -> SweepPart:
    """Run one job: its input read once per bridge setting among its variants.

    Never raises for the input's sake: an input or config problem, or any other exception of
    the replay, is every row's ``error`` (one line).
    """
    try:
        opened_recording(job.path)  # refused here once, before any pass
        rows: dict[int, tuple[RunRow, list[CodeRow]]] = {}
        losses: list[Loss] = []
        for options, members in _groups(job.configs, job.variants):
            rows.update(_run_group(job, options, members, losses))
    except Exception as err:  # one input must not end the sweep
        error = run_error(job.path, err)
    else:
        ordered = [rows[v.index] for v in job.variants]
        return SweepPart(
            tuple(run for run, _ in ordered),
            tuple(c for _, codes in ordered for c in codes),
            total_loss(losses, job.label) if losses else None,
        )
    return failed_part(job, error)


def failed_part(job: SweepJob, problem: str) -> SweepPart:
    """Every variant of the job failed, for this reason (one line, the input named as given)."""
    error = row_error(problem, job.path, job.label, named_first=True)
    runs = tuple(RunRow(variant=v.id, input=job.label, error=error) for v in job.variants)
    return SweepPart(runs, ())
