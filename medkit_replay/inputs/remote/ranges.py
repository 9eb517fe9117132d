"""A remote object read by ranges: hints gathered, coalesced and sent as concurrent, bounded
batches of range requests, so the one MCAP reader reads an object as it reads a local file.
"""

from __future__ import annotations

import io
import threading
from bisect import bisect_right, insort
from concurrent.futures import CancelledError, Future, ThreadPoolExecutor
from typing import TYPE_CHECKING, NamedTuple

from medkit_replay.closing import Closing

if TYPE_CHECKING:
    from typing import BinaryIO

    from medkit_replay.inputs.ranges import RangeReader
    from medkit_replay.inputs.remote.store import RemoteObject

BATCHES = 4
"""Batches of range requests in flight at once for one file (each sends its requests
concurrently, up to ten at a time)."""
BATCH_RANGES = 128
"""Most ranges asked for in one batch."""
COALESCE_GAP = 4 * 1024
"""Wanted ranges this close are fetched as one request (the gap is fetched too): in S3's
prices a request costs what 4 KB do (see mcap.plan.SKIP_AT_LEAST)."""
MAX_REQUEST = 8 * 1024 * 1024
"""Coalescing stops at this many bytes per request."""
READ_AHEAD_LIMIT = 64 * 1024 * 1024
"""Most bytes of asked-ahead ranges held for one file; the oldest go first."""
STREAM_BLOCK = 8 * 1024 * 1024
"""Bytes one sequential read of a remote object asks for (a file without an index is streamed)."""


class _Block(NamedTuple):
    """One asked-for range: where it ends, the batch fetching it, its place in the batch."""

    end: int
    batch: Future[list[bytes]]
    slot: int


class RemoteRanges(Closing):
    """:class:`~medkit_replay.inputs.ranges.RangeReader` over one remote object.

    Hints are gathered until the next read, then sorted, coalesced and sent in batches (one
    call asks for a batch's ranges concurrently); a read served by a hinted range waits for
    it, any other read is one request. What is held is bounded (READ_AHEAD_LIMIT) and let go
    once the reader says it is past it (:meth:`forget`).
    """

    always_ahead = True

    def __init__(self, remote: RemoteObject) -> None:
        self._remote = remote
        self.size = remote.size
        self._pool = ThreadPoolExecutor(BATCHES, thread_name_prefix="medkit-replay-fetch")
        self._stop = threading.Event()  # set on close: fetches in flight try no more
        self._pending: list[tuple[int, int]] = []
        self._blocks: dict[int, _Block] = {}  # by start, oldest first
        self._starts: list[int] = []  # sorted
        self._users: dict[Future[list[bytes]], int] = {}  # blocks held of each batch
        self._held = 0

    def _covering(self, start: int, end: int) -> tuple[int, _Block] | None:
        at = bisect_right(self._starts, start) - 1
        if at < 0:
            return None
        block_start = self._starts[at]
        block = self._blocks[block_start]
        return (block_start, block) if block.end >= end else None

    def will_need(self, offset: int, length: int) -> None:
        end = min(self.size, offset + length)
        if offset >= 0 and end > offset and self._covering(offset, end) is None:
            self._pending.append((offset, end))

    def _send(self) -> None:
        pending, self._pending = sorted(self._pending), []
        merged: list[list[int]] = []
        for start, end in pending:
            last = merged[-1] if merged else None
            if last and start - last[1] <= COALESCE_GAP and end - last[0] <= MAX_REQUEST:
                last[1] = max(last[1], end)
            else:
                merged.append([start, end])
        fresh = [
            (start, end)
            for start, end in merged
            if start not in self._blocks and self._covering(start, end) is None
        ]
        for first in range(0, len(fresh), BATCH_RANGES):
            batch = fresh[first : first + BATCH_RANGES]
            starts, ends = [start for start, _ in batch], [end for _, end in batch]
            fetch = self._pool.submit(self._remote.fetch_many, starts, ends, self._stop)
            self._users[fetch] = len(batch)
            for slot, (start, end) in enumerate(batch):
                self._blocks[start] = _Block(end, fetch, slot)
                insort(self._starts, start)
                self._held += end - start
        while self._held > READ_AHEAD_LIMIT and len(self._starts) > 1:
            oldest = next(iter(self._blocks))
            self._release(oldest)
            self._starts.remove(oldest)

    def _release(self, start: int) -> None:
        """Let the block at ``start`` go (its start stays in ``_starts``: the caller's)."""
        block = self._blocks.pop(start)
        self._held -= block.end - start
        self._users[block.batch] -= 1
        if not self._users[block.batch]:
            del self._users[block.batch]
            block.batch.cancel()  # nothing else waits for it: not asked for, if not yet

    def forget(self, before: int) -> None:
        cut = bisect_right(self._starts, before)
        kept = []
        for start in self._starts[:cut]:
            if self._blocks[start].end <= before:
                self._release(start)
            else:
                kept.append(start)
        self._starts[:cut] = kept

    def _served(self, found: tuple[int, _Block] | None, offset: int, end: int) -> bytes | None:
        if found is None:
            return None
        start, block = found
        try:
            parts = block.batch.result()
        except CancelledError:  # let go before it was sent
            return None
        return bytes(memoryview(parts[block.slot])[offset - start : end - start])

    def read(self, offset: int, length: int) -> bytes:
        end = min(self.size, offset + max(0, length))
        if end <= offset:
            return b""
        if self._pending:
            self._send()
        data = self._served(self._covering(offset, end), offset, end)
        return data if data is not None else self._remote.fetch(offset, end, self._stop)

    def read_into(self, offset: int, view: memoryview) -> int:
        data = self.read(offset, len(view))
        view[: len(data)] = data
        return len(data)

    def cached(self, offset: int, length: int) -> bytes | None:
        end = min(self.size, offset + length)
        found = self._covering(offset, end)
        if found is None or not found[1].batch.done() or found[1].batch.cancelled():
            return None
        if found[1].batch.exception() is not None:
            return None
        return self._served(found, offset, end)

    def close(self) -> None:
        self._stop.set()
        self._pool.shutdown(wait=False, cancel_futures=True)
        self._blocks.clear()
        self._starts.clear()
        self._users.clear()
        self._held = 0


class _AheadStream(io.RawIOBase):
    """A remote object read from the start as a file (wrapped in ``io.BufferedReader``),
    asking for the next block while this one is used (the blocks before it are let go)."""

    def __init__(self, reader: RangeReader) -> None:
        super().__init__()
        self._reader = reader
        self._pos = 0

    def readable(self) -> bool:
        return True

    def seekable(self) -> bool:
        return True

    def tell(self) -> int:
        return self._pos

    def seek(self, offset: int, whence: int = io.SEEK_SET) -> int:
        base = {io.SEEK_SET: 0, io.SEEK_CUR: self._pos, io.SEEK_END: self._reader.size}[whence]
        self._pos = max(0, base + offset)
        return self._pos

    def readinto(self, buffer: memoryview) -> int:  # type: ignore[override]
        self._reader.forget(self._pos)
        view = memoryview(buffer).cast("B")
        got = self._reader.read_into(self._pos, view[: max(0, self._reader.size - self._pos)])
        self._pos += got
        self._reader.will_need(self._pos, min(len(buffer), STREAM_BLOCK))
        return got

    def close(self) -> None:
        if not self.closed:
            self._reader.close()
        super().close()


class RemoteSource:
    """:class:`~medkit_replay.inputs.ranges.ByteSource` of one remote object."""

    def __init__(self, remote: RemoteObject) -> None:
        self._remote = remote

    def ranges(self) -> RemoteRanges:
        return RemoteRanges(self._remote)

    def stream(self) -> BinaryIO:
        return io.BufferedReader(_AheadStream(self.ranges()), STREAM_BLOCK)
