"""Range requests to an object store, watched for speed: a try that stalls is ended, not waited on.

Like curl's ``--speed-limit``/``--speed-time``: a try whose bytes arrive at under LOW_SPEED_BYTES
per second, over the last LOW_SPEED_SECONDS, is abandoned (its connections closed).
"""

from __future__ import annotations

import asyncio
import math
import os
from contextlib import suppress
from typing import TYPE_CHECKING, Any, NamedTuple

from medkit_replay.errors import InputError

if TYPE_CHECKING:
    import threading

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


async def fetch_ranges(
    obstore: Any,
    store: object,
    key: str,
    ranges: list[tuple[int, int]],
    deadline: LowSpeed,
    stop: threading.Event,
) -> list[bytes]:
    """The bytes of each ``[start, end)`` of object ``key``, requested concurrently, each
    read as it arrives so that the speed of the whole try is known.

    Raises:
        Stalled: the try stayed under the speed limit for its time (its requests cancelled).
        Stopped: ``stop`` was set meanwhile.
        Exception: what obstore raised for a request.
    """
    received = 0
    gate = asyncio.Semaphore(CONCURRENT_RANGES)

    async def one(start: int, end: int) -> bytes:
        nonlocal received
        async with gate:
            result = await obstore.get_async(store, key, options={"range": (start, end)})
            pieces = []
            async for piece in result.stream(min_chunk_size=1):  # each piece as it comes
                pieces.append(piece)
                received += len(piece)
        return b"".join(pieces)

    work = asyncio.gather(*(one(start, end) for start, end in ranges))
    loop = asyncio.get_running_loop()
    samples = [(loop.time(), 0)]  # (time, bytes received by then) over the last window
    tick = min(1.0, deadline.seconds / 4)
    try:
        while True:
            done, _ = await asyncio.wait({work}, timeout=tick)
            if done:
                parts: list[bytes] = work.result()
                return parts
            if stop.is_set():
                raise Stopped
            now = loop.time()
            samples.append((now, received))
            while len(samples) > 1 and samples[1][0] <= now - deadline.seconds:
                del samples[0]
            since, before = samples[0]
            slow = received - before < deadline.bytes_per_s * deadline.seconds
            if now - since >= deadline.seconds and slow:
                raise Stalled
    finally:
        if not work.done():
            work.cancel()  # closes the connections: the server stops sending
            with suppress(asyncio.CancelledError, Exception):
                await work
