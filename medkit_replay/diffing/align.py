"""Aligns one fault's transitions or events, baseline with current, as a line diff aligns lines.

Pure: two sequences of report items in, the items left unaligned or shifted out.
"""

from __future__ import annotations

from difflib import SequenceMatcher
from typing import TYPE_CHECKING, Literal

if TYPE_CHECKING:
    from collections.abc import Callable, Mapping, Sequence

    KeyFunction = Callable[[Mapping[str, object]], tuple[object, ...]]

Unaligned = tuple[
    Literal["shifted", "missing", "extra"], tuple[object, ...], int | None, int | None
]
"""An item unaligned (``missing`` from the current, ``extra`` in it) or aligned but ``shifted``
beyond the tolerance: how, its key, its baseline and its current bag time (None where absent)."""


def align(
    before: Sequence[Mapping[str, object]],
    after: Sequence[Mapping[str, object]],
    key: KeyFunction,
    tolerance: int,
) -> list[Unaligned]:
    """Align two sequences of one fault's items on their keys, as a line diff does.

    First the items equal in key and bag time are aligned (the same item, surely); then, in
    each gap between those, the remaining items are aligned on their keys alone.
    """
    old_keys = [key(item) for item in before]
    new_keys = [key(item) for item in after]
    old_times = [_time(item) for item in before]
    new_times = [_time(item) for item in after]
    found: list[Unaligned] = []

    exact = SequenceMatcher(
        None,
        list(zip(old_keys, old_times, strict=True)),
        list(zip(new_keys, new_times, strict=True)),
        autojunk=False,
    )
    for tag, a1, a2, b1, b2 in exact.get_opcodes():
        if tag == "equal":
            continue
        old_gap = [(old_keys[i], old_times[i]) for i in range(a1, a2)]
        new_gap = [(new_keys[j], new_times[j]) for j in range(b1, b2)]
        for i, j in _gap_pairs(old_gap, new_gap):
            if i is None:
                if j is not None:
                    found.append(("extra", new_gap[j][0], None, new_gap[j][1]))
            elif j is None:
                found.append(("missing", old_gap[i][0], old_gap[i][1], None))
            elif abs(new_gap[j][1] - old_gap[i][1]) > tolerance:
                found.append(("shifted", old_gap[i][0], old_gap[i][1], new_gap[j][1]))
    # Listed in bag-time order of the baseline (missing, shifted) or current (extra) item.
    found.sort(key=_first_time)
    return found


_Item = tuple[tuple[object, ...], int]
"""An item's key and bag time."""
_Pairs = list[tuple[int | None, int | None]]
"""An alignment: (i, j) aligned, (i, None) only in the baseline, (None, j) only in the current."""
MAX_CELLS = 40_000
"""Largest (baseline x current) table an exact alignment fills; larger gaps are aligned by runs
of equal keys first."""
MAX_RUN_CELLS = 200_000
"""Largest table aligning two runs of one key by least total shift; beyond, pairs in order."""


def _gap_pairs(before: Sequence[_Item], after: Sequence[_Item]) -> _Pairs:
    """Align the items of a gap: as many pairs of equal keys as possible and, among those
    alignments, the one with the least total time shift.

    Large gaps (two unrelated recordings, say) are aligned by runs of equal keys (``fault_updated``
    x 500), then item by item inside aligned runs; the largest, key occurrence by occurrence.
    """
    n, m = len(before), len(after)
    if n * m <= MAX_CELLS:
        return _exact_pairs(before, after)
    old_runs, new_runs = _runs(before), _runs(after)
    if len(old_runs) * len(new_runs) > MAX_CELLS:
        return _occurrence_pairs(before, after)
    run_pairs = _exact_pairs(
        [(key, length) for key, _, length in old_runs],
        [(key, length) for key, _, length in new_runs],
        weight=min,
        cost=lambda a, b: abs(a - b),
    )
    pairs: _Pairs = []
    for i, j in run_pairs:
        if i is None:
            if j is not None:
                _, first, length = new_runs[j]
                pairs += [(None, k) for k in range(first, first + length)]
        elif j is None:
            _, first, length = old_runs[i]
            pairs += [(k, None) for k in range(first, first + length)]
        else:
            _, old_first, old_length = old_runs[i]
            _, new_first, new_length = new_runs[j]
            old_times = [t for _, t in before[old_first : old_first + old_length]]
            new_times = [t for _, t in after[new_first : new_first + new_length]]
            pairs += [
                (None if a is None else old_first + a, None if b is None else new_first + b)
                for a, b in _run_pairs(old_times, new_times)
            ]
    return pairs


def _exact_pairs(
    before: Sequence[_Item],
    after: Sequence[_Item],
    *,
    weight: Callable[[int, int], int] = lambda a, b: 1,
    cost: Callable[[int, int], int] = lambda a, b: abs(b - a),
) -> _Pairs:
    """The alignment of greatest total ``weight`` (1 per pair of equal keys), and among those
    the least total ``cost`` (the time shift); each item's int is passed to both."""
    n, m = len(before), len(after)
    # best[i][j]: (weight, -cost) of the best alignment of before[i:] and after[j:]
    best = [[(0, 0)] * (m + 1) for _ in range(n + 1)]

    def paired(i: int, j: int) -> tuple[int, int]:
        gained, spent = best[i + 1][j + 1]
        a, b = before[i][1], after[j][1]
        return gained + weight(a, b), spent - cost(a, b)

    for i in range(n - 1, -1, -1):
        row, below = best[i], best[i + 1]
        for j in range(m - 1, -1, -1):
            choice = max(below[j], row[j + 1])
            if before[i][0] == after[j][0]:
                choice = max(choice, paired(i, j))
            row[j] = choice
    pairs: _Pairs = []
    i = j = 0
    while i < n and j < m:
        if before[i][0] == after[j][0] and best[i][j] == paired(i, j):
            pairs.append((i, j))
            i, j = i + 1, j + 1
        elif best[i][j] == best[i + 1][j]:
            pairs.append((i, None))
            i += 1
        else:
            pairs.append((None, j))
            j += 1
    pairs += [(k, None) for k in range(i, n)]
    pairs += [(None, k) for k in range(j, m)]
    return pairs


def _runs(items: Sequence[_Item]) -> list[tuple[tuple[object, ...], int, int]]:
    """Runs of equal keys: (key, first index, length)."""
    runs: list[tuple[tuple[object, ...], int, int]] = []
    for index, (key, _) in enumerate(items):
        if runs and runs[-1][0] == key:
            runs[-1] = (key, runs[-1][1], runs[-1][2] + 1)
        else:
            runs.append((key, index, 1))
    return runs


def _run_pairs(before: Sequence[int], after: Sequence[int]) -> _Pairs:
    """Align two runs of one key (their times): every item of the shorter run paired, in
    order, with the least total shift; the longer run's others unpaired."""
    if len(before) > len(after):
        return [(j, i) for i, j in _run_pairs(after, before)]
    short, extra = len(before), len(after) - len(before)
    if extra == 0 or short * (extra + 1) > MAX_RUN_CELLS:
        return [*zip(range(short), range(short), strict=True)] + [
            (None, k) for k in range(short, len(after))
        ]
    # cost[i][k]: least shift pairing before[:i] within after[:i + k] (k of those unpaired)
    inf = float("inf")
    cost = [[inf] * (extra + 1) for _ in range(short + 1)]
    cost[0] = [0.0] * (extra + 1)
    for i in range(1, short + 1):
        for k in range(extra + 1):
            take = cost[i - 1][k] + abs(after[i - 1 + k] - before[i - 1])
            skip = cost[i][k - 1] if k else inf
            cost[i][k] = min(take, skip)
    pairs: _Pairs = []
    i, k = short, extra
    while i > 0:
        if k and cost[i][k] == cost[i][k - 1]:
            pairs.append((None, i + k - 1))
            k -= 1
        else:
            pairs.append((i - 1, i - 1 + k))
            i -= 1
    pairs += [(None, index) for index in range(k - 1, -1, -1)]
    pairs.reverse()
    return pairs


def _occurrence_pairs(before: Sequence[_Item], after: Sequence[_Item]) -> _Pairs:
    """The n-th item of each key in the baseline with the n-th of that key in the current."""
    positions: dict[tuple[object, ...], list[int]] = {}
    for j, (key, _) in enumerate(after):
        positions.setdefault(key, []).append(j)
    seen: dict[tuple[object, ...], int] = {}
    pairs: _Pairs = []
    for i, (key, _) in enumerate(before):
        count = seen.get(key, 0)
        seen[key] = count + 1
        candidates = positions.get(key, [])
        pairs.append((i, candidates[count] if count < len(candidates) else None))
    for key, candidates in positions.items():
        pairs += [(None, j) for j in candidates[seen.get(key, 0) :]]
    return pairs


def _time(item: Mapping[str, object]) -> int:
    t_ns = item["t_ns"]
    assert isinstance(t_ns, int)  # checked when the report was read
    return t_ns


def _first_time(item: Unaligned) -> int:
    _, _, old_t, new_t = item
    t = old_t if isinstance(old_t, int) else new_t
    return t if isinstance(t, int) else 0
