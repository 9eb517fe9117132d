"""Range requests to an object store, watched for speed: a try that stalls is ended, not waited on.

Like curl's ``--speed-limit``/``--speed-time``: a try whose bytes arrive at under LOW_SPEED_BYTES
per second, over the last LOW_SPEED_SECONDS, is abandoned (its connections closed).
"""

from __future__ import annotations

import math
import os
import queue
import threading
import time
from typing import TYPE_CHECKING, Any, NamedTuple

from medkit_replay.errors import InputError

if TYPE_CHECKING:
    from collections.abc import Callable

LOW_SPEED_BYTES = 1024
"""A try is too slow under this many bytes per second (over LOW_SPEED_SECONDS)."""
LOW_SPEED_SECONDS = 30.0
"""How long a try may stay under LOW_SPEED_BYTES per second before it is ended."""
SPEED_LIMIT_ENV = "MEDKIT_REPLAY_REMOTE_SPEED_LIMIT"
"""Environment variable: bytes per second under which a try is stalled (0: never)."""
SPEED_TIME_ENV = "MEDKIT_REPLAY_REMOTE_SPEED_TIME"
"""Environment variable: seconds a try may stay under the speed limit."""
CONCURRENT_RANGES = 10
"""Requests of one try in flight at once (as obstore's own ``get_ranges``)."""


class LowSpeed(NamedTuple):
    """The low-speed deadline: under ``bytes_per_s`` for ``seconds`` ends a try."""

    bytes_per_s: float
    seconds: float

    def __str__(self) -> str:
        return f"under {_rate(self.bytes_per_s)} for {self.seconds:g} s"

    def slower(self) -> str:
        """The limit alone, as said of reads that each ended before the time."""
        return f"reads under {_rate(self.bytes_per_s)}"


class Stalled(Exception):  # noqa: N818  # a condition met, not an error of ours
    """A try stayed under the speed limit for its time (said as :class:`LowSpeed` says)."""


class Stopped(Exception):  # noqa: N818
    """The reader was closed while a try was in flight."""


def _rate(per_s: float) -> str:
    for unit, size in (("MB", 1024 * 1024), ("KB", 1024)):
        if per_s >= size:
            return f"{per_s / size:g} {unit}/s"
    return f"{per_s:g} B/s"


def low_speed() -> LowSpeed:
    """The deadline in force: the defaults, or as the environment variables set it.

    Raises:
        InputError: a variable that is not a number in range (one line naming it).
    """
    return LowSpeed(
        _number(SPEED_LIMIT_ENV, LOW_SPEED_BYTES, "a number of bytes per second, 0 or more"),
        _number(SPEED_TIME_ENV, LOW_SPEED_SECONDS, "a number of seconds, more than 0", low=0),
    )


def _number(name: str, default: float, expected: str, low: float | None = None) -> float:
    text = os.environ.get(name, "").strip()
    if not text:
        return default
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or value < 0 or (low is not None and value <= low):
        raise InputError(f"{name}={text[:40]!r}: must be {expected}")
    return value


def fetch_ranges(
    obstore: Any,
    store: object,
    key: str,
    ranges: list[tuple[int, int]],
    deadline: LowSpeed,
    stop: threading.Event,
) -> list[bytes]:
    """The bytes of each ``[start, end)`` of object ``key``: one try, its requests sent
    concurrently (up to CONCURRENT_RANGES), each body read as it arrives so that the speed
    of the whole try is known.

    Raises:
        Stalled: the try stayed under the speed limit for its time; its requests are
            abandoned (each closes its connection at its next bytes, or at obstore's request
            timeout if none come).
        Stopped: ``stop`` was set meanwhile.
        Exception: what obstore raised for a request.
    """
    attempt = _Try(obstore, store, key, ranges)
    for _ in range(min(CONCURRENT_RANGES, len(ranges))):
        _WORKERS.submit(attempt.work)
    samples = [(time.monotonic(), 0)]  # (time, bytes received by then) over the last window
    tick = min(1.0, deadline.seconds / 4)
    try:
        while not attempt.over.wait(tick):
            if stop.is_set():
                raise Stopped
            now, received = time.monotonic(), sum(attempt.received)
            samples.append((now, received))
            while len(samples) > 1 and samples[1][0] <= now - deadline.seconds:
                del samples[0]
            since, before = samples[0]
            slow = received - before < deadline.bytes_per_s * deadline.seconds
            if now - since >= deadline.seconds and slow:
                raise Stalled
    finally:
        attempt.abandon.set()
    if attempt.error is not None:
        raise attempt.error
    return [part if part is not None else b"" for part in attempt.parts]


class _Workers:
    """Daemon threads that read ranges, kept between tries (starting a thread costs about
    what a request on a fast link does); one is started whenever a job would otherwise wait,
    and none is joined at exit (one abandoned on a silent server must not hold the process)."""

    def __init__(self) -> None:
        self._jobs: queue.SimpleQueue[Callable[[], None]] = queue.SimpleQueue()
        self._lock = threading.Lock()
        self._idle = 0
        self._waiting = 0

    def submit(self, job: Callable[[], None]) -> None:
        with self._lock:
            self._waiting += 1
            if self._waiting > self._idle:
                self._idle += 1  # counted from now, so that the next job sees it
                threading.Thread(target=self._run, name="medkit-replay-range", daemon=True).start()
        self._jobs.put(job)

    def _run(self) -> None:
        while True:
            job = self._jobs.get()
            with self._lock:
                self._idle -= 1
                self._waiting -= 1
            job()
            with self._lock:
                self._idle += 1


_WORKERS = _Workers()


class _Try:
    """The requests of one try, taken in turn by its threads; what each received so far."""

    def __init__(self, obstore: Any, store: object, key: str, ranges: list[tuple[int, int]]):
        self._obstore, self._store, self._key, self._ranges = obstore, store, key, ranges
        self.parts: list[bytes | None] = [None] * len(ranges)
        self.received = [0] * len(ranges)  # each slot written by the one thread reading it
        self.error: Exception | None = None
        self.over = threading.Event()  # every range read, or one failed
        self.abandon = threading.Event()
        self._next = iter(range(len(ranges)))
        self._left = len(ranges)
        self._lock = threading.Lock()

    def work(self) -> None:
        while not self.abandon.is_set():
            with self._lock:
                k = next(self._next, None)
            if k is None:
                return
            try:
                part = self._read(k)
            except Exception as exc:  # said by the caller, in its words
                with self._lock:
                    self.error = self.error or exc
                self.over.set()
                return
            if part is None:
                return  # abandoned
            self.parts[k] = part
            with self._lock:
                self._left -= 1
                if not self._left:
                    self.over.set()

    def _read(self, k: int) -> bytes | None:
        start, end = self._ranges[k]
        result = self._obstore.get(self._store, self._key, options={"range": (start, end)})
        pieces = []
        for piece in result.stream(min_chunk_size=1):  # each piece as it comes
            if self.abandon.is_set():
                return None  # the stream goes, and its connection with it
            pieces.append(piece)
            self.received[k] += len(piece)
        return b"".join(pieces)
