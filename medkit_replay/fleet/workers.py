"""A fleet's local executor: ``run_one`` for every recording, in this process or in workers.

``run_jobs`` is the pool itself, for any picklable task (a sweep's runs use it too); ``run_all``
is the fleet's use of it. Summaries come back in input order whatever order the runs finish in. A
worker process that
dies (the OOM killer, a resource limit) or a run past its ``timeout`` costs
only that run: the dead run is tried once more in a fresh worker, a run that timed out is killed
with its worker, and the others go on.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import time
from collections import deque
from contextlib import suppress
from functools import partial
from multiprocessing.connection import wait
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from medkit_replay.fleet.run import failed_run, run_one

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence
    from multiprocessing.connection import Connection
    from multiprocessing.process import BaseProcess
    from pathlib import Path

    from medkit_replay.checks import Budget
    from medkit_replay.fleet.run import RunSummary

J = TypeVar("J")
R = TypeVar("R")

ATTEMPTS = 2
"""How often a run whose worker died is tried before it is reported as failed."""
READY = "ready"
"""What a worker process sends once it has started."""


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


def _serve(connection: Connection, task: Callable[[Any], object]) -> None:
    """A worker process: say it is ready, then run the task on each ``(index, job)`` it is sent
    and send back its result."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    connection.send(READY)
    while True:
        try:
            job = connection.recv()
        except (EOFError, OSError):
            return
        if job is None:
            return
        index, item = job
        connection.send((index, task(item)))


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
        self, context: multiprocessing.context.BaseContext, task: Callable[[Any], object]
    ) -> None:
        parent, child = context.Pipe()
        self.connection: Connection = parent
        self.process: BaseProcess = context.Process(  # type: ignore[attr-defined]
            target=_serve, args=(child, task), daemon=True
        )
        self.process.start()
        child.close()
        self.ready = False
        """It has started (imports done) and waits for a job: a run's time starts when given."""
        self.index: int | None = None
        self.deadline: float | None = None

    def give(self, index: int, job: object, timeout: float | None) -> None:
        self.index = index
        self.deadline = None if timeout is None else time.monotonic() + timeout
        self.connection.send((index, job))

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
    paths: Sequence[Path | str],
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
    results: list[RunSummary | None] = [None] * len(paths)

    def done(index: int, summary: RunSummary) -> None:
        results[index] = summary
        if on_done is not None:
            on_done(index, summary)

    task = partial(run_one, configs=tuple(configs), budget=budget)
    run_jobs(paths, task, failed_run, jobs=jobs, timeout=timeout, on_done=done)
    return [r for r in results if r is not None]


def run_jobs(
    items: Sequence[J],
    task: Callable[[J], R],
    failed: Callable[[J, str], R],
    *,
    jobs: int | None = None,
    timeout: float | None = None,
    on_done: Callable[[int, R], None],
) -> None:
    """Run ``task`` on every item, ``jobs`` at a time in worker processes (1 and no
    ``timeout``: in this process); ``on_done(index, result)`` is called in this process as
    each ends, in the order they end.

    Args:
        items: what each run is given (picklable).
        task: a picklable callable (a module-level function or a ``partial`` of one) that never
            raises for its item's sake.
        failed: the result of a run whose worker died twice or that ran out of time, from
            its item and why (``worker died: killed by SIGKILL``).
        jobs: worker processes (default: one per CPU; never more than items).
        timeout: seconds a run may take; a run past it is killed and reported as failed.
        on_done: receives each result.
    """
    workers = min(jobs or default_jobs(), len(items))
    if workers <= 1 and timeout is None:
        for index, item in enumerate(items):
            on_done(index, task(item))
        return
    _Pool(items, task, failed, on_done).run(max(workers, 1), timeout)


class _Pool(Generic[J, R]):
    """Runs handed to worker processes one at a time; a worker that dies is replaced (its run
    tried again, up to ATTEMPTS), one that runs out of time is killed (its run failed)."""

    def __init__(
        self,
        items: Sequence[J],
        task: Callable[[J], R],
        failed: Callable[[J, str], R],
        done: Callable[[int, R], None],
    ) -> None:
        self.items, self.task, self.failed, self.done = items, task, failed, done

    def run(self, count: int, timeout: float | None) -> None:
        items, failed, done = self.items, self.failed, self.done
        context = _context()
        pending = deque(range(len(items)))
        attempts = [0] * len(items)
        remaining = len(items)
        pool: list[_Worker] = []
        stillborn = 0

        def finish(index: int, result: R) -> None:
            nonlocal remaining
            remaining -= 1
            done(index, result)

        try:
            while remaining:
                while pending and len(pool) < count:
                    pool.append(_Worker(context, self.task))
                for worker in pool:
                    if worker.ready and worker.index is None and pending:
                        job = pending.popleft()
                        attempts[job] += 1
                        with suppress(OSError):  # it died idle: its sentinel says so below
                            worker.give(job, items[job], timeout)
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
                        late = f"timed out after {seconds_text(timeout or 0)} s"
                        finish(index, failed(items[index], late))
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
                                finish(job, failed(items[job], f"worker died at start: {how}"))
                        continue
                    if attempts[index] < ATTEMPTS:
                        pending.appendleft(index)
                        continue
                    tries = " (also when run again in a new worker)" if ATTEMPTS > 1 else ""
                    finish(index, failed(items[index], f"worker died: {how}{tries}"))
        finally:
            for worker in pool:
                worker.stop(kill=worker.index is not None or not worker.ready)
