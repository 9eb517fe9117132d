"""The fast path's plumbing: the reorder window (FIFO run, batches) and spools holding rows.

``reorder_batches`` keeps the items that arrive in order in a FIFO and uses a heap only after
one arrives out of order; with or without batches it must behave exactly as the plain heap
version (kept here as the oracle) on the flattened stream.
"""

from __future__ import annotations

import heapq
from itertools import count
from typing import TYPE_CHECKING

from hypothesis import given, strategies as st

from medkit_replay.inputs.merge import Bound, Timed, reorder_batches
from medkit_replay.model import EVENT_ROWS, REPORT_ROWS, FaultEvent, FaultSnapshot, ReportRecord
from medkit_replay.spool import Spool

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Iterator

    from medkit_replay.inputs.merge import Position


def heap_reorder(
    stream: Iterable[Bound | Timed[str]], on_late: Callable[[Timed[str]], None], max_held: int
) -> Iterator[Timed[str]]:
    """The reorder window as it was before the fast path: every item through a heap."""
    heap: list[tuple[int, Position, int, Timed[str]]] = []
    tiebreak = count()
    last: tuple[int, Position] | None = None
    for entry in stream:
        if isinstance(entry, Bound):
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


entries = st.lists(
    st.one_of(
        st.builds(Bound, st.integers(0, 30)),
        st.builds(
            lambda t, p, tag: Timed(t, (p,), f"{t}:{p}:{tag}"),
            st.integers(0, 30),
            st.integers(0, 5),
            st.integers(0, 3),
        ),
    ),
    max_size=60,
)


def run(
    function: Callable[..., Iterator[Timed[str]]], stream: list[Bound | Timed[str]], held: int
) -> tuple[list[str], list[str]]:
    late: list[str] = []
    out = [t.item for t in function(stream, lambda t: late.append(t.item), held)]
    return out, late


def flat(
    stream: Iterable[Bound | Timed[str] | list[Timed[str]]],
    on_late: Callable[[Timed[str]], None],
    max_held: int,
) -> Iterator[Timed[str]]:
    for batch in reorder_batches(stream, on_late, max_held):
        yield from batch


@given(stream=entries, held=st.integers(1, 8))
def test_reorder_behaves_as_the_heap_version(stream: list[Bound | Timed[str]], held: int) -> None:
    assert run(flat, stream, held) == run(heap_reorder, stream, held)


@given(stream=entries, held=st.integers(1, 8), cuts=st.lists(st.integers(0, 60), max_size=10))
def test_batches_behave_as_the_heap_version_flattened(
    stream: list[Bound | Timed[str]], held: int, cuts: list[int]
) -> None:
    # Runs of consecutive items that are sorted become batches, as a chunk reader makes them.
    batched: list[Bound | Timed[str] | list[Timed[str]]] = []
    for index, entry in enumerate(stream):
        last = batched[-1] if batched else None
        if isinstance(entry, Timed) and index not in cuts:
            if isinstance(last, list) and (last[-1].t_ns, last[-1].position) <= (
                entry.t_ns,
                entry.position,
            ):
                last.append(entry)
                continue
            batched.append([entry])
            continue
        batched.append(entry)
    late: list[str] = []
    out = [
        t.item
        for batch in reorder_batches(batched, lambda t: late.append(t.item), held)
        for t in batch
    ]
    assert (out, late) == run(heap_reorder, stream, held)


def report(t_ns: int) -> ReportRecord:
    return ReportRecord(
        t_ns=t_ns,
        origin="diagnostic_bridge",
        topic="/diagnostics",
        fault_code="MOTOR",
        event_type="PASSED",
        severity=0,
        description="",
        source_id="/diagnostic_bridge",
        accepted=True,
        reject_reason=None,
        status="CONFIRMED",
        debounce_counter=3,
        confirmation_threshold=-1,
        healing_threshold=3,
    )


@given(
    kinds=st.lists(st.sampled_from(["object", "row", "sink"]), max_size=40), chunk=st.integers(1, 7)
)
def test_a_spool_of_rows_reads_as_its_records(kinds: list[str], chunk: int) -> None:
    spool: Spool[ReportRecord] = Spool(chunk, codec=REPORT_ROWS)
    sink = spool.row_sink()
    expected = []
    for t_ns, kind in enumerate(kinds):
        record = report(t_ns)
        expected.append(record)
        if kind == "object":
            spool.append(record)
        elif kind == "row":
            spool.append_row(REPORT_ROWS.encode(record))
        else:
            sink(REPORT_ROWS.encode(record))
            spool.settle()
    assert len(spool) == len(expected)
    assert list(spool) == expected
    assert [spool[i] for i in range(-len(expected), len(expected))] == expected + expected
    assert list(spool.rows()) == [REPORT_ROWS.encode(r) for r in expected]
    # A record read twice from memory is the same object, as before rows existed.
    assert all(a is b for a, b in zip(spool._tail, list(spool)[spool._spilled :], strict=True))
    spool.close()


def test_event_rows_splice_the_snapshot_in() -> None:
    snapshot = FaultSnapshot(
        fault_code="A",
        severity=2,
        description="d",
        first_occurred_ns=1,
        last_occurred_ns=2,
        last_passed_ns=3,
        occurrence_count=4,
        status="CONFIRMED",
        reporting_sources=("/s",),
        muted=False,
        root_cause_code=None,
        cluster_ids=(),
    )
    event = FaultEvent(t_ns=5, event_type="fault_updated", fault=snapshot)
    row = EVENT_ROWS.encode(event)
    assert row == (
        5,
        "fault_updated",
        "A",
        2,
        "d",
        1,
        2,
        3,
        4,
        "CONFIRMED",
        ("/s",),
        False,
        None,
        (),
        (),
    )
    assert EVENT_ROWS.decode(row) == event
