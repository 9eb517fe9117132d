"""One run of a fleet: a recording replayed as ``analyze`` replays it, reduced to a small summary.

``run_one`` is the per-run function, the same in every executor: in this process, in worker
processes (``run_all``) or on a Dask distributed cluster (``run_on_dask``). It never raises for
a recording that cannot be replayed: the summary's ``error`` says why. Summaries come back in
input order whatever order the runs finish in.
"""

from __future__ import annotations

import multiprocessing
import os
from collections import Counter
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.config.fault_manager import fault_manager_config
from medkit_replay.config.params import load_parameters
from medkit_replay.config.replay_options import replay_options
from medkit_replay.errors import MedkitReplayError
from medkit_replay.inputs.recording import input_kind
from medkit_replay.pipeline import replay
from medkit_replay.result import STATUSES

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from distributed import Client

    from medkit_replay.checks import Budget
    from medkit_replay.result import Result

TOP_CODES = 5
"""Codes listed per run, most FAILED reports first."""
DASK_CONNECT_TIMEOUT = "20s"
"""How long ``--dask`` waits for the scheduler before giving up."""
DASK_EXTRA_HINT = "pip install 'medkit-replay[dask]'"

KINDS = {"dir": "rosbag2", ".mcap": "mcap", ".db3": "db3", ".jsonl": "script"}
"""A run's ``kind`` by READERS key: a bag directory, a bare storage file or a script."""


@dataclass(frozen=True, slots=True, kw_only=True)
class RunSummary:
    """What a fleet keeps of one run: small, plain, picklable.

    Attributes:
        path: the recording, as discovered.
        kind: ``rosbag2`` (a bag directory), ``mcap`` or ``db3`` (a bare file), ``script``.
        start_ns, end_ns: first and last log time of the recording (None when nothing was read).
        messages: messages the replay read (None when the run failed).
        faults_by_status: final status counts, every status of ``result.STATUSES`` in order.
        top_codes: ``(code, reports)`` of the codes with the most accepted FAILED reports,
            most first (then by code).
        confirmed: ``(code, t_ns)`` of every code that was ever CONFIRMED, with the time it was
            first confirmed, in that order.
        heals: ``(code, ns)`` for each CONFIRMED→HEALED transition: how long the fault had been
            CONFIRMED, in the order the heals happened.
        warnings: how many warnings the replay gave.
        budget: the budget verdict, ``pass`` or ``fail``; None when no budget was checked.
        budget_failures: the names of the budget's rules that did not hold, in budget order.
        error: why the run failed (one line), None when it did not.
    """

    path: str
    kind: str
    start_ns: int | None = None
    end_ns: int | None = None
    messages: int | None = None
    faults_by_status: tuple[tuple[str, int], ...] = ()
    top_codes: tuple[tuple[str, int], ...] = ()
    confirmed: tuple[tuple[str, int], ...] = ()
    heals: tuple[tuple[str, int], ...] = ()
    warnings: int = 0
    budget: str | None = None
    budget_failures: tuple[str, ...] = ()
    error: str | None = None

    @property
    def ok(self) -> bool:
        """The recording was replayed."""
        return self.error is None

    @property
    def span_ns(self) -> int | None:
        """Bag time the recording covers (None when unknown)."""
        if self.start_ns is None or self.end_ns is None:
            return None
        return self.end_ns - self.start_ns


def run_kind(path: Path) -> str:
    """The ``kind`` of a run for a recording path (see :class:`RunSummary`)."""
    kind = input_kind(path)
    return KINDS.get(kind, kind.lstrip(".") or "unknown")


def summarize(path: str, kind: str, result: Result) -> RunSummary:
    """Reduce a replay's result to a run summary."""
    summary = result.summary
    starts = [i.start_ns for i in result.inputs if i.start_ns is not None]
    ends = [i.end_ns for i in result.inputs if i.end_ns is not None]
    if summary.start_ns is not None:
        starts.append(summary.start_ns)
    if summary.end_ns is not None:
        ends.append(summary.end_ns)
    failed_reports: Counter[str] = Counter(
        r.fault_code for r in result.reports if r.accepted and r.event_type == "FAILED"
    )
    ranked = sorted(failed_reports.items(), key=lambda item: (-item[1], item[0]))
    first_confirmed: dict[str, int] = {}
    confirmed_since: dict[str, int] = {}
    heals: list[tuple[str, int]] = []
    for transition in result.transitions:
        code = transition.fault_code
        if transition.to_status == "CONFIRMED" and transition.from_status != "CONFIRMED":
            first_confirmed.setdefault(code, transition.t_ns)
            confirmed_since[code] = transition.t_ns
        elif transition.from_status == "CONFIRMED" and transition.to_status == "HEALED":
            since = confirmed_since.pop(code, None)
            if since is not None:
                heals.append((code, transition.t_ns - since))
    return RunSummary(
        path=path,
        kind=kind,
        start_ns=min(starts, default=None),
        end_ns=max(ends, default=None),
        messages=summary.messages_read,
        faults_by_status=tuple((s, summary.faults_by_status.get(s, 0)) for s in STATUSES),
        top_codes=tuple(ranked[:TOP_CODES]),
        confirmed=tuple(first_confirmed.items()),
        heals=tuple(heals),
        warnings=len(result.warnings),
    )


def run_one(
    path: str | Path,
    configs: Sequence[str | Path] = (),
    budget: Budget | None = None,
    label: str | None = None,
) -> RunSummary:
    """Replay one recording with the configs, as ``analyze`` would, and summarize it.

    Args:
        path: the recording (any input ``analyze`` takes).
        configs: ROS 2 parameter files, later ones overriding earlier ones.
        budget: a fault budget (``medkit_replay.checks.load_budget``) to check the run
            against with ``medkit_replay.checks.evaluate``, as ``check`` does.
        label: how the summary names the recording, also in its error (default: ``path``);
            a cluster is sent absolute paths but reports the paths as they were found.

    Never raises for the recording's sake: an input or config problem, or any other exception
    of the replay, is the summary's ``error`` (one line).
    """
    recording = Path(path)
    kind = run_kind(recording)
    shown = str(path) if label is None else label
    try:
        result = replay([recording], list(configs))
        summary = summarize(shown, kind, result)
        if budget is None:
            return summary
        from medkit_replay.checks import evaluate  # noqa: PLC0415  # only with a budget

        failures = tuple(v.rule.name for v in evaluate(budget, result) if not v.passed)
        return replace(summary, budget="fail" if failures else "pass", budget_failures=failures)
    except MedkitReplayError as err:
        error = err.render()
    except Exception as err:  # one recording must not end the fleet
        error = f"{type(err).__name__}: {err}" if str(err) else type(err).__name__
    error = " ".join(error.split())
    if label is not None:
        error = error.replace(str(path), label)
    return RunSummary(path=shown, kind=kind, error=error)


def check_configs(configs: Sequence[str | Path]) -> None:
    """Load the configs as every run will, so that a bad one stops the fleet before it starts
    (once, with its file and line) instead of failing every run.

    Raises:
        ConfigError: a config file is missing, invalid, or holds a value upstream refuses.
    """
    params = load_parameters(Path(c) for c in configs)
    fault_manager_config(params.node("fault_manager"))
    replay_options(params)


def _failed(path: Path, error: BaseException) -> RunSummary:
    text = " ".join(str(error).split())
    return RunSummary(
        path=str(path),
        kind=run_kind(path),
        error=f"{type(error).__name__}: {text}" if text else type(error).__name__,
    )


def default_jobs() -> int:
    """Worker processes by default: one per CPU this process may run on."""
    affinity = getattr(os, "sched_getaffinity", None)
    if affinity is not None:
        return max(len(affinity(0)), 1)
    return os.cpu_count() or 1


def _context() -> multiprocessing.context.BaseContext:
    """Workers started clean (forkserver where there is one, else spawn): forking a process
    that runs threads (the progress bar's) is unsafe."""
    methods = multiprocessing.get_all_start_methods()
    return multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")


def run_all(
    paths: Sequence[Path],
    configs: Sequence[Path] = (),
    *,
    budget: Budget | None = None,
    jobs: int | None = None,
    on_done: Callable[[int, RunSummary], None] | None = None,
) -> list[RunSummary]:
    """Run every recording, ``jobs`` at a time in worker processes (1: in this process).

    Args:
        paths: the recordings.
        configs: the ROS 2 parameter files, the same for every run.
        budget: a fault budget checked on every run, if any.
        jobs: worker processes (default: one per CPU; never more than recordings).
        on_done: called in this process as each run ends, with its index and summary.

    Returns:
        One summary per path, in the order of ``paths``.
    """
    workers = min(jobs or default_jobs(), len(paths))
    results: list[RunSummary | None] = [None] * len(paths)

    def done(index: int, summary: RunSummary) -> None:
        results[index] = summary
        if on_done is not None:
            on_done(index, summary)

    if workers <= 1:
        for index, path in enumerate(paths):
            done(index, run_one(path, configs, budget))
        return [r for r in results if r is not None]
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=_context())
    try:
        futures: dict[Future[RunSummary], int] = {
            pool.submit(run_one, path, tuple(configs), budget): index
            for index, path in enumerate(paths)
        }
        for future in as_completed(futures):
            index = futures[future]
            try:
                summary = future.result()
            except Exception as err:  # a worker that died (BrokenProcessPool), unpicklable data
                summary = _failed(paths[index], err)
            done(index, summary)
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    return [r for r in results if r is not None]


def run_on_dask(
    address: str,
    paths: Sequence[Path],
    configs: Sequence[Path] = (),
    *,
    budget: Budget | None = None,
    on_done: Callable[[int, RunSummary], None] | None = None,
) -> list[RunSummary]:
    """Run every recording on a Dask distributed cluster, with the same ``run_one``.

    The workers need medkit-replay installed and the recordings and configs at the same
    absolute paths (a shared file system); they are sent absolute paths, and the summaries
    come back named as found (``run_one``'s ``label``), so the report is the same as
    ``run_all``'s.

    Raises:
        MedkitReplayError: the ``distributed`` package is missing, or the scheduler cannot be
            reached.
    """
    client_type = dask_client_type()
    try:
        client = client_type(address, timeout=DASK_CONNECT_TIMEOUT, set_as_default=False)
    except (OSError, TimeoutError, ValueError, TypeError) as err:
        problem = " ".join(str(err).split()) or type(err).__name__
        raise MedkitReplayError(
            f"cannot reach the Dask scheduler ({problem})", path=address
        ) from None
    from distributed import as_completed as dask_as_completed  # noqa: PLC0415  # optional

    results: list[RunSummary | None] = [None] * len(paths)
    try:
        absolute_configs = tuple(str(Path(c).absolute()) for c in configs)
        futures = client.map(
            run_one,
            [str(p.absolute()) for p in paths],
            [absolute_configs] * len(paths),
            [budget] * len(paths),
            [str(p) for p in paths],
            pure=False,
        )
        index_of = {future.key: index for index, future in enumerate(futures)}
        for future in dask_as_completed(futures, loop=client.loop):  # type: ignore[no-untyped-call]
            index = index_of[future.key]
            try:
                summary = future.result()
            except Exception as err:  # a lost worker (KilledWorker), a cancelled task
                summary = _failed(paths[index], err)
            results[index] = summary
            if on_done is not None:
                on_done(index, summary)
    finally:
        client.close()  # type: ignore[no-untyped-call]
    return [r for r in results if r is not None]


def dask_client_type() -> type[Client]:
    """``distributed.Client``, imported on demand.

    Raises:
        MedkitReplayError: ``distributed`` is not installed (names the extra to install).
    """
    try:
        from distributed import Client  # noqa: PLC0415  # optional and heavy
    except ImportError:
        raise MedkitReplayError(
            f"--dask needs the Dask distributed package: {DASK_EXTRA_HINT}"
        ) from None
    return Client
