"""Outputs written by a forked child while this process writes the JSON report: another core,
the same files. Its errors come back as raised; what it left undone when killed is done here.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import signal
import sys
from typing import TYPE_CHECKING

from medkit_replay.errors import MedkitReplayError
from medkit_replay.outputs.atomic import remove_partials
from medkit_replay.outputs.console import warn

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence
    from pathlib import Path
    from typing import Self

_SIGNALS = {signal.SIGINT, signal.SIGTERM, signal.SIGHUP}
_ANSWER_LIMIT = 1 << 20
"""Bytes of the child's answer read at most (an error message)."""
_DONE = b"+"  # the child's answer: one per job done, then _FAILED and the pickled error, if any
_FAILED = b"!"
_TEXT_LIMIT = 2000
"""Characters of an unexpected failure's text the child sends back."""

Job = tuple[str, "Callable[[], None]"]
"""An output's name (for messages) and the work that writes it."""


class Forked:
    """``jobs`` run in order in a forked child (inline where the system cannot fork).

    :meth:`wait` raises the MedkitReplayError a job raised, as such. A child killed (by any
    signal) or failing otherwise costs only its own outputs: the temporary files it left
    beside ``targets`` are removed, the jobs it did not finish are run here, and one warning
    line says so. The child leaves with ``os._exit``: it runs none of this process's exit
    functions (they would remove temporary folders this process still uses) and frees
    nothing on the way.
    """

    def __init__(self, jobs: Sequence[Job], targets: Sequence[Path] = ()) -> None:
        self._pid: int | None = None
        self._answer: int | None = None
        self._jobs, self._targets = list(jobs), list(targets)
        if not hasattr(os, "fork") or not hasattr(signal, "pthread_sigmask"):
            _run(self._jobs)  # no fork here: the work is done before this returns, as before
            return
        read, write = os.pipe()
        sys.stdout.flush()
        sys.stderr.flush()
        # Signals wait until each side is in place: one raised in the child before its work is
        # under way would unwind into this process's own code, run by the child.
        held = signal.pthread_sigmask(signal.SIG_BLOCK, _SIGNALS)
        try:
            pid = os.fork()
        except OSError:  # no process to be had (EAGAIN, ENOMEM): the work is done here
            signal.pthread_sigmask(signal.SIG_SETMASK, held)
            os.close(read)
            os.close(write)
            _run(self._jobs)
            return
        if pid == 0:  # the child
            status = 1
            try:
                os.close(read)
                signal.pthread_sigmask(signal.SIG_SETMASK, held)
                status = _child(self._jobs, write)
            finally:
                os._exit(status)
        signal.pthread_sigmask(signal.SIG_SETMASK, held)
        os.close(write)
        self._pid, self._answer = pid, read

    def wait(self) -> None:
        """Wait for the child; raise the MedkitReplayError it raised, or do what it left."""
        if self._pid is None or self._answer is None:
            return
        pid, answer = self._pid, self._answer
        self._pid = self._answer = None
        with os.fdopen(answer, "rb") as stream:
            data = stream.read(_ANSWER_LIMIT)
        _, status = os.waitpid(pid, 0)
        failure = data.lstrip(_DONE)
        done = len(data) - len(failure)
        if failure.startswith(_FAILED):
            try:
                raised = pickle.loads(failure[1:])  # our own child's
            except Exception:  # cut at the limit
                raised = "an error too long to read"
            # A MedkitReplayError comes back as its class with its rendered text: same line.
            if isinstance(raised, MedkitReplayError):
                raise raised
            why = f"failed ({raised})"
        elif status != 0 or done < len(self._jobs):
            why = _ending(status)
        else:
            return
        left = self._jobs[done:]
        remove_partials(self._targets, pid)
        if left:
            names = ", ".join(name for name, _ in left)
            warn(f"the process writing {names} {why}; {names} written by the main one instead")
            _run(left)

    def stop(self) -> None:
        """End the child (its atomic writes remove their temporary files) and wait for it."""
        if self._pid is None:
            return
        with contextlib.suppress(OSError):
            os.kill(self._pid, signal.SIGTERM)
        with contextlib.suppress(OSError):
            os.waitpid(self._pid, 0)
        remove_partials(self._targets, self._pid)
        if self._answer is not None:
            os.close(self._answer)
        self._pid = self._answer = None

    def __enter__(self) -> Self:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, *_: object) -> None:
        if exc_type is None:
            self.wait()
        else:
            self.stop()


def _run(jobs: Sequence[Job]) -> None:
    for _, job in jobs:
        job()


def _ending(status: int) -> str:
    """How a child with wait status ``status`` ended, in words."""
    if os.WIFSIGNALED(status):
        number = os.WTERMSIG(status)
        try:
            return f"was killed by {signal.Signals(number).name}"
        except ValueError:
            return f"was killed by signal {number}"
    return f"ended with status {os.waitstatus_to_exitcode(status)}"


def _child(jobs: Sequence[Job], answer: int) -> int:
    """Run the jobs, answering _DONE after each; an error goes back through ``answer``.
    Returns the exit status."""
    status = 0
    reply = b""
    try:
        for _, job in jobs:
            job()
            os.write(answer, _DONE)
    except MedkitReplayError as err:
        reply = _FAILED + _pickled(err)
        status = 1
    except BaseException as err:  # every failure goes back to the parent
        reply = _FAILED + pickle.dumps(f"{type(err).__name__}: {err}"[:_TEXT_LIMIT])
        status = 1
    with contextlib.suppress(OSError):
        sys.stdout.flush()
        sys.stderr.flush()
        os.write(answer, reply)
        os.close(answer)
    return status


def _pickled(err: MedkitReplayError) -> bytes:
    try:
        return pickle.dumps(err)
    except Exception:  # an error that does not pickle still says its line
        return pickle.dumps(err.render())
