"""Outputs written by a forked child while this process writes the JSON report: another core,
the same files. The child's failure comes back as the error it would have raised here.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import signal
import sys
from typing import TYPE_CHECKING

from medkit_replay.errors import MedkitReplayError

if TYPE_CHECKING:
    from collections.abc import Callable
    from types import TracebackType
    from typing import Self

_SIGNALS = {signal.SIGINT, signal.SIGTERM, signal.SIGHUP}
_ANSWER_LIMIT = 1 << 20
"""Bytes of the child's answer read at most (an error message)."""


class ForkedError(Exception):
    """The forked writer failed with something other than a MedkitReplayError (a bug)."""


class Forked:
    """``work`` run in a forked child (inline where the system cannot fork); :meth:`wait`
    raises what it raised: a MedkitReplayError as such, anything else as ForkedError.

    The child leaves with ``os._exit``: it runs none of this process's exit functions (they
    would remove temporary folders this process still uses) and frees nothing on the way.
    """

    def __init__(self, work: Callable[[], None]) -> None:
        self._pid: int | None = None
        self._answer: int | None = None
        if not hasattr(os, "fork") or not hasattr(signal, "pthread_sigmask"):
            work()  # no fork here: the work is done before this returns, as before
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
            work()
            return
        if pid == 0:  # the child
            status = 1
            try:
                os.close(read)
                signal.pthread_sigmask(signal.SIG_SETMASK, held)
                status = _child(work, write)
            finally:
                os._exit(status)
        signal.pthread_sigmask(signal.SIG_SETMASK, held)
        os.close(write)
        self._pid, self._answer = pid, read

    def wait(self) -> None:
        """Wait for the child; raise what its work raised."""
        if self._pid is None or self._answer is None:
            return
        pid, answer = self._pid, self._answer
        self._pid = self._answer = None
        with os.fdopen(answer, "rb") as stream:
            data = stream.read(_ANSWER_LIMIT)
        _, status = os.waitpid(pid, 0)
        if data:
            failure = pickle.loads(data)  # our own child's
            # A MedkitReplayError comes back as its class with its rendered text: same line.
            raise failure if isinstance(failure, MedkitReplayError) else ForkedError(failure)
        if status != 0:
            raise ForkedError(f"the output writer ended with status {status}")

    def stop(self) -> None:
        """End the child (its atomic writes remove their temporary files) and wait for it."""
        if self._pid is None:
            return
        with contextlib.suppress(OSError):
            os.kill(self._pid, signal.SIGTERM)
        with contextlib.suppress(OSError):
            os.waitpid(self._pid, 0)
        if self._answer is not None:
            os.close(self._answer)
        self._pid = self._answer = None

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        if exc_type is None:
            self.wait()
        else:
            self.stop()


def _child(work: Callable[[], None], answer: int) -> int:
    """Run the work; an error goes back through ``answer``. Returns the exit status."""
    status = 0
    reply = b""
    try:
        work()
    except MedkitReplayError as err:
        reply = _pickled(err)
        status = 1
    except BaseException as err:  # every failure goes back to the parent
        reply = pickle.dumps(f"{type(err).__name__}: {err}")
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
