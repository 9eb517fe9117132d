"""Ports of upstream's node-level event and service tests (fault-manager.md §4.3: E, M, SC, A).

FaultManager is the node: bag time stands in for the node's wall clock and FaultEvents are read
from its output. Node parameter tests (N-xx) are in test_upstream_node_params.
"""

from __future__ import annotations

import pytest

from medkit_replay.engine.debounce import DebounceConfig
from medkit_replay.engine.manager import FaultManager, FaultManagerConfig
from medkit_replay.engine.queries import list_faults_for_entity, matches_entity
from medkit_replay.engine.timeline import Timeline
from medkit_replay.model import NS_PER_MS, NS_PER_SEC, ClearRequest, FaultEvent, ReportRequest
from tests.engine.upstream_support import (
    CLEARED_EV,
    CONFIRMED_EV,
    CRITICAL,
    ERROR,
    FAILED,
    HEALED_EV,
    NO_EVENTS,
    PASSED,
    UPDATED_EV,
    WARN,
    Case,
    events_of,
    events_since,
    failed,
    passed,
    run_node,
    signatures,
    status_of,
    upstream,
)

S = NS_PER_SEC
T0 = 1_790_000_000 * S  # a 2026 bag time


def report(
    manager: FaultManager,
    t_ns: int,
    code: str,
    severity: int = ERROR,
    source: str = "/test_node",
    description: str = "Test fault",
    event_type: int = FAILED,
) -> bool:
    """One ReportFault request; returns ``accepted``."""
    return manager.report(
        ReportRequest(
            t_ns=t_ns,
            fault_code=code,
            event_type=event_type,
            severity=severity,
            description=description,
            source_id=source,
        )
    )


def since(manager: FaultManager, count: int) -> list[FaultEvent]:
    """Events published after the first ``count``."""
    return events_since(manager, count)


# -- events and services (E-01..E-15) -----------------------------------------------------------


@upstream("E-01")
def test_e01_new_fault_publishes_confirmed_event() -> None:
    """E-01 NewFaultPublishesConfirmedEvent."""
    manager = FaultManager(FaultManagerConfig())
    assert report(manager, T0, "TEST_FAULT_1")
    [event] = events_of(manager)
    assert event.event_type == "fault_confirmed"
    assert event.fault.fault_code == "TEST_FAULT_1"
    assert event.fault.severity == ERROR
    assert event.fault.status == "CONFIRMED"


@upstream("E-02")
def test_e02_update_existing_fault_publishes_updated_event() -> None:
    """E-02 UpdateExistingFaultPublishesUpdatedEvent."""
    manager = FaultManager(FaultManagerConfig())
    assert report(manager, T0, "TEST_FAULT_2", WARN, "/test_node1")
    assert signatures(events_of(manager)) == (CONFIRMED_EV,)
    assert report(manager, T0 + S, "TEST_FAULT_2", ERROR, "/test_node2")
    [event] = since(manager, 1)
    assert event.event_type == "fault_updated"
    assert event.fault.fault_code == "TEST_FAULT_2"
    assert event.fault.occurrence_count == 1
    assert event.fault.severity == ERROR
    assert event.fault.reporting_sources == ("/test_node1", "/test_node2")


@upstream("E-03")
def test_e03_clear_fault_publishes_cleared_event() -> None:
    """E-03 ClearFaultPublishesClearedEvent."""
    manager = FaultManager(FaultManagerConfig())
    report(manager, T0, "TEST_FAULT_3")
    assert signatures(events_of(manager)) == (CONFIRMED_EV,)
    assert manager.clear(ClearRequest(t_ns=T0 + S, fault_code="TEST_FAULT_3"))
    [event] = since(manager, 1)
    assert event.event_type == "fault_cleared"
    assert event.fault.fault_code == "TEST_FAULT_3"
    assert event.fault.status == "CLEARED"
    assert event.auto_cleared_codes == ()


@upstream("E-04")
def test_e04_heal_publishes_cleared_event() -> None:
    """E-04 HealingFaultEventPublishingTest.HealPublishesClearedEventSoStreamConsumersSeeTheEnd:
    conf -1, healing on, heal 1."""
    manager = FaultManager(
        FaultManagerConfig(debounce=DebounceConfig(healing_enabled=True, healing_threshold=1))
    )
    report(manager, T0, "HEAL_ME")
    assert report(manager, T0 + S, "HEAL_ME", event_type=PASSED)
    fault = manager.storage.faults["HEAL_ME"]
    assert (fault.counter, fault.status) == (0, "CONFIRMED")
    assert signatures(since(manager, 1)) == (UPDATED_EV,)
    assert report(manager, T0 + 2 * S, "HEAL_ME", event_type=PASSED)
    assert (fault.counter, fault.status) == (1, "HEALED")
    cleared = [e for e in since(manager, 2) if e.event_type == "fault_cleared"]
    assert len(cleared) == 1
    assert cleared[0].fault.fault_code == "HEAL_ME"
    assert cleared[0].fault.status == "HEALED"


@upstream("E-05")
def test_e05_clear_non_existent_fault_no_event() -> None:
    """E-05 ClearNonExistentFaultNoEvent."""
    manager = FaultManager(FaultManagerConfig())
    assert not manager.clear(ClearRequest(t_ns=T0, fault_code="NON_EXISTENT_FAULT"))
    assert events_of(manager) == []


@upstream("E-06", "E-08")
@pytest.mark.parametrize(
    ("code", "t_ns"),
    [
        pytest.param("TEST_FAULT_4", T0, id="E-06-EventContainsCorrectTimestamp"),
        pytest.param(
            "WALL_CLOCK_TEST", T0 + 123_456_789, id="E-08-TimestampUsesWallClockNotSimTime"
        ),
    ],
)
def test_event_timestamp_is_the_handling_time(code: str, t_ns: int) -> None:
    """E-06 / E-08: the event is stamped with the time the report is handled, which offline is
    the report's bag time (the live node's wall clock); it lies after 2020-01-01."""
    manager = FaultManager(FaultManagerConfig())
    report(manager, t_ns, code, WARN)
    [event] = events_of(manager)
    assert event.t_ns == t_ns
    assert event.t_ns > 1_577_836_800 * S


@upstream("E-07")
def test_e07_event_contains_full_fault_data() -> None:
    """E-07 EventContainsFullFaultData."""
    manager = FaultManager(FaultManagerConfig())
    report(manager, T0, "FULL_DATA_TEST", CRITICAL, "/sensor/temperature")
    [event] = events_of(manager)
    assert event.event_type == "fault_confirmed"
    fault = event.fault
    assert fault.fault_code == "FULL_DATA_TEST"
    assert fault.severity == CRITICAL
    assert fault.description == "Test fault"
    assert fault.status == "CONFIRMED"
    assert fault.occurrence_count == 1
    assert fault.reporting_sources == ("/sensor/temperature",)


def by_code(manager: FaultManager) -> dict[str, object]:
    """GetFault stand-in: every known fault by code."""
    return {fault.fault_code: fault for fault in manager.faults()}


@upstream("E-09")
def test_e09_get_fault_returns_expected_fault() -> None:
    """E-09 GetFaultReturnsExpectedFault."""
    manager = FaultManager(FaultManagerConfig())
    report(manager, T0, "GET_FAULT_TEST")
    [fault] = [f for f in manager.faults() if f.fault_code == "GET_FAULT_TEST"]
    assert (fault.severity, fault.status) == (ERROR, "CONFIRMED")


@upstream("E-10")
def test_e10_get_fault_not_found_for_missing_fault() -> None:
    """E-10 GetFaultReturnsNotFoundForMissingFault, state part: the code is unknown (the
    "Fault not found" text is the service's)."""
    manager = FaultManager(FaultManagerConfig())
    report(manager, T0, "OTHER_FAULT")
    assert "NON_EXISTENT_FAULT" not in by_code(manager)


@upstream("E-11")
def test_e11_get_fault_environment_data() -> None:
    """E-11 GetFaultReturnsEnvironmentData, state part: the fault is found (snapshots are not
    modelled)."""
    manager = FaultManager(FaultManagerConfig())
    report(manager, T0, "ENV_DATA_TEST", WARN, "/sensor/temp")
    assert "ENV_DATA_TEST" in by_code(manager)


@upstream("E-12")
def test_e12_extended_data_records() -> None:
    """E-12 GetFaultReturnsExtendedDataRecords: first/last occurrence are the report times."""
    manager = FaultManager(FaultManagerConfig())
    report(manager, T0, "EDR_TEST", ERROR, "/node1")
    report(manager, T0 + S, "EDR_TEST", ERROR, "/node2")
    assert signatures(events_of(manager)) == (CONFIRMED_EV, UPDATED_EV)
    [fault] = manager.faults()
    assert (fault.first_occurred_ns, fault.last_occurred_ns) == (T0, T0 + S)


@upstream("E-13")
def test_e13_list_faults_for_entity_success() -> None:
    """E-13 ListFaultsForEntitySuccess."""
    manager = FaultManager(FaultManagerConfig())
    report(manager, T0, "MOTOR_FAULT", ERROR, "/powertrain/motor_controller")
    report(manager, T0 + S, "SENSOR_FAULT", WARN, "/powertrain/motor_controller")
    report(manager, T0 + 2 * S, "BRAKE_FAULT", ERROR, "/chassis/brake_system")
    assert len(manager.output.events) >= 3
    snapshots = list_faults_for_entity(manager.faults(), "motor_controller")
    records = list_faults_for_entity(manager.storage.faults.values(), "motor_controller")
    assert snapshots.success
    assert records.success
    assert [f.fault_code for f in snapshots.faults] == ["MOTOR_FAULT", "SENSOR_FAULT"]
    assert [f.fault_code for f in records.faults] == ["MOTOR_FAULT", "SENSOR_FAULT"]


@upstream("E-14")
def test_e14_list_faults_for_entity_empty_result() -> None:
    """E-14 ListFaultsForEntityEmptyResult."""
    manager = FaultManager(FaultManagerConfig())
    report(manager, T0, "SOME_FAULT", ERROR, "/some/other_entity")
    result = list_faults_for_entity(manager.faults(), "motor_controller")
    assert result.success
    assert result.faults == ()


@upstream("E-15")
def test_e15_list_faults_for_entity_with_empty_id() -> None:
    """E-15 ListFaultsForEntityWithEmptyId."""
    manager = FaultManager(FaultManagerConfig())
    report(manager, T0, "SOME_FAULT", ERROR, "/")
    result = list_faults_for_entity(manager.faults(), "")
    assert not result.success
    assert result.error_message == "entity_id cannot be empty"
    assert result.faults == ()


@upstream("E-13")
def test_e13_list_faults_for_entity_keeps_any_status() -> None:
    """§1.10 (used by E-13): ListFaultsForEntity returns faults in any status, CLEARED too."""
    manager = FaultManager(FaultManagerConfig())
    report(manager, T0, "MOTOR_FAULT", ERROR, "/powertrain/motor_controller")
    manager.clear(ClearRequest(t_ns=T0 + S, fault_code="MOTOR_FAULT"))
    [fault] = list_faults_for_entity(manager.faults(), "motor_controller").faults
    assert fault.status == "CLEARED"


MOTOR_FQN = "/powertrain/motor_controller"
MULTI = ("/chassis/brake_system", MOTOR_FQN, "/sensor/temperature")


@upstream("M-01", "M-02", "M-03", "M-04", "M-05")
@pytest.mark.parametrize(
    ("sources", "entity_id", "expected"),
    [
        pytest.param(("motor_controller",), "motor_controller", True, id="M-01-ExactMatch"),
        pytest.param(("motor_controller",), "other", False, id="M-01-ExactMatch-other"),
        pytest.param((MOTOR_FQN,), "motor_controller", True, id="M-02-FQNSuffixMatch"),
        pytest.param((MOTOR_FQN,), "powertrain", False, id="M-02-FQNSuffixMatch-namespace"),
        pytest.param((MOTOR_FQN,), "controller", False, id="M-02-FQNSuffixMatch-partial"),
        pytest.param(
            ("/perception/lidar/front_sensor",), "front_sensor", True, id="M-03-Hierarchical"
        ),
        pytest.param(("/perception/lidar/front_sensor",), "lidar", False, id="M-03-mid-segment"),
        pytest.param(("/perception/lidar/front_sensor",), "perception", False, id="M-03-root"),
        pytest.param(MULTI, "brake_system", True, id="M-04-MultipleSources-brake"),
        pytest.param(MULTI, "motor_controller", True, id="M-04-MultipleSources-motor"),
        pytest.param(MULTI, "temperature", True, id="M-04-MultipleSources-temperature"),
        pytest.param(MULTI, "unknown", False, id="M-04-MultipleSources-unknown"),
        pytest.param((), "motor_controller", False, id="M-05-EmptySources"),
    ],
)
def test_matches_entity(sources: tuple[str, ...], entity_id: str, expected: bool) -> None:
    """MatchesEntityTest.*: equal, or ending with '/' + entity_id."""
    assert matches_entity(sources, entity_id) is expected


# -- snapshot cooldown and audit scenarios: their state-machine part ----------------------------

HEAL1 = DebounceConfig(healing_enabled=True, healing_threshold=1)
HEAL1_NODE = FaultManagerConfig(debounce=HEAL1)

STATE_CASES: tuple[Case, ...] = (
    Case(
        sid="SC-01",
        name="SnapshotCooldownTest.CooldownPreventsRapidRecapture",
        config=HEAL1,
        steps=(
            failed(
                "COOLDOWN_TEST",
                CRITICAL,
                "/test",
                "Test",
                status="CONFIRMED",
                events=(CONFIRMED_EV,),
            ),
            passed("COOLDOWN_TEST", "/test", status="CONFIRMED", ctr=0, events=(UPDATED_EV,)),
            failed(
                "COOLDOWN_TEST", CRITICAL, "/test", "Test", status="CONFIRMED", events=(UPDATED_EV,)
            ),
            passed(
                "COOLDOWN_TEST",
                "/test",
                t_ns=10 * S,
                status="CONFIRMED",
                ctr=0,
                events=(UPDATED_EV,),
            ),
            failed(
                "COOLDOWN_TEST", CRITICAL, "/test", "Test", status="CONFIRMED", events=(UPDATED_EV,)
            ),
        ),
    ),
    Case(
        sid="A-01",
        name="FaultAuditIntegrationTest.TransitionsAppendVerifiableChain",
        config=HEAL1,
        steps=(
            failed(
                "AUDIT_FAULT",
                CRITICAL,
                "/plc/pump",
                "overpressure",
                status="CONFIRMED",
                events=(CONFIRMED_EV,),
            ),
        ),
    ),
    Case(
        sid="A-02",
        name="FaultAuditIntegrationTest.AutoHealAppendsHealedRow",
        config=HEAL1,
        steps=(
            failed(
                "HEAL_FAULT",
                ERROR,
                "/robot/sensor",
                "intermittent sensor",
                ctr=-1,
                status="CONFIRMED",
                events=(CONFIRMED_EV,),
            ),
            passed(
                "HEAL_FAULT",
                "/robot/sensor",
                ERROR,
                "intermittent sensor",
                ctr=0,
                status="CONFIRMED",
                events=(UPDATED_EV,),
            ),
            passed(
                "HEAL_FAULT",
                "/robot/sensor",
                ERROR,
                "intermittent sensor",
                ctr=1,
                status="HEALED",
                events=(HEALED_EV,),
            ),
            *(
                passed(
                    "HEAL_FAULT",
                    "/robot/sensor",
                    ERROR,
                    "intermittent sensor",
                    ctr=1,
                    status="HEALED",
                    events=NO_EVENTS,
                    stored_description="intermittent sensor",
                )
                for _ in range(2)
            ),
        ),
    ),
    Case(
        sid="A-03",
        name="FaultAuditIntegrationTest.ConfirmedLatchNoDuplicateConfirmedRows",
        config=HEAL1,
        steps=(
            failed(
                "LATCH_FAULT",
                ERROR,
                "/robot/sensor",
                "flapping sensor",
                status="CONFIRMED",
                events=(CONFIRMED_EV,),
            ),
            passed("LATCH_FAULT", "/robot/sensor", ERROR, ctr=0, events=(UPDATED_EV,)),
            failed(
                "LATCH_FAULT",
                ERROR,
                "/robot/sensor",
                "flapping sensor",
                ctr=-1,
                status="CONFIRMED",
                events=(UPDATED_EV,),
            ),
        ),
    ),
    Case(
        sid="A-04",
        name="FaultAuditSingleEventHealTest.SinglePassedHealAuditedOnce",
        config=DebounceConfig(healing_enabled=True, healing_threshold=0),
        steps=(
            failed(
                "FAST_HEAL",
                ERROR,
                "/robot/imu",
                "transient glitch",
                status="CONFIRMED",
                events=(CONFIRMED_EV,),
            ),
            passed("FAST_HEAL", "/robot/imu", ERROR, ctr=0, status="HEALED", events=(HEALED_EV,)),
            passed("FAST_HEAL", "/robot/imu", ERROR, ctr=0, status="HEALED", events=NO_EVENTS),
        ),
    ),
    Case(
        sid="A-07",
        name="FaultAuditStartupReclassifyTest.StartupReclassifyAppendsClearedRow",
        # Seed part only: the restart reclassification HEALED→CLEARED needs persisted state.
        config=DebounceConfig(healing_enabled=True, healing_threshold=3),
        steps=(
            failed("STALE_HEALED", ERROR, "/robot/src", "stale", events=(CONFIRMED_EV,)),
            *(passed("STALE_HEALED", "/robot/src") for _ in range(3)),
            passed("STALE_HEALED", "/robot/src", status="HEALED", events=(HEALED_EV,)),
        ),
    ),
)


@upstream(*(case.sid for case in STATE_CASES), "A-08")
@pytest.mark.parametrize("case", STATE_CASES, ids=[case.test_id for case in STATE_CASES])
def test_node_state_scenario(case: Case) -> None:
    """SC-01, A-01..A-04, A-07/A-08 (same seed): statuses, counters and FaultEvents per step."""
    run_node(case)


AUDIT_ROWS: dict[str, tuple[tuple[str, str], ...]] = {
    # Audit rows derive from transitions: occurred (created), confirmed, healed, cleared.
    "A-01": (("occurred", "/plc/pump"), ("confirmed", "/plc/pump"), ("cleared", "")),
    "A-02": (("occurred", "/robot/sensor"), ("confirmed", "/robot/sensor"), ("healed", "")),
    "A-03": (("occurred", "/robot/sensor"), ("confirmed", "/robot/sensor")),
    "A-04": (("occurred", "/robot/imu"), ("confirmed", "/robot/imu"), ("healed", "")),
}


@upstream("A-01", "A-02", "A-03", "A-04")
@pytest.mark.parametrize("sid", sorted(AUDIT_ROWS))
def test_audit_rows_from_transitions(sid: str) -> None:
    """A-01..A-04: the transitions behind the audit rows upstream asserts (one `confirmed`
    even when the latch is crossed again; `healed` once; A-01 ends with its clear)."""
    [case] = [c for c in STATE_CASES if c.sid == sid]
    manager = run_node(case)
    if sid == "A-01":
        assert manager.clear(ClearRequest(t_ns=100 * S, fault_code="AUDIT_FAULT"))
        assert signatures(events_of(manager)) == (CONFIRMED_EV, CLEARED_EV)
    rows: list[tuple[str, str]] = []
    for tr in manager.output.transitions:
        if tr.from_status is None:
            rows.append(("occurred", tr.source_id or ""))
        names = {"CONFIRMED": "confirmed", "HEALED": "healed", "CLEARED": "cleared"}
        if tr.to_status in names:
            source = (tr.source_id or "") if tr.to_status == "CONFIRMED" else ""
            rows.append((names[tr.to_status], source))
    assert tuple(rows) == AUDIT_ROWS[sid]


@upstream("A-06")
def test_a06_timer_confirmation() -> None:
    """A-06 FaultAuditTimerTest.TimerConfirmationAppendsConfirmedAuditRow: conf -3, auto 0.2 s;
    the PREFAILED fault is confirmed by the first 1 s tick, with no FaultEvent."""
    manager = FaultManager(
        FaultManagerConfig(
            debounce=DebounceConfig(confirmation_threshold=-3),
            auto_confirm_after_ns=200 * NS_PER_MS,
        )
    )
    timeline = Timeline(manager)
    timeline.advance(T0)
    timeline.apply(
        ReportRequest(
            t_ns=T0,
            fault_code="AUTO_CONF_1",
            event_type=FAILED,
            severity=ERROR,
            description="stuck",
            source_id="/robot/src",
        )
    )
    assert status_of(manager, "AUTO_CONF_1") == "PREFAILED"
    timeline.advance(T0 + 5 * S)
    assert status_of(manager, "AUTO_CONF_1") == "CONFIRMED"
    confirmations = [t for t in manager.output.transitions if t.to_status == "CONFIRMED"]
    assert [(t.cause, t.t_ns) for t in confirmations] == [("auto_confirm", T0 + S)]
    assert events_of(manager) == []
