"""Time order for message streams: a bounded reorder window and the k-way merge of inputs.

Pure: no I/O, no clock; items are plain tuples whose payload is never compared.
"""

from __future__ import annotations

import heapq
from collections import deque
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


def reorder_batches(
    stream: Iterable[Bound | Timed[T] | list[Timed[T]]],
    on_late: Callable[[Timed[T]], None],
    max_held: int,
) -> Iterator[list[Timed[T]]]:
    """Sort a stream that is in order up to what its bounds allow, holding only the overlap.

    An item is held until a bound past its time shows nothing earlier can follow; ties in time
    leave in position order. An item older than one already released (its reader's bound was
    wrong) is passed to ``on_late`` instead of being yielded, so the output never goes back.
    Items arriving in order wait in a FIFO run (cheap); the first one out of order moves the
    run into a heap until the heap has drained again.

    Args:
        stream: items, bounds, and batches: a list is items already sorted by
            ``(t_ns, position)`` (a chunk's messages) with no bound among them; a batch that
            continues the items held moves through in one piece.
        on_late: called with each item that arrived after a later one was released.
        max_held: most items held at once; past it the earliest is released without a bound,
            so memory stays bounded even when a reader gives no bounds.

    Yields:
        The items sorted by ``(t_ns, position)``, in lists.
    """
    run: deque[Timed[T]] = deque()
    heap: list[tuple[int, Position, int, Timed[T]]] = []
    tiebreak = count()
    last: tuple[int, Position] | None = None

    def one(entry: Timed[T]) -> list[Timed[T]]:
        """An item on its own; returns what leaves because of it."""
        nonlocal last
        t_ns, position = entry.t_ns, entry.position
        if last is not None and (t_ns < last[0] or (t_ns == last[0] and position < last[1])):
            on_late(entry)
            return []
        if not heap and (
            not run
            or t_ns > run[-1].t_ns
            or (t_ns == run[-1].t_ns and position >= run[-1].position)
        ):
            run.append(entry)
            if len(run) > max_held:
                timed = run.popleft()
                last = (timed.t_ns, timed.position)
                return [timed]
            return []
        for held in run:
            heapq.heappush(heap, (held.t_ns, held.position, next(tiebreak), held))
        run.clear()
        heapq.heappush(heap, (t_ns, position, next(tiebreak), entry))
        if len(heap) > max_held:
            t_ns, position, _, timed = heapq.heappop(heap)
            last = (t_ns, position)
            return [timed]
        return []

    for entry in stream:
        if type(entry) is list:
            if not entry:
                continue
            first = entry[0]
            key = (first.t_ns, first.position)
            if (
                not heap
                and (last is None or key >= last)
                and (not run or key >= (run[-1].t_ns, run[-1].position))
            ):
                run.extend(entry)  # in order and none late: it joins the run whole
                if len(run) > max_held:
                    out = [run.popleft() for _ in range(len(run) - max_held)]
                    last = (out[-1].t_ns, out[-1].position)
                    yield out
                continue
            out = []
            for item in entry:
                out += one(item)
            if out:
                yield out
        elif type(entry) is Bound or isinstance(entry, Bound):
            # Strict: an item at exactly the bound may still be preceded by one at a lower position.
            bound = entry.t_ns
            if heap:
                out = []
                while heap and heap[0][0] < bound:
                    out.append(heapq.heappop(heap)[3])
                if out:
                    last = (out[-1].t_ns, out[-1].position)
                    yield out
            elif run and run[0].t_ns < bound:
                if run[-1].t_ns < bound:
                    out = list(run)
                    run.clear()
                else:
                    out = []
                    while run[0].t_ns < bound:
                        out.append(run.popleft())
                last = (out[-1].t_ns, out[-1].position)
                yield out
        else:
            out = one(entry)  # type: ignore[arg-type]  # a Timed
            if out:
                yield out
    if run:
        yield list(run)
    if heap:
        yield [heapq.heappop(heap)[3] for _ in range(len(heap))]


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
