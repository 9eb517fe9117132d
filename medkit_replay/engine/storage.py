"""Fault records and the in-memory storage semantics of ros2_medkit's fault manager.

Pure state machine (fault-manager.md §1.4-§1.8, §1.13): no validation, events or clock.
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from medkit_replay.engine.debounce import (
    DebounceConfig,
    counter_step,
    status_rule,
)
from medkit_replay.model import NearMiss, Status
from medkit_replay.releases import Release, default_release

if TYPE_CHECKING:
    from collections.abc import Callable

CRITICAL = 3
FAILED = 0
UINT32_MAX = 2**32 - 1
DEFAULT_NEAR_MISS_BOUND = 200
STORAGE_TYPES = ("memory", "sqlite")
DEFAULT_STORAGE_TYPE = "sqlite"


@dataclass(slots=True)
class FaultRecord:
    """Mutable per-code state, aggregated across all reporters."""

    fault_code: str
    severity: int
    description: str
    first_occurred_ns: int
    last_occurred_ns: int
    last_failed_ns: int
    status: Status
    counter: int = -1
    occurrence_count: int = 1
    last_passed_ns: int = 0
    sources: set[str] = field(default_factory=set)
    _sorted_sources: tuple[str, ...] | None = None

    def add_source(self, source_id: str) -> None:
        """Add a FAILED reporter's source_id (the set is never pruned)."""
        if source_id not in self.sources:
            self.sources.add(source_id)
            self._sorted_sources = None

    def sorted_sources(self) -> tuple[str, ...]:
        """Reporting sources in byte order, as upstream returns them."""
        if self._sorted_sources is None:
            self._sorted_sources = tuple(sorted(self.sources, key=lambda s: s.encode("utf-8")))
        return self._sorted_sources


ReportOutcome = tuple["Status | None", "Status | None", bool]
"""What one applied report did: status before, status after, whether it began an occurrence
(a plain tuple: one is made per report, and a named one costs several times more)."""


class FaultStorage:
    """Upstream's fault storage of one release: one record per fault code, never evicted.

    ``storage_type`` ("memory" or "sqlite", upstream's parameter) matters only for a release
    whose two backends decide a status differently (0.6.0); every rule that differs between
    releases is picked here, once, from the release's fields.
    """

    def __init__(
        self,
        near_miss_bound: int = DEFAULT_NEAR_MISS_BOUND,
        release: Release | None = None,
        storage_type: str = DEFAULT_STORAGE_TYPE,
    ) -> None:
        self.faults: dict[str, FaultRecord] = {}
        self.near_misses: dict[str, list[NearMiss]] = {}
        self.near_miss_bound = near_miss_bound
        rules = release or default_release()
        shared = rules.backends_share_status_rule or storage_type != "sqlite"
        latch = rules.latch_confirmed_healed
        self._after_failed = status_rule(confirm=True, heal=shared, latch=latch)
        self._after_passed = status_rule(confirm=shared, heal=True, latch=latch)
        self._step = counter_step(in_band=rules.clamp_counter)
        self._count_every_failed = not rules.occurrences_on_edges
        self._passed_dates = rules.passed_sets_last_occurred
        self._reset_first = rules.reactivation_resets_first_occurred
        self.record_near_miss: Callable[[FaultRecord, DebounceConfig, int, str, int], None] = (
            self._near_miss if rules.near_misses else _no_near_miss
        )
        # PREFAILED faults by last FAILED time, for time-based confirmation: a heap of
        # (last_failed_ns, code) and each code's live entry. An entry may be stale (the fault
        # left PREFAILED, or failed again later); it is checked when it comes out.
        self.tracks_prefailed = False
        self._prefailed: list[tuple[int, str]] = []
        self._entry_ns: dict[str, int] = {}

    def track_prefailed(self) -> None:
        """Keep PREFAILED faults ordered by last FAILED time (for :meth:`take_prefailed`)."""
        if not self.tracks_prefailed:
            self.tracks_prefailed = True
            for fault in self.faults.values():
                self.watch(fault)

    def watch(self, fault: FaultRecord) -> None:
        """Note a fault that may be PREFAILED now, or may have failed again since last noted.

        Invariant while tracking: every PREFAILED fault has a live entry no later than its
        last FAILED time (a later entry is never needed: it is moved on when it comes out).
        """
        if not self.tracks_prefailed or fault.status != "PREFAILED":
            return
        code, key = fault.fault_code, fault.last_failed_ns
        entry = self._entry_ns.get(code)
        if entry is None or key < entry:
            self._entry_ns[code] = key
            heapq.heappush(self._prefailed, (key, code))

    def take_prefailed(self, failed_by_ns: int) -> list[FaultRecord]:
        """PREFAILED faults whose last FAILED is at or before ``failed_by_ns``, any order.

        They leave the index: the caller confirms them. Costs their number (and that of the
        stale entries passed), times log of the index size; never a scan of every fault.
        """
        heap, entries, faults = self._prefailed, self._entry_ns, self.faults
        due: list[FaultRecord] = []
        while heap and heap[0][0] <= failed_by_ns:
            key, code = heapq.heappop(heap)
            if entries.get(code) != key:
                continue  # superseded by an earlier entry for the same code
            del entries[code]
            fault = faults[code]
            if fault.status != "PREFAILED":
                continue  # noted again by watch() if it ever becomes PREFAILED
            if fault.last_failed_ns != key:
                self.watch(fault)  # failed again since: its entry moves to the new time
                continue
            due.append(fault)
        return due

    def report(
        self,
        fault_code: str,
        event_type: int,
        severity: int,
        description: str,
        source_id: str,
        t_ns: int,
        config: DebounceConfig,
    ) -> ReportOutcome:
        """Apply one accepted report (fault-manager.md §1.20)."""
        fault = self.faults.get(fault_code)
        failed = event_type == FAILED
        crit_hit = config.critical_immediate_confirm and severity == CRITICAL
        if fault is None:
            if not failed:
                return (None, None, False)
            status = "CONFIRMED" if crit_hit else self._after_failed(-1, None, config)
            assert status is not None  # counter -1 always yields a status
            fault = FaultRecord(
                fault_code=fault_code,
                severity=severity,
                description=description,
                first_occurred_ns=t_ns,
                last_occurred_ns=t_ns,
                last_failed_ns=t_ns,
                status=status,
                sources={source_id},
            )
            self.faults[fault_code] = fault
            self.record_near_miss(fault, config, severity, source_id, t_ns)
            if self.tracks_prefailed:
                self.watch(fault)
            return (None, status, True)

        before = fault.status
        if before == "CLEARED":
            if not failed:
                return (before, before, False)
            fault.counter = -1
            if self._reset_first:
                fault.first_occurred_ns = t_ns
            fault.last_occurred_ns = fault.last_failed_ns = t_ns
            fault.add_source(source_id)
            fault.occurrence_count = min(fault.occurrence_count + 1, UINT32_MAX)
            fault.severity = max(fault.severity, severity)
            if description:
                fault.description = description
            status = "CONFIRMED" if crit_hit else self._after_failed(-1, "CLEARED", config)
            assert status is not None
            fault.status = status
            self.record_near_miss(fault, config, severity, source_id, t_ns)
            if self.tracks_prefailed:
                self.watch(fault)
            return (before, status, True)

        if failed:
            fault.last_occurred_ns = fault.last_failed_ns = t_ns
            fault.counter = self._step(fault.counter, -1, config)
            if self._count_every_failed:
                fault.occurrence_count = min(fault.occurrence_count + 1, UINT32_MAX)
            fault.add_source(source_id)
            fault.severity = max(fault.severity, severity)
            if description:
                fault.description = description
            new_status = (
                "CONFIRMED" if crit_hit else self._after_failed(fault.counter, before, config)
            )
        else:
            fault.last_passed_ns = t_ns
            if self._passed_dates:
                fault.last_occurred_ns = t_ns
            fault.counter = self._step(fault.counter, 1, config)
            new_status = self._after_passed(fault.counter, before, config)
        assert new_status is not None  # an existing fault always has a status to keep
        fault.status = new_status
        if failed:
            self.record_near_miss(fault, config, severity, source_id, t_ns)
        if self.tracks_prefailed:
            self.watch(fault)
        return (before, new_status, False)

    def clear(self, fault_code: str) -> bool:
        """Mark a fault CLEARED; False when the code was never reported."""
        fault = self.faults.get(fault_code)
        if fault is None:
            return False
        fault.status = "CLEARED"
        return True

    def take_due_for_auto_confirm(self, now_ns: int, after_ns: int) -> list[str]:
        """Codes of PREFAILED faults whose last FAILED is at least ``after_ns`` old, byte order.

        Taken out of the PREFAILED index (:meth:`track_prefailed` must be on): confirm them.
        """
        due = [fault.fault_code for fault in self.take_prefailed(now_ns - after_ns)]
        due.sort(key=lambda c: c.encode("utf-8"))
        return due

    def set_near_miss_bound(self, bound: int) -> int:
        """Apply a new per-code bound (0 = unlimited); returns how many entries were dropped."""
        self.near_miss_bound = bound
        if bound <= 0:
            return 0
        dropped = 0
        for series in self.near_misses.values():
            excess = len(series) - bound
            if excess > 0:
                del series[:excess]
                dropped += excess
        return dropped

    def _near_miss(
        self, fault: FaultRecord, config: DebounceConfig, severity: int, source_id: str, t_ns: int
    ) -> None:
        if fault.status == "CONFIRMED":
            return
        series = self.near_misses.setdefault(fault.fault_code, [])
        series.append(
            NearMiss(
                fault_code=fault.fault_code,
                t_ns=t_ns,
                debounce_counter=fault.counter,
                confirmation_threshold=config.confirmation_threshold,
                severity=severity,
                source_id=source_id,
                resulting_status=fault.status,
            )
        )
        if self.near_miss_bound > 0 and len(series) > self.near_miss_bound:
            del series[0]


def _no_near_miss(
    fault: FaultRecord, config: DebounceConfig, severity: int, source_id: str, t_ns: int
) -> None:
    """A release without near misses keeps none."""
