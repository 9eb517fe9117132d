"""Correlation rules learned from a fleet: codes that confirm shortly after another code in most
runs (a root and its symptoms), and codes that confirm together (a burst).

Pure: fed each run's confirmations in order, as ``(t_ns, fault_code)``; no I/O, no clock.
"""

from __future__ import annotations

import math
import re
from bisect import bisect_left, bisect_right
from collections.abc import Sequence
from dataclasses import dataclass

from medkit_replay.model import NS_PER_MS

DEFAULT_WINDOW_MS = 2000
"""How long after a root its symptoms may confirm, and how close a burst's codes confirm (ms).
Wider than upstream's 500 ms default: bridges and debounce thresholds delay a symptom's
confirmation by a second or more after its cause."""
DEFAULT_MIN_SUPPORT = 3
"""Runs a pattern must be seen in before it is proposed."""
DEFAULT_MIN_CONFIDENCE = 0.8
"""Share of the runs in which the later code confirmed that the pattern explains (for a
cascade: the root confirmed shortly before; for a burst: the codes confirmed together)."""
WINDOW_STEP_MS = 100
"""A rule's window is the longest delay seen, with a quarter more, rounded up to this."""
DEFAULT_MAX_PAIRS = 20_000
"""Pairs of codes compared, at most (``--max-pairs``): every pair is weighed in every run, and
its delays kept, so time and memory grow with the square of the codes. 20,000 pairs are 200
codes (some seconds and tens of MB over tens of runs); past it, the codes confirmed in the most
runs are kept (ties in byte order) and the pairs left out are counted."""
"""A rule's window is the longest delay seen, with a quarter more, rounded up to this."""

Confirmations = Sequence[tuple[int, str]]


@dataclass(frozen=True, slots=True)
class Symptom:
    """One symptom of a proposed cascade, with its evidence.

    Attributes:
        support: runs where it confirmed within the window after the root.
        confirmed_runs: runs where it confirmed at all.
        max_delay_ms: the longest root-to-symptom delay in those runs.
    """

    code: str
    support: int
    confirmed_runs: int
    max_delay_ms: int

    @property
    def confidence(self) -> float:
        """support / confirmed_runs: how rarely it confirmed without the root before it."""
        return self.support / self.confirmed_runs if self.confirmed_runs else 0.0


@dataclass(frozen=True, slots=True)
class Cascade:
    """A proposed hierarchical rule: a root and the symptoms it drags."""

    root: str
    root_runs: int
    symptoms: tuple[Symptom, ...]

    @property
    def window_ms(self) -> int:
        """The rule's window: the longest delay seen with a margin (see WINDOW_STEP_MS)."""
        return rule_window(max(s.max_delay_ms for s in self.symptoms))


@dataclass(frozen=True, slots=True)
class Burst:
    """A proposed auto-cluster rule: codes that confirm together.

    Attributes:
        support: runs where at least two of them confirmed within the window of each other.
        confidence: the lowest share, over its pairs, of runs with either code in which both
            confirmed together.
        spread_ms: the longest gap seen between two of them confirming together.
    """

    codes: tuple[str, ...]
    support: int
    confidence: float
    spread_ms: int

    @property
    def window_ms(self) -> int:
        """The rule's window (see WINDOW_STEP_MS)."""
        return rule_window(self.spread_ms)


@dataclass(frozen=True, slots=True)
class Paired:
    """Which codes were compared in pairs: those confirmed in at least min_support runs (no
    other can make a pattern), or the ``kept`` of them confirmed in most runs when they make
    more than max_pairs pairs (``dropped`` pairs were then never weighed)."""

    candidates: int
    kept: int
    max_pairs: int

    @property
    def dropped(self) -> int:
        return pairs_of(self.candidates) - pairs_of(self.kept)


@dataclass(frozen=True, slots=True)
class Suggestion:
    """What the fleet suggests, and what it was learned from."""

    runs: int
    window_ms: int
    min_support: int
    min_confidence: float
    cascades: tuple[Cascade, ...]
    bursts: tuple[Burst, ...]
    paired: Paired


def pairs_of(codes: int) -> int:
    """Unordered pairs of ``codes`` codes."""
    return codes * (codes - 1) // 2


def _paired_codes(
    present: dict[str, int], min_support: int, max_pairs: int
) -> tuple[list[str], Paired]:
    """The codes to compare in pairs, in byte order (see :class:`Paired`)."""
    candidates = sorted(
        (c for c, runs in present.items() if runs >= min_support),
        key=lambda c: (-present[c], c.encode("utf-8")),
    )
    kept = len(candidates)
    while pairs_of(kept) > max_pairs:
        kept -= 1
    codes = sorted(candidates[:kept], key=lambda c: c.encode("utf-8"))
    return codes, Paired(len(candidates), kept, max_pairs)


def rule_window(delay_ms: int) -> int:
    """A window that holds ``delay_ms`` with a quarter more, rounded up to WINDOW_STEP_MS."""
    return max(WINDOW_STEP_MS, math.ceil(delay_ms * 1.25 / WINDOW_STEP_MS) * WINDOW_STEP_MS)


class _Run:
    """One run's confirmations: times per code, and each confirmation's place in the order."""

    def __init__(self, confirmations: Confirmations) -> None:
        self.times: dict[str, list[int]] = {}
        self.order: dict[str, list[int]] = {}
        for position, (t_ns, code) in enumerate(confirmations):
            self.times.setdefault(code, []).append(t_ns)
            self.order.setdefault(code, []).append(position)

    def delay_after(self, first: str, then: str, window_ns: int) -> int | None:
        """The shortest delay (ns) from a confirmation of ``first`` to a later confirmation of
        ``then`` within the window, or None."""
        best: int | None = None
        first_times, first_order = self.times[first], self.order[first]
        then_times, then_order = self.times[then], self.order[then]
        for t_ns, position in zip(then_times, then_order, strict=True):
            start = bisect_left(first_times, t_ns - window_ns)
            end = bisect_right(first_times, t_ns)
            for index in range(end - 1, start - 1, -1):
                if first_order[index] < position:
                    delay = t_ns - first_times[index]
                    best = delay if best is None else min(best, delay)
                    break
        return best

    def gap_near(self, one: str, other: str, window_ns: int) -> int | None:
        """The shortest gap (ns) between a confirmation of ``one`` and one of ``other``."""
        best: int | None = None
        other_times = self.times[other]
        for t_ns in self.times[one]:
            at = bisect_left(other_times, t_ns - window_ns)
            if at < len(other_times) and abs(other_times[at] - t_ns) <= window_ns:
                gap = abs(other_times[at] - t_ns)
                if at + 1 < len(other_times):
                    gap = min(gap, abs(other_times[at + 1] - t_ns))
                best = gap if best is None else min(best, gap)
        return best


def suggest(
    runs: Sequence[Confirmations],
    window_ms: int = DEFAULT_WINDOW_MS,
    min_support: int = DEFAULT_MIN_SUPPORT,
    min_confidence: float = DEFAULT_MIN_CONFIDENCE,
    max_pairs: int = DEFAULT_MAX_PAIRS,
) -> Suggestion:
    """Propose cascades and bursts from runs' confirmations (each in the order they happened).

    A cascade ``root -> symptom``: in at least ``min_support`` runs the symptom confirmed within
    ``window_ms`` after the root, in at least ``min_confidence`` of the runs it confirmed in,
    and not half as often the other way round. Codes together: a pair confirming within
    ``window_ms`` of each other in at least ``min_support`` runs and ``min_confidence`` of the
    runs either confirmed in. Codes joined by either relation form a group: when one of them
    leads every other, the group is a cascade (root and symptoms), else a burst; symptoms that
    confirm together because their root drags them are thus never a burst of their own.
    At most ``max_pairs`` pairs of codes are weighed (see :class:`Paired`).
    """
    window_ns = window_ms * NS_PER_MS
    parsed = [_Run(run) for run in runs]
    present: dict[str, int] = {}
    for run in parsed:
        for code in run.times:
            present[code] = present.get(code, 0) + 1
    codes, paired = _paired_codes(present, min_support, max_pairs)
    after: dict[tuple[str, str], list[int]] = {}
    together: dict[tuple[str, str], list[int]] = {}
    for run in parsed:
        here = [c for c in codes if c in run.times]
        for first in here:
            for then in here:
                if first == then:
                    continue
                delay = run.delay_after(first, then, window_ns)
                if delay is not None:
                    after.setdefault((first, then), []).append(delay)
                if first < then:
                    gap = run.gap_near(first, then, window_ns)
                    if gap is not None:
                        together.setdefault((first, then), []).append(gap)

    def leads(first: str, then: str) -> bool:
        delays = after.get((first, then), [])
        backwards = len(after.get((then, first), []))
        return (
            len(delays) >= min_support
            and len(delays) / present[then] >= min_confidence
            and backwards * 2 < len(delays)
        )

    strong = {
        pair: gaps
        for pair, gaps in together.items()
        if len(gaps) >= min_support
        and len(gaps) / max(present[pair[0]], present[pair[1]]) >= min_confidence
    }
    led = {pair for pair in after if leads(*pair)}
    cascades: list[Cascade] = []
    bursts: list[Burst] = []
    for group in _components(codes, led | set(strong)):
        leaders = [r for r in group if all((r, x) in led for x in group if x != r)]
        if leaders:  # one code leads all the others: a root and its symptoms
            cascades.append(_cascade(leaders[0], group, after, present))
            continue
        pairs = {p: gaps for p, gaps in strong.items() if p[0] in group}
        if pairs:  # no order among them: they confirm together
            bursts.append(_burst(group, pairs, present))
            continue
        # Ordered pairs but no common root (a chain longer than the window): each root with
        # what it leads, roots with more support first.
        inner = sorted(
            {p for p in led if p[0] in group},
            key=lambda p: (-len(after[p]), p[0].encode(), p[1].encode()),
        )
        taken: set[str] = set()
        for root, _ in inner:
            if root in taken:
                continue
            symptoms = [t for r, t in inner if r == root and t not in taken]
            if symptoms:
                cascades.append(_cascade(root, [root, *symptoms], after, present))
                taken.update([root, *symptoms])
    cascades.sort(key=lambda c: (-max(x.support for x in c.symptoms), c.root.encode()))
    bursts.sort(key=lambda b: (-b.support, b.codes[0].encode()))
    return Suggestion(
        len(runs), window_ms, min_support, min_confidence, tuple(cascades), tuple(bursts), paired
    )


def _components(codes: Sequence[str], edges: set[tuple[str, str]]) -> list[list[str]]:
    """Groups of codes joined by edges (either way), each in code byte order."""
    neighbours: dict[str, set[str]] = {}
    for one, other in edges:
        neighbours.setdefault(one, set()).add(other)
        neighbours.setdefault(other, set()).add(one)
    seen: set[str] = set()
    groups = []
    for start in codes:
        if start in seen or start not in neighbours:
            continue
        group: set[str] = set()
        stack = [start]
        while stack:
            code = stack.pop()
            if code not in group:
                group.add(code)
                stack.extend(neighbours[code] - group)
        seen |= group
        groups.append(sorted(group, key=lambda c: c.encode("utf-8")))
    return groups


def _cascade(
    root: str,
    group: Sequence[str],
    after: dict[tuple[str, str], list[int]],
    present: dict[str, int],
) -> Cascade:
    symptoms = tuple(
        Symptom(
            code, len(after[(root, code)]), present[code], max(after[(root, code)]) // NS_PER_MS
        )
        for code in group
        if code != root
    )
    return Cascade(root, present[root], symptoms)


def _burst(
    group: Sequence[str], pairs: dict[tuple[str, str], list[int]], present: dict[str, int]
) -> Burst:
    support = max(len(gaps) for gaps in pairs.values())
    confidence = min(
        len(gaps) / max(present[one], present[other]) for (one, other), gaps in pairs.items()
    )
    spread = max(max(gaps) for gaps in pairs.values()) // NS_PER_MS
    return Burst(tuple(group), support, confidence, spread)


def rule_id(prefix: str, code: str, used: set[str]) -> str:
    """A rule or pattern id from a code: lower case, runs of other characters as ``_``, made
    unique with a number."""
    base = f"{prefix}_{re.sub(r'[^a-z0-9]+', '_', code.lower()).strip('_')}"
    name, number = base, 2
    while name in used:
        name, number = f"{base}_{number}", number + 1
    used.add(name)
    return name
