"""The pure ordering kernel: reorder window and k-way merge, on plain tuples.

No files: every stream is a list of Bound and Timed tuples.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from hypothesis import given, strategies as st

from medkit_replay.inputs.merge import Bound, Merged, Timed, merge, reorder_batches

if TYPE_CHECKING:
    from collections.abc import Iterator


def _run(stream: list[Bound | Timed[str]], max_held: int = 1000) -> tuple[list[str], list[str]]:
    late: list[str] = []
    batches = reorder_batches(stream, lambda t: late.append(t.item), max_held)
    out = [t.item for batch in batches for t in batch]
    return out, late


def test_reorder_sorts_within_what_bounds_allow() -> None:
    stream: list[Bound | Timed[str]] = [
        Bound(10),
        Timed(12, (0,), "b"),
        Timed(10, (1,), "a"),
        Bound(11),
        Timed(11, (2,), "c"),
        Bound(20),
        Timed(25, (3,), "d"),
    ]
    assert _run(stream) == (["a", "c", "b", "d"], [])


def test_reorder_ties_leave_in_position_order_even_when_stored_later() -> None:
    # A chunk read out of file order (indexed reading) holds a lower position at the same time.
    stream: list[Bound | Timed[str]] = [
        Bound(5),
        Timed(5, (0, 200, 0), "second"),
        Bound(5),
        Timed(5, (0, 100, 0), "first"),
    ]
    assert _run(stream) == (["first", "second"], [])


def test_reorder_drops_items_older_than_released_ones() -> None:
    stream: list[Bound | Timed[str]] = [Timed(5, (0,), "a"), Bound(9), Timed(3, (1,), "late")]
    assert _run(stream) == (["a"], ["late"])


def test_reorder_holds_no_more_than_max_held() -> None:
    stream: list[Bound | Timed[str]] = [Timed(t, (t,), str(t)) for t in (3, 1, 2, 0)]
    assert _run(stream, max_held=2) == (["1", "2", "3"], ["0"])


@given(st.lists(st.integers(0, 50), max_size=60))
def test_reorder_with_exact_bounds_is_a_stable_sort(times: list[int]) -> None:
    # Bounds from a sorted prefix-minimum of the remaining times are always true promises.
    stream: list[Bound | Timed[str]] = []
    for index, t_ns in enumerate(times):
        stream.append(Bound(min(times[index:])))
        stream.append(Timed(t_ns, (index,), f"{t_ns}:{index}"))
    out, late = _run(stream)
    expected = [f"{t}:{i}" for i, t in sorted(enumerate(times), key=lambda e: (e[1], e[0]))]
    assert out == expected
    assert late == []


def test_merge_orders_by_time_then_input_then_position() -> None:
    first = [Timed(1, (0,), "a0"), Timed(5, (1,), "a1"), Timed(5, (2,), "a2")]
    second = [Timed(1, (0,), "b0"), Timed(5, (0,), "b1"), Timed(7, (1,), "b2")]
    merged = list(merge([first, second]))
    assert [m.item for m in merged] == ["a0", "b0", "a1", "a2", "b1", "b2"]
    assert merged[1] == Merged(1, 1, (0,), "b0")


def test_merge_is_lazy() -> None:
    def endless() -> Iterator[Timed[int]]:
        t_ns = 0
        while True:
            yield Timed(t_ns, (t_ns,), t_ns)
            t_ns += 1

    stream = merge([endless(), [Timed(2, (0,), -1)]])
    assert [next(stream).item for _ in range(4)] == [0, 1, 2, -1]


@given(st.lists(st.lists(st.integers(0, 20), max_size=15), max_size=5))
def test_merge_equals_sorting_everything(inputs: list[list[int]]) -> None:
    streams = [
        [Timed(t, (pos,), (t, index, pos)) for pos, t in enumerate(sorted(times))]
        for index, times in enumerate(inputs)
    ]
    merged = [m.item for m in merge(streams)]
    assert merged == sorted(item for stream in streams for _, _, item in stream)
