"""A fleet on a Dask distributed cluster: ``run_one`` for every recording as a Dask task.

``run_jobs_on_dask`` runs any picklable task so (a sweep's runs too). With a per-run timeout
each task runs in a child process of its own (``run_isolated``), killed when the time is up.
"""

from __future__ import annotations

import pickle
import subprocess
import sys
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar, cast

from medkit_replay.errors import MedkitReplayError
from medkit_replay.fleet.run import RunSummary, describe_error, run_kind, run_one
from medkit_replay.fleet.workers import death_text, seconds_text
from medkit_replay.text import one_line

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from distributed import Client

    from medkit_replay.checks import Budget

DASK_CONNECT_TIMEOUT = "20s"
"""How long ``--dask`` waits for the scheduler before giving up."""
DASK_EXTRA_HINT = "pip install 'medkit-replay[dask]'"
READY_BYTE = b"R"
"""What the child of ``run_isolated`` writes once it has started."""


_CHILD = "from medkit_replay.fleet.cluster import serve_one; serve_one()"
J = TypeVar("J")
R = TypeVar("R")


def serve_one() -> None:
    """The child of :func:`run_isolated`: says it has started, then runs the pickled task on
    the pickled job on standard input and writes its result, pickled, on standard output."""
    sys.stdout.buffer.write(READY_BYTE)
    sys.stdout.buffer.flush()
    task, job = pickle.load(sys.stdin.buffer)  # from our own parent
    result = task(job)
    sys.stdout.buffer.write(pickle.dumps(result, protocol=pickle.HIGHEST_PROTOCOL))
    sys.stdout.buffer.flush()


def run_isolated(
    job: J,
    task: Callable[[J], R],
    failed: Callable[[J, str], R],
    timeout: float | None = None,
) -> R:
    """``task(job)`` in a child process of its own, killed after ``timeout`` seconds (counted
    once it has started): what a Dask task runs when the runs have a timeout (a thread cannot
    be stopped, and a daemonic Dask worker may not use multiprocessing). A child that dies or
    runs out of time is this run's failure, ``failed(job, why)``."""
    payload = pickle.dumps((task, job))
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
            output, _ = child.communicate(payload, timeout=timeout)
        child.wait()
    except subprocess.TimeoutExpired:
        problem = f"timed out after {seconds_text(timeout or 0)} s"
    else:
        if child.returncode == 0:
            try:
                return cast("R", pickle.loads(output))  # from our own child
            except Exception:  # a truncated pickle: the child did not finish
                pass
        problem = f"worker died: {death_text(child.returncode)}"
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
        for stream in (child.stdin, child.stdout):
            if stream is not None:
                stream.close()
    return failed(job, problem)


def _run_labelled(
    job: tuple[str, str], configs: tuple[str, ...], budget: Budget | None
) -> RunSummary:
    """``run_one`` on an absolute path, its summary naming the path as it was found."""
    path, label = job
    return run_one(path, configs, budget, label)


def _failed_labelled(job: tuple[str, str], problem: str) -> RunSummary:
    path, label = job
    return RunSummary(path=label, kind=run_kind(path), error=f"{label}: {problem}")


def run_on_dask(
    address: str,
    paths: Sequence[Path | str],
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
    results: list[RunSummary | None] = [None] * len(paths)

    def done(index: int, summary: RunSummary) -> None:
        results[index] = summary
        if on_done is not None:
            on_done(index, summary)

    absolute_configs = tuple(str(Path(c).absolute()) for c in configs)
    jobs = [(p if isinstance(p, str) else str(p.absolute()), str(p)) for p in paths]
    task = partial(_run_labelled, configs=absolute_configs, budget=budget)
    run_jobs_on_dask(address, jobs, task, _failed_labelled, timeout=timeout, on_done=done)
    return [r for r in results if r is not None]


def run_jobs_on_dask(
    address: str,
    jobs: Sequence[J],
    task: Callable[[J], R],
    failed: Callable[[J, str], R],
    *,
    timeout: float | None = None,
    on_done: Callable[[int, R], None],
) -> None:
    """Run ``task`` on every job as a Dask task; ``on_done(index, result)`` as each ends.

    ``task`` and ``failed`` must pickle (module-level functions or partials of them);
    ``failed(job, why)`` stands for a run whose task was lost (a ``KilledWorker``) or, with
    ``timeout``, whose child process died or ran out of time.

    Raises:
        MedkitReplayError: the ``distributed`` package is missing, or the scheduler cannot be
            reached.
    """
    client_type = dask_client_type()
    try:
        client = client_type(address, timeout=DASK_CONNECT_TIMEOUT, set_as_default=False)
    except (OSError, TimeoutError, ValueError, TypeError) as err:
        problem = one_line(err, or_name=True)
        raise MedkitReplayError(
            f"cannot reach the Dask scheduler ({problem})", path=address
        ) from None
    from distributed import as_completed as dask_as_completed  # noqa: PLC0415  # optional

    try:
        if timeout is None:
            futures = client.map(task, list(jobs), pure=False)
        else:
            isolated = partial(run_isolated, task=task, failed=failed, timeout=timeout)
            futures = client.map(isolated, list(jobs), pure=False)
        index_of = {future.key: index for index, future in enumerate(futures)}
        for future in dask_as_completed(futures, loop=client.loop):  # type: ignore[no-untyped-call]
            index = index_of[future.key]
            try:
                result = future.result()
            except Exception as err:  # a lost worker (KilledWorker), a cancelled task
                result = failed(jobs[index], describe_error(err))
            on_done(index, result)
    finally:
        client.close()  # type: ignore[no-untyped-call]


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
