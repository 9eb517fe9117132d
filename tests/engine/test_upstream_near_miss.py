"""Ports of upstream's near-miss series tests (fault-manager.md §4.4, NM-01..NM-28).

Storage level: FaultStorage.report with the test's explicit config; "reopen" is modelled as
carrying on with the same storage. Default report: PUMP_PRESSURE_LOW, WARN, /hydraulics/pump,
"pressure dipping", at t_i = 1.7e18 ns + i ms.
"""

from __future__ import annotations

from dataclasses import replace

from medkit_replay.engine.debounce import DebounceConfig
from medkit_replay.engine.manager import FaultManager, FaultManagerConfig
from medkit_replay.engine.storage import FaultStorage
from medkit_replay.model import NS_PER_MS, NearMiss, ReportRequest
from tests.engine.upstream_support import (
    CONFIRMED_EV,
    CRITICAL,
    ERROR,
    FAILED,
    HEALED_EV,
    PASSED,
    WARN,
    events_since,
    signatures,
    upstream,
)

CODE = "PUMP_PRESSURE_LOW"
SRC = "/hydraulics/pump"
DESC = "pressure dipping"
FOUR_STRIKE = DebounceConfig(confirmation_threshold=-4, critical_immediate_confirm=False)
DEEP = replace(FOUR_STRIKE, confirmation_threshold=-20)
SIZE_MAX = 2**64 - 1


def t(i: int) -> int:
    """t_i = 1 700 000 000 000 000 000 ns + i·1 ms."""
    return 1_700_000_000_000_000_000 + i * NS_PER_MS


def fail(
    storage: FaultStorage,
    i: int,
    config: DebounceConfig = FOUR_STRIKE,
    *,
    code: str = CODE,
    severity: int = WARN,
    source: str = SRC,
    description: str = DESC,
) -> None:
    """One FAILED report at t_i."""
    storage.report(code, FAILED, severity, description, source, t(i), config)


def pass_(storage: FaultStorage, i: int, config: DebounceConfig = FOUR_STRIKE) -> None:
    """One PASSED report (severity WARN, as upstream's tests send it) at t_i."""
    storage.report(CODE, PASSED, WARN, "", SRC, t(i), config)


def series(storage: FaultStorage, code: str = CODE) -> list[NearMiss]:
    """The near-miss series of a code (empty when it has none)."""
    return list(storage.near_misses.get(code, []))


def counters(storage: FaultStorage, code: str = CODE) -> list[int]:
    """Debounce counters of a code's series."""
    return [entry.debounce_counter for entry in series(storage, code)]


@upstream("NM-01")
def test_nm01_series_is_appended_and_survives_clear() -> None:
    """NM-01 SeriesIsAppendedAndSurvivesClear (InMemory), NearMissSeriesIsAppendedNotOverwritten."""
    storage = FaultStorage()
    for i in range(3):
        fail(storage, i)
    assert storage.faults[CODE].status != "CONFIRMED"
    entries = series(storage)
    assert len(entries) == 3
    assert [e.debounce_counter for e in entries] == [-1, -2, -3]
    assert [e.t_ns for e in entries] == [t(0), t(1), t(2)]
    for entry in entries:
        assert entry.fault_code == CODE
        assert entry.confirmation_threshold == -4
        assert entry.source_id == SRC
        assert entry.severity == WARN
        assert entry.resulting_status == "PREFAILED"
    assert storage.clear(CODE)
    assert series(storage) == entries


@upstream("NM-01")
def test_nm01_near_miss_series_survives_clear_fault() -> None:
    """NM-01 NearMissSeriesSurvivesClearFault (SQLite): 4 FAILED (4th confirms) → 3 entries,
    still 3 with counters -1..-3 after CLEAR."""
    storage = FaultStorage()
    for i in range(4):
        fail(storage, i)
    assert storage.faults[CODE].status == "CONFIRMED"
    assert counters(storage) == [-1, -2, -3]
    assert storage.clear(CODE)
    assert counters(storage) == [-1, -2, -3]


@upstream("NM-02")
def test_nm02_confirming_report_is_not_a_near_miss() -> None:
    """NM-02 ConfirmingReportIsNotANearMiss."""
    storage = FaultStorage()
    for i in range(4):
        fail(storage, i)
    assert storage.faults[CODE].status == "CONFIRMED"
    assert len(series(storage)) == 3


@upstream("NM-03")
def test_nm03_series_continues_across_reactivation() -> None:
    """NM-03 NearMissSeriesContinuesAcrossReactivation."""
    storage = FaultStorage()
    for i in range(4):
        fail(storage, i)
    storage.clear(CODE)
    fail(storage, 10, description="pressure dipping again")
    entries = series(storage)
    assert len(entries) == 4
    assert entries[3].debounce_counter == -1
    assert entries[3].t_ns == t(10)
    fault = storage.faults[CODE]
    assert fault.status == "PREFAILED"
    assert fault.occurrence_count == 2


@upstream("NM-04")
def test_nm04_series_survives_reopen() -> None:
    """NM-04 NearMissSeriesSurvivesReopen: 3 FAILED, CLEAR, reopen (carry on) → -1..-3."""
    storage = FaultStorage()
    for i in range(3):
        fail(storage, i)
    storage.clear(CODE)
    assert counters(storage) == [-1, -2, -3]


@upstream("NM-05")
def test_nm05_passed_report_is_not_a_near_miss() -> None:
    """NM-05 PassedReportIsNotANearMiss."""
    storage = FaultStorage()
    fail(storage, 0)
    fail(storage, 1)
    assert len(series(storage)) == 2
    pass_(storage, 2)
    assert len(series(storage)) == 2


@upstream("NM-06")
def test_nm06_critical_immediate_confirm_is_not_a_near_miss() -> None:
    """NM-06 CriticalImmediateConfirmIsNotANearMiss: four-strike with the CRITICAL bypass on."""
    storage = FaultStorage()
    config = replace(FOUR_STRIKE, critical_immediate_confirm=True)
    code = "BATTERY_THERMAL_RUNAWAY"
    fail(
        storage,
        0,
        config,
        code=code,
        severity=CRITICAL,
        source="/power/bms",
        description="cell over temperature",
    )
    assert storage.faults[code].status == "CONFIRMED"
    assert series(storage, code) == []


@upstream("NM-07")
def test_nm07_immediate_confirm_threshold_records_no_near_miss() -> None:
    """NM-07 ImmediateConfirmThresholdRecordsNoNearMiss: defaults."""
    storage = FaultStorage()
    fail(storage, 0, DebounceConfig(), severity=ERROR, description="pressure lost")
    assert storage.faults[CODE].status == "CONFIRMED"
    assert series(storage) == []


@upstream("NM-08")
def test_nm08_failed_report_under_healed_latch_is_near_miss() -> None:
    """NM-08 FailedReportUnderHealedLatchIsNearMiss: four-strike, healing on, heal 1."""
    storage = FaultStorage()
    config = replace(FOUR_STRIKE, healing_enabled=True, healing_threshold=1)
    fail(storage, 0, config)
    assert len(series(storage)) == 1
    assert (storage.faults[CODE].counter, storage.faults[CODE].status) == (-1, "PREFAILED")
    pass_(storage, 1, config)
    assert (storage.faults[CODE].counter, storage.faults[CODE].status) == (0, "PREFAILED")
    pass_(storage, 2, config)
    assert (storage.faults[CODE].counter, storage.faults[CODE].status) == (1, "HEALED")
    fail(storage, 3, config)
    entries = series(storage)
    assert len(entries) == 2
    assert entries[1].debounce_counter == 0
    assert entries[1].resulting_status == "HEALED"


@upstream("NM-09")
def test_nm09_series_bounded_keeping_newest() -> None:
    """NM-09 SeriesBoundedKeepingNewest: conf -20, bound 3, 5 FAILED → -3, -4, -5."""
    storage = FaultStorage(near_miss_bound=3)
    for i in range(5):
        fail(storage, i, DEEP)
    assert counters(storage) == [-3, -4, -5]


@upstream("NM-10")
def test_nm10_near_miss_bound_of_one_keeps_latest_only() -> None:
    """NM-10 NearMissBoundOfOneKeepsLatestOnly."""
    storage = FaultStorage(near_miss_bound=1)
    for i in range(4):
        fail(storage, i, DEEP)
    assert counters(storage) == [-4]


@upstream("NM-11")
def test_nm11_bound_is_per_fault_code() -> None:
    """NM-11 BoundIsPerFaultCode: bound 2, three interleaved rounds of two codes."""
    storage = FaultStorage(near_miss_bound=2)
    for i in range(3):
        fail(storage, i, DEEP)
        fail(
            storage,
            i,
            DEEP,
            code="MOTOR_OVERHEAT",
            source="/powertrain/motor",
            description="temperature rising",
        )
    assert len(series(storage)) == 2
    assert len(series(storage, "MOTOR_OVERHEAT")) == 2


@upstream("NM-12")
def test_nm12_bound_zero_is_unlimited() -> None:
    """NM-12 BoundZeroIsUnlimited: conf -200, bound 0, 150 FAILED → 150."""
    storage = FaultStorage(near_miss_bound=0)
    for i in range(150):
        fail(storage, i, replace(FOUR_STRIKE, confirmation_threshold=-200))
    assert len(series(storage)) == 150


@upstream("NM-13")
def test_nm13_first_near_miss_on_empty_series() -> None:
    """NM-13 NearMissTableCreatedOnDatabaseFromOlderBuild, state part: with no series yet, the
    next FAILED starts one with a single entry. (The table migration is SQLite-only.)"""
    storage = FaultStorage()
    assert series(storage) == []
    fail(storage, 0)
    assert len(series(storage)) == 1


@upstream("NM-14")
def test_nm14_series_survives_healed_state() -> None:
    """NM-14 SeriesSurvivesHealedReclassification, state part: four-strike, healing on, heal 1:
    F, P, P → HEALED with 1 entry. Reclassification HEALED→CLEARED is a restart feature of the
    SQLite backend (not modelled); clearing stands in for it and keeps the series."""
    storage = FaultStorage()
    config = replace(FOUR_STRIKE, healing_enabled=True, healing_threshold=1)
    fail(storage, 0, config)
    pass_(storage, 1, config)
    pass_(storage, 2, config)
    assert storage.faults[CODE].status == "HEALED"
    assert len(series(storage)) == 1
    assert storage.clear(CODE)
    assert len(series(storage)) == 1


@upstream("NM-15")
def test_nm15_series_uses_arrival_order_not_timestamps() -> None:
    """NM-15 NearMissSeriesUsesArrivalOrderNotTimestamps: bound 2; F @t10, @t11, @t0."""
    storage = FaultStorage(near_miss_bound=2)
    for i in (10, 11, 0):
        fail(storage, i, DEEP)
    entries = series(storage)
    assert [e.t_ns for e in entries] == [t(11), t(0)]
    assert [e.debounce_counter for e in entries] == [-2, -3]
    assert storage.faults[CODE].last_occurred_ns == t(0)  # no monotonic guard


@upstream("NM-16")
def test_nm16_entries_describe_their_own_report() -> None:
    """NM-16 NearMissEntriesDescribeTheirOwnReport: each entry has its report's threshold,
    severity and source."""
    storage = FaultStorage()
    fail(storage, 0, FOUR_STRIKE)
    fail(
        storage,
        1,
        replace(FOUR_STRIKE, confirmation_threshold=-8),
        severity=ERROR,
        source="/hydraulics/backup_pump",
    )
    entries = series(storage)
    assert [
        (e.confirmation_threshold, e.severity, e.source_id, e.debounce_counter) for e in entries
    ] == [(-4, WARN, SRC, -1), (-8, ERROR, "/hydraulics/backup_pump", -2)]


@upstream("NM-17")
def test_nm17_series_continues_after_reopen() -> None:
    """NM-17 NearMissSeriesContinuesAfterReopen: 2 FAILED, reopen (carry on), F @t2."""
    storage = FaultStorage()
    fail(storage, 0)
    fail(storage, 1)
    fail(storage, 2)
    assert counters(storage) == [-1, -2, -3]
    assert series(storage)[2].t_ns == t(2)


@upstream("NM-18", "NM-21")
def test_nm18_nm21_applying_smaller_bound_trims_and_reports_dropped() -> None:
    """NM-18 ApplyingSmallerBoundTrimsExistingSeries and NM-21
    ApplyingBoundReportsHowManyEntriesItDropped: 5+5 entries, bound 2 → 6 dropped, then 0."""
    storage = FaultStorage(near_miss_bound=0)
    for i in range(5):
        fail(storage, i, DEEP)
        fail(
            storage,
            i,
            DEEP,
            code="MOTOR_OVERHEAT",
            source="/powertrain/motor",
            description="temperature rising",
        )
    assert len(series(storage)) == 5
    assert storage.set_near_miss_bound(2) == 6
    assert counters(storage) == [-4, -5]
    assert len(series(storage, "MOTOR_OVERHEAT")) == 2
    assert storage.set_near_miss_bound(2) == 0


@upstream("NM-19")
def test_nm19_applying_unlimited_bound_keeps_existing_series() -> None:
    """NM-19 ApplyingUnlimitedBoundKeepsExistingSeries: bound 4, 4 FAILED, bound 0 → 4."""
    storage = FaultStorage(near_miss_bound=4)
    for i in range(4):
        fail(storage, i, DEEP)
    assert storage.set_near_miss_bound(0) == 0
    assert len(series(storage)) == 4


@upstream("NM-20")
def test_nm20_unlimited_bound_spelt_as_size_max_keeps_the_series() -> None:
    """NM-20 UnlimitedBoundSpeltAsSizeMaxKeepsTheSeries."""
    storage = FaultStorage()
    for i in range(3):
        fail(storage, i, DEEP)
    assert storage.set_near_miss_bound(SIZE_MAX) == 0
    assert len(series(storage)) == 3
    fail(storage, 3, DEEP)
    assert len(series(storage)) == 4


@upstream("NM-22")
def test_nm22_passed_report_on_unknown_fault_writes_nothing() -> None:
    """NM-22 PassedReportOnUnknownFaultWritesNothing."""
    storage = FaultStorage()
    outcome = storage.report("NEVER_REPORTED", PASSED, WARN, "", SRC, t(0), FOUR_STRIKE)
    assert outcome[2] is False
    assert len(storage.faults) == 0
    assert series(storage, "NEVER_REPORTED") == []
    assert storage.near_misses == {}


NM23_SERIES = [
    (-1, "PREFAILED"),
    (1, "HEALED"),
    (0, "HEALED"),
    (-1, "HEALED"),
    (-2, "HEALED"),
    (-3, "HEALED"),
]


@upstream("NM-23")
def test_nm23_near_miss_separates_approach_from_ramp_back() -> None:
    """NM-23 NearMissSeparatesApproachFromRampBackIntoAFault: four-strike, healing on, heal 2."""
    storage = FaultStorage()
    config = replace(FOUR_STRIKE, healing_enabled=True, healing_threshold=2)
    fail(storage, 0, config)
    statuses = []
    for i in (1, 2, 3):
        pass_(storage, i, config)
        statuses.append((storage.faults[CODE].counter, storage.faults[CODE].status))
    assert statuses == [(0, "PREFAILED"), (1, "PREPASSED"), (2, "HEALED")]
    for i in range(4, 10):
        fail(storage, i, config)
    assert storage.faults[CODE].status == "CONFIRMED"
    assert storage.faults[CODE].counter == -4
    entries = series(storage)
    assert entries[0].resulting_status == "PREFAILED"
    assert all(e.resulting_status != "CONFIRMED" for e in entries)
    assert sum(e.resulting_status == "PREFAILED" for e in entries) == 1
    assert [(e.debounce_counter, e.resulting_status) for e in entries] == NM23_SERIES


@upstream("NM-23")
def test_nm23_node_events() -> None:
    """NM-23 at node level (conf -4, healing on, heal 2): the only events are fault_cleared
    (HEALED) at the 3rd PASSED (step 4) and fault_confirmed at the 10th step."""
    manager = FaultManager(
        FaultManagerConfig(
            debounce=DebounceConfig(
                confirmation_threshold=-4, healing_enabled=True, healing_threshold=2
            )
        )
    )
    kinds = ["F", "P", "P", "P", *["F"] * 6]
    per_step = []
    for i, kind in enumerate(kinds):
        before = len(manager.output.events)
        event_type = FAILED if kind == "F" else PASSED
        assert manager.report(
            ReportRequest(
                t_ns=t(i),
                fault_code=CODE,
                event_type=event_type,
                severity=WARN,
                description=DESC if kind == "F" else "",
                source_id=SRC,
            )
        )
        per_step.append(signatures(events_since(manager, before)))
    assert per_step == [()] * 3 + [(HEALED_EV,)] + [()] * 5 + [(CONFIRMED_EV,)]
    assert [
        (e.debounce_counter, e.resulting_status) for e in manager.storage.near_misses[CODE]
    ] == NM23_SERIES


@upstream("NM-24")
def test_nm24_resulting_status_survives_reopen() -> None:
    """NM-24 NearMissResultingStatusSurvivesReopen: 1 FAILED, reopen (carry on) → [PREFAILED]."""
    storage = FaultStorage()
    fail(storage, 0)
    assert [e.resulting_status for e in series(storage)] == ["PREFAILED"]


@upstream("NM-25")
def test_nm25_next_failed_appends_prefailed() -> None:
    """NM-25 NearMissResultingStatusColumnAddedToOlderTable, state part: the next FAILED appends
    an entry with resulting_status PREFAILED. (The old-row column migration is SQLite-only.)"""
    storage = FaultStorage()
    fail(storage, 0)
    fail(storage, 1)
    assert [e.resulting_status for e in series(storage)] == ["PREFAILED", "PREFAILED"]


@upstream("NM-26")
def test_nm26_empty_for_unknown_fault() -> None:
    """NM-26 EmptyForUnknownFault / NearMissSeriesEmptyForUnknownFault."""
    storage = FaultStorage()
    fail(storage, 0)
    assert series(storage, "UNKNOWN_FAULT") == []
    assert "UNKNOWN_FAULT" not in storage.near_misses


@upstream("NM-27")
def test_nm27_entries_carry_the_resulting_status() -> None:
    """NM-27 EntriesCarryTheResultingStatus: four-strike, healing on, heal 2."""
    storage = FaultStorage()
    config = replace(FOUR_STRIKE, healing_enabled=True, healing_threshold=2)
    fail(storage, 0, config)
    for i in (1, 2, 3):
        pass_(storage, i, config)
    assert storage.faults[CODE].status == "HEALED"
    fail(storage, 4, config)
    entries = series(storage)
    assert [e.resulting_status for e in entries] == ["PREFAILED", "HEALED"]
    assert [e.debounce_counter for e in entries] == [-1, 1]


@upstream("NM-28")
def test_nm28_mixed_entity_thresholds_produce_the_same_series() -> None:
    """NM-28 StorageBackendParityTest.MixedEntityThresholdsProduceTheSameSeries: the stored
    counter 6 (wide band) is re-clamped to 3 for the narrow report, then drops to 2."""
    wide = DebounceConfig(
        confirmation_threshold=-4, healing_threshold=6, critical_immediate_confirm=False
    )
    narrow = DebounceConfig(
        confirmation_threshold=-4, healing_threshold=3, critical_immediate_confirm=False
    )
    storage = FaultStorage()
    code = "SHARED_CODE"
    storage.report(code, FAILED, WARN, "dip", "/wide_source", 1000, wide)
    assert (storage.faults[code].counter, storage.faults[code].status) == (-1, "PREFAILED")
    walk = []
    for i in range(7):
        storage.report(code, PASSED, WARN, "", "/wide_source", 1001 + i, wide)
        walk.append((storage.faults[code].counter, storage.faults[code].status))
    assert walk == [(0, "PREFAILED"), *[(n, "PREPASSED") for n in range(1, 7)]]
    storage.report(code, FAILED, WARN, "dip", "/narrow_source", 2000, narrow)
    assert storage.faults[code].status == "PREPASSED"
    assert storage.faults[code].counter == 2
    assert [
        (e.debounce_counter, e.resulting_status, e.confirmation_threshold, e.source_id)
        for e in series(storage, code)
    ] == [(-1, "PREFAILED", -4, "/wide_source"), (2, "PREPASSED", -4, "/narrow_source")]
