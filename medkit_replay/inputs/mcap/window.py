"""Which MCAP chunks a time window needs, and their messages merged into log-time order.

Pure: chunks are described by their chunk index (first and last log time, offset), and each is
decoded by a callback only when the merge needs it, so a reverse read stops near its window's end.
"""

from __future__ import annotations

import heapq
from typing import TYPE_CHECKING, TypeVar

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator, Sequence

    from medkit_replay.inputs.mcap.plan import ChunkIndex
    from medkit_replay.inputs.merge import Position, Timed

T = TypeVar("T")


def window_chunks(
    chunks: Sequence[ChunkIndex], start_ns: int, end_ns: int, *, reverse: bool = False
) -> list[ChunkIndex]:
    """The chunks whose log times meet [start_ns, end_ns], in the order a read takes them:
    by first log time (then offset), or with ``reverse`` by last log time (then end), latest first.
    """
    inside = [c for c in chunks if c.start_ns <= end_ns and c.end_ns >= start_ns]
    if reverse:
        inside.sort(key=lambda c: (c.end_ns, c.offset + c.length), reverse=True)
    else:
        inside.sort()
    return inside


def merge_window(
    chunks: Sequence[ChunkIndex],
    decode: Callable[[ChunkIndex], list[Timed[T]]],
    start_ns: int,
    end_ns: int,
    *,
    reverse: bool = False,
) -> Iterator[Timed[T]]:
    """The messages of ``chunks`` (in :func:`window_chunks` order) with log time in
    [start_ns, end_ns], sorted by (log time, position), or exactly the opposite with ``reverse``.

    A chunk is decoded only once every message before its first log time (with ``reverse``:
    after its last) has been yielded, so only the messages of chunks that overlap in time are
    held, and a reader that stops early never decodes the chunks beyond.
    """
    held: list[tuple[int, Position, int, Timed[T]]] = []  # (time, position) keys, negated: reverse
    sign = -1 if reverse else 1
    serial = 0  # breaks ties between equal keys (only damage repeats a position)
    for chunk in chunks:
        edge = sign * (chunk.end_ns if reverse else chunk.start_ns)
        while held and held[0][0] < edge:
            yield heapq.heappop(held)[3]
        for message in decode(chunk):
            if start_ns <= message.t_ns <= end_ns:
                position = tuple(sign * p for p in message.position)
                heapq.heappush(held, (sign * message.t_ns, position, serial, message))
                serial += 1
    while held:
        yield heapq.heappop(held)[3]
