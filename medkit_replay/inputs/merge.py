"""Time order for message streams: a bounded reorder window and the k-way merge of inputs.

Pure: no I/O, no clock; items are plain tuples whose payload is never compared.
"""

from __future__ import annotations

import heapq
from itertools import count
from typing import TYPE_CHECKING, Generic, NamedTuple, TypeVar

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Iterator, Sequence

T = TypeVar("T")

Position = tuple[int, ...]
"""Where a message sits in its input; increases in the order the input stores its messages."""


class Bound(NamedTuple):
    """A promise from a reader: every item it yields after this one has ``t_ns >= t_ns``."""

    t_ns: int


class Timed(NamedTuple, Generic[T]):
    """One message of one input: log time (ns), position in the input, payload."""

    t_ns: int
    position: Position
    item: T


class Merged(NamedTuple, Generic[T]):
    """One message of the merged stream."""

    t_ns: int
    input_index: int
    position: Position
    item: T


def reorder(
    stream: Iterable[Bound | Timed[T]], on_late: Callable[[Timed[T]], None], max_held: int
) -> Iterator[Timed[T]]:
    """Sort a stream that is in order up to what its bounds allow, holding only the overlap.

    An item is held until a bound past its time shows nothing earlier can follow; ties in time
    leave in position order. An item older than one already released (its reader's bound was
    wrong) is passed to ``on_late`` instead of being yielded, so the output never goes back.

    Args:
        stream: items and bounds as the reader produces them.
        on_late: called with each item that arrived after a later one was released.
        max_held: most items held at once; past it the earliest is released without a bound,
            so memory stays bounded even when a reader gives no bounds.

    Yields:
        The items, sorted by ``(t_ns, position)``.
    """
    heap: list[tuple[int, Position, int, Timed[T]]] = []
    tiebreak = count()
    last: tuple[int, Position] | None = None
    for entry in stream:
        if isinstance(entry, Bound):
            # Strict: an item at exactly the bound may still be preceded by one at a lower position.
            while heap and heap[0][0] < entry.t_ns:
                t_ns, position, _, timed = heapq.heappop(heap)
                last = (t_ns, position)
                yield timed
            continue
        if last is not None and (entry.t_ns, entry.position) < last:
            on_late(entry)
            continue
        heapq.heappush(heap, (entry.t_ns, entry.position, next(tiebreak), entry))
        if len(heap) > max_held:
            t_ns, position, _, timed = heapq.heappop(heap)
            last = (t_ns, position)
            yield timed
    while heap:
        yield heapq.heappop(heap)[3]


def merge(streams: Sequence[Iterable[Timed[T]]]) -> Iterator[Merged[T]]:
    """Merge sorted per-input streams into one, ordered by (t_ns, input index, position).

    Args:
        streams: one stream per input, each sorted by ``(t_ns, position)``.

    Returns:
        A lazy iterator; it holds one pending item per input.
    """
    tagged = [_tag(index, stream) for index, stream in enumerate(streams)]
    return heapq.merge(*tagged, key=_merge_key)


def _tag(index: int, stream: Iterable[Timed[T]]) -> Iterator[Merged[T]]:
    for timed in stream:
        yield Merged(timed.t_ns, index, timed.position, timed.item)


def _merge_key(entry: Merged[T]) -> tuple[int, int, Position]:
    return (entry.t_ns, entry.input_index, entry.position)
