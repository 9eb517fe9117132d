"""Ports of upstream's SQLite-only storage scenarios (fault-manager.md §4.5, SQ-01..SQ-13).

medkit-replay has no SQLite backend: "reopen" is modelled as carrying on with the same storage,
database pokes as direct edits of the record, and confirmed_at_ns as the time of the fault's
last transition into CONFIRMED in FaultManager.output.transitions.
"""

from __future__ import annotations

import pytest

from medkit_replay.engine.debounce import DebounceConfig
from medkit_replay.engine.manager import FaultManager, FaultManagerConfig
from medkit_replay.model import NS_PER_SEC, ReportRequest
from tests.engine.upstream_support import (
    CONFIRMED_EV,
    ERROR,
    HEALED_EV,
    INFO,
    NO_EVENTS,
    UPDATED_EV,
    WARN,
    Case,
    clear,
    events_of,
    events_since,
    failed,
    passed,
    query,
    run_node,
    run_storage,
    status_of,
    upstream,
)

S = NS_PER_SEC
ALL_STATUSES = ("PREFAILED", "PREPASSED", "CONFIRMED", "HEALED", "CLEARED")

CASES: tuple[Case, ...] = (
    Case(
        sid="SQ-01",
        name="ReopenRepairsLastOccurredInflatedByOldPassedBug",
        # State part: a PASSED never moves last_occurred (the old bug the repair undoes).
        steps=(
            failed("FAULT_MIG", ERROR, "/node1", t_ns=1000 * S, last_ns=1000 * S),
            passed("FAULT_MIG", "/node1", t_ns=9000 * S, last_ns=1000 * S, last_passed_ns=9000 * S),
        ),
    ),
    Case(
        sid="SQ-02",
        name="PersistenceAcrossRestarts",
        steps=(
            failed("FAULT_1", ERROR, "/node1", "Persistent fault 1"),
            failed("FAULT_2", WARN, "/node2", "Persistent fault 2"),
            clear("FAULT_2", returns=True, size=2),
            # "reopen": the same storage carries on.
            query(
                ALL_STATUSES,
                code="FAULT_1",
                listed=("FAULT_1", "FAULT_2"),
                size=2,
                stored_severity=ERROR,
                status="CONFIRMED",
                stored_description="Persistent fault 1",
            ),
            query(ALL_STATUSES, code="FAULT_2", status="CLEARED"),
        ),
    ),
    Case(
        sid="SQ-03",
        name="TimestampPrecision",
        steps=(
            failed(
                "FAULT_TS",
                INFO,
                "/node1",
                t_ns=1735312456123456789,
                first_ns=1735312456123456789,
                last_ns=1735312456123456789,
            ),
        ),
    ),
    Case(
        sid="SQ-04",
        name="SqliteInMemoryTest.InMemoryDatabase",
        steps=(failed("MEM_FAULT", WARN, "/test", size=1, status="CONFIRMED"),),
    ),
    Case(
        sid="SQ-05",
        name="ReportingSourcesJsonHandling",
        steps=(
            failed("MULTI_SRC", ERROR, "/node/path/with/slashes"),
            failed("MULTI_SRC", ERROR, "/another/node"),
            failed(
                "MULTI_SRC",
                ERROR,
                '/special"chars',
                sources=("/another/node", "/node/path/with/slashes", '/special"chars'),
            ),
        ),
    ),
    Case(
        sid="SQ-06",
        name="ConfirmationPersistsAfterReopen",
        steps=(
            failed("FAULT_1", ERROR, "/node1"),
            failed("FAULT_1", ERROR, "/node2"),
            failed("FAULT_1", ERROR, "/node3"),
            query(ALL_STATUSES, code="FAULT_1", status="CONFIRMED"),
        ),
    ),
    Case(
        sid="SQ-07",
        name="ConfirmedFaultSurvivesHealHeartbeat",
        steps=(
            failed("FAULT_1", ERROR, "/node1", status="CONFIRMED", events=(CONFIRMED_EV,)),
            *(
                passed("FAULT_1", "/node1", status="CONFIRMED", ctr=min(i, 3), events=(UPDATED_EV,))
                for i in range(20)
            ),
            failed("FAULT_1", ERROR, "/node1", status="CONFIRMED", ctr=2, events=(UPDATED_EV,)),
        ),
    ),
    Case(
        sid="SQ-13",
        name="SnapshotsRetainedThroughHealedReclassification",
        # State part only (snapshots and reclassification are not modelled).
        config=DebounceConfig(healing_enabled=True, healing_threshold=1),
        steps=(
            failed("FAULT_1", ERROR, "/node1", status="CONFIRMED", events=(CONFIRMED_EV,)),
            passed("FAULT_1", "/node1", status="CONFIRMED", ctr=0, events=(UPDATED_EV,)),
            passed("FAULT_1", "/node1", status="HEALED", ctr=1, events=(HEALED_EV,)),
        ),
    ),
)


@upstream(*(case.sid for case in CASES))
@pytest.mark.parametrize("case", CASES, ids=[case.test_id for case in CASES])
def test_sqlite_scenario(case: Case) -> None:
    """Storage layer state after every step."""
    run_storage(case)


@upstream(*(case.sid for case in CASES))
@pytest.mark.parametrize("case", CASES, ids=[case.test_id for case in CASES])
def test_sqlite_scenario_node_events(case: Case) -> None:
    """Through FaultManager: same state, and the FaultEvents of each step."""
    run_node(case)


def _failed(manager: FaultManager, code: str, t_ns: int) -> None:
    assert manager.report(
        ReportRequest(t_ns=t_ns, fault_code=code, event_type=0, severity=ERROR, source_id="/node1")
    )


def confirmed_at(manager: FaultManager, code: str) -> int:
    """confirmed_at_ns: time of the last transition into CONFIRMED, 0 if there is none."""
    times = [
        tr.t_ns
        for tr in manager.output.transitions
        if tr.fault_code == code and tr.to_status == "CONFIRMED"
    ]
    return times[-1] if times else 0


@upstream("SQ-08")
def test_sq08_runaway_counter_from_old_db_recovers() -> None:
    """SQ-08 RunawayCounterFromOldDbRecovers: a stored counter of 100000 (status PREPASSED) is
    re-clamped to heal 3 on first touch; FAILED then walks 2, 1, 0 (PREPASSED) and -1 confirms.
    """
    manager = FaultManager(FaultManagerConfig())
    _failed(manager, "FAULT_1", 1 * S)
    fault = manager.storage.faults["FAULT_1"]
    assert fault.status == "CONFIRMED"
    fault.counter = 100000  # the database poke
    fault.status = "PREPASSED"
    expected = [(2, "PREPASSED", NO_EVENTS), (1, "PREPASSED", NO_EVENTS)]
    expected += [(0, "PREPASSED", NO_EVENTS), (-1, "CONFIRMED", (CONFIRMED_EV,))]
    for i, (ctr, status, events) in enumerate(expected):
        before = len(manager.output.events)
        _failed(manager, "FAULT_1", (2 + i) * S)
        assert (fault.counter, fault.status) == (ctr, status), i
        emitted = events_since(manager, before)
        assert tuple((e.event_type, e.fault.status) for e in emitted) == events, i


@upstream("SQ-09")
def test_sq09_confirmed_at_recorded_on_immediate_confirmation() -> None:
    """SQ-09 ConfirmedAtRecordedOnImmediateConfirmation: set at t, unchanged by a later FAILED."""
    manager = FaultManager(FaultManagerConfig())
    t = 1000 * S
    _failed(manager, "FAULT_1", t)
    assert status_of(manager, "FAULT_1") == "CONFIRMED"
    assert confirmed_at(manager, "FAULT_1") == t
    _failed(manager, "FAULT_1", t + 5 * S)
    assert confirmed_at(manager, "FAULT_1") == t


@upstream("SQ-10")
def test_sq10_confirmed_at_recorded_on_debounced_confirmation() -> None:
    """SQ-10 ConfirmedAtRecordedOnDebouncedConfirmation: conf -2 → 0, then t1 + 1 s."""
    manager = FaultManager(FaultManagerConfig(debounce=DebounceConfig(confirmation_threshold=-2)))
    t1 = 1000 * S
    _failed(manager, "FAULT_1", t1)
    assert status_of(manager, "FAULT_1") == "PREFAILED"
    assert confirmed_at(manager, "FAULT_1") == 0
    _failed(manager, "FAULT_1", t1 + S)
    assert status_of(manager, "FAULT_1") == "CONFIRMED"
    assert confirmed_at(manager, "FAULT_1") == t1 + S


@upstream("SQ-11")
def test_sq11_confirmed_at_recorded_on_time_based_confirmation() -> None:
    """SQ-11 ConfirmedAtRecordedOnTimeBasedConfirmation: conf -3, auto 10 s; check at now+15 s."""
    manager = FaultManager(
        FaultManagerConfig(
            debounce=DebounceConfig(confirmation_threshold=-3), auto_confirm_after_ns=10 * S
        )
    )
    now = 1000 * S
    _failed(manager, "FAULT_1", now)
    assert manager.auto_confirm_tick(now + 15 * S) == ["FAULT_1"]
    assert confirmed_at(manager, "FAULT_1") == now + 15 * S
    assert events_of(manager) == []


@upstream("SQ-12")
def test_sq12_confirmed_at_for_new_confirmation() -> None:
    """SQ-12 ConfirmedAtColumnMigratedIntoOldDatabase, state part: a new FAILED at t (defaults)
    records confirmed_at t. (The schema migration itself is SQLite-only.)"""
    manager = FaultManager(FaultManagerConfig())
    assert confirmed_at(manager, "FAULT_NEW") == 0
    _failed(manager, "FAULT_NEW", 77 * S)
    assert confirmed_at(manager, "FAULT_NEW") == 77 * S
