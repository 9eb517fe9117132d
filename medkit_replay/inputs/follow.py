"""How a recording still being written is waited for: the poll interval, the idle timeout, the stop.

The only wall clock of the inputs (monotonic, for waiting); what is read keeps bag time only.
"""

from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, NamedTuple

from medkit_replay.inputs.watch import Watched
from medkit_replay.model import POLL_DEFAULT_S, POLL_MAX_S, POLL_MIN_S

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator
    from pathlib import Path

COSTLY_SHARE = 0.1
"""Most of the time a costly step of following may take (copying a database again)."""
SETTLE_S = 2.0
"""How long the signs that the writer is done with a file (metadata.yaml, the next split file)
must stand before the file is taken as finished without its own end (an MCAP's Data End
record, a closed database): rosbag2 writes them just before it closes the file."""


class FollowStopped(BaseException):  # not an Exception: no reader's last-resort handler takes it
    """Following ended before the recording was finished (a stop was asked for, or idle)."""

    def __init__(self, reason: str) -> None:
        self.reason = reason
        super().__init__(reason)


@dataclass(slots=True)
class Follow:
    """Waiting for a growing recording: how often to look, when to give up, whether to stop.

    Attributes:
        poll_s: seconds between two looks at the files (clamped to the bounds above).
        idle_timeout_s: stop when nothing new arrived for this long (None: wait forever).
        stop_reason: set (from a signal handler) to end the following at the next look.
        finished: set by the input when the recording was finished (not stopped).
        stopped: why following ended early, if it did.
        notes: what the user should know about the run, beyond the report.
        restarts: why the replay started again (a followed file replaced or cut), in order;
            each is a warning of the report.
        watched: the files (and folder) read so far, looked at on every poll
            (:class:`~medkit_replay.inputs.watch.FollowRestart` when one is not what it was).
    """

    poll_s: float = POLL_DEFAULT_S
    idle_timeout_s: float | None = None
    stop_reason: str | None = None
    finished: bool = False
    stopped: str | None = None
    notes: list[str] = field(default_factory=list)
    restarts: list[str] = field(default_factory=list)
    watched: list[Watched] = field(default_factory=list)
    _last_data: float = field(default_factory=time.monotonic)
    _since: dict[object, float] = field(default_factory=dict)
    _spent: dict[object, tuple[float, float]] = field(default_factory=dict)  # start, duration

    def __post_init__(self) -> None:
        self.poll_s = min(max(self.poll_s, POLL_MIN_S), POLL_MAX_S)

    def watch(self, path: Path, *, folder: bool = False) -> Watched:
        """Start watching a file (or the bag folder) now read: see :class:`Watched`."""
        watched = Watched(path, folder=folder)
        self.watched.append(watched)
        return watched

    def restart(self, reason: str) -> None:
        """Start over: the recording is to be replayed again from its start (``reason`` is
        kept in :attr:`restarts`); what was learnt of the old files goes."""
        self.restarts.append(reason)
        self.finished, self.stopped = False, None
        self.notes.clear()
        self.watched.clear()
        self._since.clear()
        self._spent.clear()
        self.saw_data()

    def request_stop(self, reason: str) -> None:
        """Ask the following to end at its next look (safe from a signal handler)."""
        if self.stop_reason is None:
            self.stop_reason = reason

    def saw_data(self) -> None:
        """Something new arrived: the idle timeout starts again."""
        self._last_data = time.monotonic()

    def lasting(self, key: object, holds: bool) -> bool:
        """Whether ``holds`` has been true at every look for SETTLE_S (at least two polls)."""
        if not holds:
            self._since.pop(key, None)
            return False
        since = self._since.setdefault(key, time.monotonic())
        return time.monotonic() - since >= max(SETTLE_S, 2 * self.poll_s)

    def may_spend(self, key: object) -> bool:
        """Whether a costly step may run again: its last run took at most COSTLY_SHARE of the
        time since it began (copying a large database again after each WAL restart would
        otherwise take all the time)."""
        last = self._spent.get(key)
        return last is None or time.monotonic() - last[0] >= last[1] / COSTLY_SHARE

    @contextmanager
    def spending(self, key: object) -> Iterator[None]:
        """Time a costly step for :meth:`may_spend`."""
        start = time.monotonic()
        try:
            yield
        finally:
            self._spent[key] = (start, time.monotonic() - start)

    def check(self) -> None:
        """Raise :class:`FollowStopped` if a stop was asked for.

        Raises:
            FollowStopped: a stop was asked for.
        """
        if self.stop_reason is not None:
            raise FollowStopped(self.stop_reason)

    def wait(self) -> None:
        """Sleep one poll interval before the next look, then look at every file read so far.

        Raises:
            FollowStopped: a stop was asked for, or nothing new arrived for the idle timeout.
            FollowRestart: a file read so far was replaced or cut.
        """
        self.check()
        if (
            self.idle_timeout_s is not None
            and time.monotonic() - self._last_data >= self.idle_timeout_s
        ):
            raise FollowStopped(f"nothing new for {self.idle_timeout_s:g} s")
        time.sleep(self.poll_s)
        self.check()
        for watched in self.watched:
            watched.look()


class Growing(NamedTuple):
    """How one storage file still being written is read: the :class:`Follow` that paces each
    wait, whether the writer has moved on from it (``done``), and its identity (``watched``)."""

    follow: Follow
    done: Callable[[], bool]
    watched: Watched
