"""One run of a fleet: a recording replayed as ``analyze`` replays it, reduced to a small summary.

``run_one`` is the per-run function, the same in every executor: in this process, in worker
processes (``run_all``) or on a Dask distributed cluster (``run_on_dask``). It never raises for
a recording that cannot be replayed: the summary's ``error`` says why. Summaries come back in
input order whatever order the runs finish in.

A worker process that dies (the OOM killer, a resource limit) or a run past its ``timeout``
costs only that run: the dead run is tried once more in a fresh worker, a run that timed out
is killed with its worker, and the others go on.
"""

from __future__ import annotations

import multiprocessing
import os
import pickle
import signal
import subprocess
import sys
import time
from collections import Counter, deque
from contextlib import suppress
from dataclasses import dataclass, replace
from multiprocessing.connection import wait
from pathlib import Path
from typing import TYPE_CHECKING, Any

from medkit_replay.config.fault_manager import fault_manager_config
from medkit_replay.config.params import load_parameters
from medkit_replay.config.replay_options import replay_options
from medkit_replay.errors import MedkitReplayError
from medkit_replay.files import FileRefusedError, check_regular
from medkit_replay.inputs.recording import input_kind
from medkit_replay.pipeline import replay
from medkit_replay.result import STATUSES

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence
    from multiprocessing.connection import Connection
    from multiprocessing.process import BaseProcess

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
ATTEMPTS = 2
"""How often a run whose worker died is tried before it is reported as failed."""
READY = "ready"
"""What a worker process sends once it has started."""
MAX_ERROR_CHARS = 4000
"""A run's error is cut here (an ellipsis ends it): a message quoting a 10 MB field stays short."""
READY_BYTE = b"R"
"""What the child of ``run_isolated`` writes once it has started."""


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
    shown = str(path) if label is None else label
    kind = "unknown"
    try:
        recording = Path(path)
        kind = run_kind(recording)
        if recording.exists() and not recording.is_dir():
            check_regular(recording)  # a FIFO named like a recording would block its reader
        result = replay([recording], list(configs))
        summary = summarize(shown, kind, result)
        if budget is not None:
            from medkit_replay.checks import evaluate  # noqa: PLC0415  # only with a budget

            failures = tuple(v.rule.name for v in evaluate(budget, result) if not v.passed)
            verdict = "fail" if failures else "pass"
            summary = replace(summary, budget=verdict, budget_failures=failures)
        problem = summary_problem(summary)
    except MedkitReplayError as err:
        error = err.render()
    except FileRefusedError as err:
        error = f"{path}: {err}"
    except Exception as err:  # one recording must not end the fleet
        error = f"{path}: {_describe(err)}"
    else:
        if problem is None:
            return summary
        error = f"{path}: {problem}"
    error = " ".join(error.split())
    if label is not None:
        error = error.replace(str(path), label)
    if len(error) > MAX_ERROR_CHARS:
        error = error[: MAX_ERROR_CHARS - 1] + "…"
    return RunSummary(path=shown, kind=kind, error=error)


def _describe(error: BaseException) -> str:
    """An exception on one line: its type, and its text when it has one."""
    try:
        text = " ".join(str(error).split())
    except Exception:  # a text that cannot be made (a number too long to print)
        text = ""
    return f"{type(error).__name__}: {text}" if text else type(error).__name__


def _shown(value: object) -> str:
    if isinstance(value, int):
        return str(value) if value.bit_length() <= 128 else f"a {value.bit_length()}-bit number"
    return repr(value)[:40]


def _int64(value: object) -> bool:
    # Never ``value in range(...)``: for anything but an int that walks the whole range.
    return type(value) is int and -(2**63) <= value < 2**63


def summary_problem(summary: RunSummary) -> str | None:
    """Why the fleet table cannot hold a summary (a time at or past 2^63 ns, a time that is not
    an integer), or None; such a run is reported as failed rather than costing the report."""
    times = [summary.start_ns, summary.end_ns, *(t for _, t in summary.confirmed)]
    for t_ns in times:
        if t_ns is not None and not _int64(t_ns):
            return f"bag time {_shown(t_ns)} is out of range (an integer ns below 2^63 expected)"
    for _, ns in summary.heals:
        if not _int64(ns):
            return f"a heal after {_shown(ns)} ns is out of range"
    span = summary.span_ns if all(_int64(t) for t in times if t is not None) else None
    if span is not None and not _int64(span):
        return f"a recording spanning {span} ns is out of range"
    for name, count in (("messages", summary.messages), ("warnings", summary.warnings)):
        if count is not None and not _int64(count):
            return f"{name} count {_shown(count)} is out of range"
    return None


def check_configs(configs: Sequence[str | Path]) -> None:
    """Load the configs as every run will, so that a bad one stops the fleet before it starts
    (once, with its file and line) instead of failing every run.

    Raises:
        ConfigError: a config file is missing, invalid, or holds a value upstream refuses.
    """
    params = load_parameters(Path(c) for c in configs)
    fault_manager_config(params.node("fault_manager"))
    replay_options(params)


def _failed(path: Path, error: BaseException | str) -> RunSummary:
    """A run that failed outside ``run_one`` (its worker died or ran out of time)."""
    problem = error if isinstance(error, str) else _describe(error)
    return RunSummary(path=str(path), kind=run_kind(path), error=f"{path}: {problem}")


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


def _serve(connection: Connection, configs: tuple[Path, ...], budget: Budget | None) -> None:
    """A worker process: say it is ready, then replay each ``(index, path)`` it is sent and
    send back its summary."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    connection.send(READY)
    while True:
        try:
            job = connection.recv()
        except (EOFError, OSError):
            return
        if job is None:
            return
        index, path = job
        connection.send((index, run_one(path, configs, budget)))


def death_text(exitcode: int | None) -> str:
    """How a worker process ended, for a run's error: ``killed by SIGKILL``, ``exited with
    status 3``."""
    if exitcode is not None and exitcode < 0:
        try:
            name = signal.Signals(-exitcode).name
        except ValueError:
            name = f"signal {-exitcode}"
        return f"killed by {name}"
    if exitcode:
        return f"exited with status {exitcode}"
    return "exited unexpectedly"


def seconds_text(seconds: float) -> str:
    """A timeout as the user gave it: ``0.2``, ``60``."""
    return f"{seconds:g}"


class _Worker:
    """One worker process, the pipe to it, and the run it is busy with."""

    def __init__(
        self,
        context: multiprocessing.context.BaseContext,
        configs: tuple[Path, ...],
        budget: Budget | None,
    ) -> None:
        parent, child = context.Pipe()
        self.connection: Connection = parent
        self.process: BaseProcess = context.Process(  # type: ignore[attr-defined]
            target=_serve, args=(child, configs, budget), daemon=True
        )
        self.process.start()
        child.close()
        self.ready = False
        """It has started (imports done) and waits for a job: a run's time starts when given."""
        self.index: int | None = None
        self.deadline: float | None = None

    def give(self, index: int, path: Path, timeout: float | None) -> None:
        self.index = index
        self.deadline = None if timeout is None else time.monotonic() + timeout
        self.connection.send((index, path))

    def receive(self) -> object:
        """What the worker sent; None when it died before sending it whole."""
        try:
            return self.connection.recv()
        except Exception:  # EOFError, a truncated pickle: it died while sending
            return None

    def stop(self, *, kill: bool = False) -> None:
        """End the process (at once with ``kill``, else when it has read its last job)."""
        if not kill:
            try:
                self.connection.send(None)
            except OSError:
                kill = True
        if kill and self.process.is_alive():
            self.process.kill()
        self.process.join(timeout=None if kill else 5)
        if self.process.is_alive():
            self.process.kill()
            self.process.join()
        self.connection.close()


def run_all(
    paths: Sequence[Path],
    configs: Sequence[Path] = (),
    *,
    budget: Budget | None = None,
    jobs: int | None = None,
    timeout: float | None = None,
    on_done: Callable[[int, RunSummary], None] | None = None,
) -> list[RunSummary]:
    """Run every recording, ``jobs`` at a time in worker processes (1 and no ``timeout``: in
    this process).

    Args:
        paths: the recordings.
        configs: the ROS 2 parameter files, the same for every run.
        budget: a fault budget checked on every run, if any.
        jobs: worker processes (default: one per CPU; never more than recordings).
        timeout: seconds a run may take; a run past it is killed and reported as failed.
        on_done: called in this process as each run ends, with its index and summary.

    Returns:
        One summary per path, in the order of ``paths``. A run whose worker died twice (see
        ``ATTEMPTS``) or that timed out is a failed summary naming why.
    """
    workers = min(jobs or default_jobs(), len(paths))
    results: list[RunSummary | None] = [None] * len(paths)

    def done(index: int, summary: RunSummary) -> None:
        results[index] = summary
        if on_done is not None:
            on_done(index, summary)

    if workers <= 1 and timeout is None:
        for index, path in enumerate(paths):
            done(index, run_one(path, configs, budget))
        return [r for r in results if r is not None]
    _run_in_workers(paths, tuple(configs), budget, max(workers, 1), timeout, done)
    return [r for r in results if r is not None]


def _run_in_workers(
    paths: Sequence[Path],
    configs: tuple[Path, ...],
    budget: Budget | None,
    count: int,
    timeout: float | None,
    done: Callable[[int, RunSummary], None],
) -> None:
    """Hand runs to ``count`` worker processes one at a time; replace a worker that dies
    (its run tried again, up to ATTEMPTS) or runs out of time (its run failed)."""
    context = _context()
    pending = deque(range(len(paths)))
    attempts = [0] * len(paths)
    remaining = len(paths)
    pool: list[_Worker] = []
    stillborn = 0

    def finish(index: int, summary: RunSummary) -> None:
        nonlocal remaining
        remaining -= 1
        done(index, summary)

    try:
        while remaining:
            while pending and len(pool) < count:
                pool.append(_Worker(context, configs, budget))
            for worker in pool:
                if worker.ready and worker.index is None and pending:
                    job = pending.popleft()
                    attempts[job] += 1
                    with suppress(OSError):  # it died idle: its sentinel says so below
                        worker.give(job, paths[job], timeout)
            watched = [w for w in pool if w.index is not None or not w.ready]
            if not watched:
                break  # cannot happen: every run is pending, busy or done
            waiting: list[Any] = [w.connection for w in watched]
            waiting += [w.process.sentinel for w in watched]
            deadlines = [w.deadline for w in watched if w.deadline is not None]
            wait_for = max(min(deadlines) - time.monotonic(), 0) if deadlines else None
            ready = set(wait(waiting, wait_for))
            now = time.monotonic()
            for worker in watched:
                index = worker.index
                if worker.connection in ready:
                    message = worker.receive()
                    if message == READY and not worker.ready:
                        worker.ready = True
                        stillborn = 0
                        continue
                    if isinstance(message, tuple) and index is not None:
                        worker.index = worker.deadline = None
                        finish(index, message[1])
                        continue
                elif worker.process.sentinel not in ready:
                    if worker.deadline is None or now < worker.deadline or index is None:
                        continue
                    worker.stop(kill=True)
                    pool.remove(worker)
                    finish(
                        index,
                        _failed(paths[index], f"timed out after {seconds_text(timeout or 0)} s"),
                    )
                    continue
                worker.process.join()
                how = death_text(worker.process.exitcode)
                worker.stop(kill=True)
                pool.remove(worker)
                if index is None:
                    stillborn += 1
                    if stillborn >= ATTEMPTS + 1:  # workers cannot even start: say so per run
                        while pending:
                            job = pending.popleft()
                            finish(job, _failed(paths[job], f"worker died at start: {how}"))
                    continue
                if attempts[index] < ATTEMPTS:
                    pending.appendleft(index)
                    continue
                tries = " (also when run again in a new worker)" if ATTEMPTS > 1 else ""
                finish(index, _failed(paths[index], f"worker died: {how}{tries}"))
    finally:
        for worker in pool:
            worker.stop(kill=worker.index is not None or not worker.ready)


_CHILD = "from medkit_replay.fleet.run import serve_one; serve_one()"


def serve_one() -> None:
    """The child of :func:`run_isolated`: says it has started, then replays the pickled job on
    standard input and writes its summary, pickled, on standard output."""
    sys.stdout.buffer.write(READY_BYTE)
    sys.stdout.buffer.flush()
    path, configs, budget, label = pickle.load(sys.stdin.buffer)  # from our own parent
    summary = run_one(path, configs, budget, label)
    sys.stdout.buffer.write(pickle.dumps(summary, protocol=pickle.HIGHEST_PROTOCOL))
    sys.stdout.buffer.flush()


def run_isolated(
    path: str | Path,
    configs: Sequence[str | Path] = (),
    budget: Budget | None = None,
    label: str | None = None,
    timeout: float | None = None,
) -> RunSummary:
    """``run_one`` in a child process of its own, killed after ``timeout`` seconds (counted once
    it has started): what a Dask task runs when the fleet has a per-run timeout (a thread
    cannot be stopped, and a daemonic Dask worker may not use multiprocessing). A child that
    dies or runs out of time is this run's failure."""
    shown = str(path) if label is None else label
    job = pickle.dumps((str(path), tuple(str(c) for c in configs), budget, label))
    child = subprocess.Popen(  # our own interpreter and module
        [sys.executable, "-c", _CHILD],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
    )
    try:
        assert child.stdout is not None
        output = b""
        if child.stdout.read(len(READY_BYTE)) == READY_BYTE:
            output, _ = child.communicate(job, timeout=timeout)
        child.wait()
    except subprocess.TimeoutExpired:
        problem = f"timed out after {seconds_text(timeout or 0)} s"
    else:
        if child.returncode == 0:
            try:
                summary = pickle.loads(output)  # from our own child
            except Exception:  # a truncated pickle: the child did not finish
                summary = None
            if isinstance(summary, RunSummary):
                return summary
        problem = f"worker died: {death_text(child.returncode)}"
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
        for stream in (child.stdin, child.stdout):
            if stream is not None:
                stream.close()
    return RunSummary(path=shown, kind=run_kind(Path(path)), error=f"{shown}: {problem}")


def run_on_dask(
    address: str,
    paths: Sequence[Path],
    configs: Sequence[Path] = (),
    *,
    budget: Budget | None = None,
    timeout: float | None = None,
    on_done: Callable[[int, RunSummary], None] | None = None,
) -> list[RunSummary]:
    """Run every recording on a Dask distributed cluster, with the same ``run_one``.

    The workers need medkit-replay installed and the recordings and configs at the same
    absolute paths (a shared file system); they are sent absolute paths, and the summaries
    come back named as found (``run_one``'s ``label``), so the report is the same as
    ``run_all``'s. With a ``timeout``, each task runs its recording in a child process
    (:func:`run_isolated`) that is killed when the time is up.

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
        arguments: list[list[object]] = [
            [str(p.absolute()) for p in paths],
            [absolute_configs] * len(paths),
            [budget] * len(paths),
            [str(p) for p in paths],
        ]
        if timeout is None:
            futures = client.map(run_one, *arguments, pure=False)
        else:
            arguments.append([timeout] * len(paths))
            futures = client.map(run_isolated, *arguments, pure=False)
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
