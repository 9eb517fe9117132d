"""Ports of upstream's service-level integration tests (fault-manager.md §4.7: I-xx, RI-02..04).

Upstream's I-tests share one node (conf -3, correlation from test_correlation.yaml) and run in
order; here the test for step k replays steps 1..k on a fresh node driven through a Timeline,
so each runs alone. Snapshot steps (I-16..I-20) are not ported (see test_upstream_coverage).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import pytest

from medkit_replay.engine.correlation import CorrelationConfig, CorrelationRule, Representative
from medkit_replay.engine.debounce import DebounceConfig
from medkit_replay.engine.manager import FaultManager, FaultManagerConfig
from medkit_replay.engine.queries import list_faults
from medkit_replay.engine.timeline import Timeline
from medkit_replay.model import (
    NS_PER_MS,
    NS_PER_SEC,
    ClearRequest,
    FaultEvent,
    FaultSnapshot,
    ReportRequest,
)
from tests.engine.upstream_support import (
    CONFIRMED_EV,
    CRITICAL,
    ERROR,
    FAILED,
    INFO,
    NO_EVENTS,
    PASSED,
    UPDATED_EV,
    WARN,
    Case,
    events_of,
    events_since,
    failed,
    run_node,
    signatures,
    upstream,
)

if TYPE_CHECKING:
    from collections.abc import Callable

S = NS_PER_SEC

TEST_CORRELATION = CorrelationConfig(
    enabled=True,
    default_window_ms=500,
    patterns={
        "drive_faults": ("DRIVE_*",),
        "motor_errors": ("MOTOR_COMM_*", "MOTOR_TIMEOUT_*"),
        "sensor_errors": ("SENSOR_*",),
    },
    rules=(
        CorrelationRule(
            id="estop_cascade",
            name="E-Stop Cascade",
            mode="hierarchical",
            root_cause_codes=("ESTOP_001",),
            symptom_pattern_ids=("motor_errors", "drive_faults"),
            window_ms=2000,
            mute_symptoms=True,
            auto_clear_with_root=True,
        ),
        CorrelationRule(
            id="sensor_storm",
            name="Sensor Storm",
            mode="auto_cluster",
            match_pattern_ids=("sensor_errors",),
            min_count=2,
            window_ms=2000,
            show_as_single=True,
            representative=Representative.HIGHEST_SEVERITY,
        ),
    ),
)


@dataclass
class Node:
    """The shared fault_manager of the I-tests, with a bag clock advancing 1 s per request."""

    manager: FaultManager = field(
        default_factory=lambda: FaultManager(
            FaultManagerConfig(
                debounce=DebounceConfig(confirmation_threshold=-3), correlation=TEST_CORRELATION
            )
        )
    )
    now: int = 1_000 * S
    timeline: Timeline = field(init=False)

    def __post_init__(self) -> None:
        self.timeline = Timeline(self.manager)

    def report(
        self,
        code: str,
        severity: int = ERROR,
        source: str = "/test_node",
        description: str = "Test fault",
        event_type: int = FAILED,
        gap_ns: int = S,
    ) -> tuple[bool, list[FaultEvent]]:
        """One ReportFault call ``gap_ns`` after the previous one: (accepted, its events)."""
        self.now += gap_ns
        self.timeline.advance(self.now)
        before = len(self.manager.output.events)
        accepted = self.manager.report(
            ReportRequest(
                t_ns=self.now,
                fault_code=code,
                event_type=event_type,
                severity=severity,
                description=description,
                source_id=source,
            )
        )
        return accepted, events_since(self.manager, before)

    def clear(self, code: str) -> tuple[bool, str, tuple[str, ...]]:
        """One ClearFault call: (success, message, auto_cleared_codes)."""
        self.now += S
        self.timeline.advance(self.now)
        success = self.manager.clear(ClearRequest(t_ns=self.now, fault_code=code))
        record = self.manager.output.clears[-1]
        return success, record.message, record.auto_cleared_codes

    def listed(self, statuses: list[str], severity: int | None = None) -> list[FaultSnapshot]:
        """ListFaults over the current faults."""
        return list_faults(self.manager.faults(), statuses, severity is not None, severity or 0)

    def fault(self, code: str) -> FaultSnapshot:
        """The current state of one fault."""
        [found] = [f for f in self.manager.faults() if f.fault_code == code]
        return found


def i01(node: Node) -> None:
    """test_01_report_fault_success."""
    accepted, events = node.report("TEST_FAULT_001", description="Test fault from integration")
    assert accepted
    assert node.fault("TEST_FAULT_001").status == "PREFAILED"
    assert events == []


def i02(node: Node) -> None:
    """test_02_report_fault_empty_code_fails."""
    assert node.report("")[0] is False


def i03(node: Node) -> None:
    """test_03_report_fault_empty_source_fails."""
    assert node.report("TEST_FAULT_002", source="")[0] is False
    assert all(f.fault_code != "TEST_FAULT_002" for f in node.manager.faults())


def i04(node: Node) -> None:
    """test_04_report_fault_invalid_severity_fails."""
    assert node.report("TEST_FAULT_003", severity=99)[0] is False
    assert node.manager.output.reports[-1].reject_reason == "invalid severity 99 for FAILED event"


def i05(node: Node) -> None:
    """test_05_list_faults_prefailed."""
    node.report("TEST_FAULT_GET_001", WARN, description="Fault for get test")
    assert "TEST_FAULT_GET_001" in [f.fault_code for f in node.listed(["PREFAILED"])]


def i06(node: Node) -> None:
    """test_06_list_faults_filter_by_severity."""
    node.report("TEST_FAULT_SEV_0", INFO)
    node.report("TEST_FAULT_SEV_1", ERROR)
    listed = node.listed(["PREFAILED"], severity=ERROR)
    assert listed
    assert all(f.severity == ERROR for f in listed)
    assert "TEST_FAULT_SEV_1" in [f.fault_code for f in listed]
    assert "TEST_FAULT_SEV_0" not in [f.fault_code for f in listed]


def i07(node: Node) -> None:
    """test_07_clear_fault_success: a PREFAILED fault can be cleared."""
    node.report("TEST_FAULT_CLEAR", description="Fault to be cleared")
    assert node.fault("TEST_FAULT_CLEAR").status == "PREFAILED"
    success, message, _ = node.clear("TEST_FAULT_CLEAR")
    assert success
    assert "cleared" in message.lower()
    assert "TEST_FAULT_CLEAR" in [f.fault_code for f in node.listed(["CLEARED"])]


def i08(node: Node) -> None:
    """test_08_clear_nonexistent_fault_fails."""
    success, message, _ = node.clear("NONEXISTENT_FAULT_XYZ")
    assert not success
    assert "not found" in message.lower()


def i09(node: Node) -> None:
    """test_09_clear_fault_empty_code_fails."""
    success, message, _ = node.clear("")
    assert not success
    assert "empty" in message.lower()


def i10(node: Node) -> None:
    """test_10_report_updates_existing_fault: one record aggregates both sources."""
    assert node.report("TEST_FAULT_UPDATE", WARN, "/node1", "First report")[0]
    assert node.report("TEST_FAULT_UPDATE", ERROR, "/node2", "Second report")[0]
    assert "TEST_FAULT_UPDATE" in [f.fault_code for f in node.listed(["PREFAILED"])]
    fault = node.fault("TEST_FAULT_UPDATE")
    assert fault.severity == ERROR
    assert fault.occurrence_count == 1
    assert fault.reporting_sources == ("/node1", "/node2")


def i11(node: Node) -> None:
    """test_11_confirmation_workflow: events none, none, fault_confirmed."""
    per_report = [
        signatures(node.report("TEST_FAULT_CONFIRM", ERROR, f"/node{i}")[1]) for i in (1, 2, 3)
    ]
    assert per_report == [NO_EVENTS, NO_EVENTS, (CONFIRMED_EV,)]
    assert "TEST_FAULT_CONFIRM" in [f.fault_code for f in node.listed(["CONFIRMED"])]
    fault = node.fault("TEST_FAULT_CONFIRM")
    assert (fault.status, fault.occurrence_count) == ("CONFIRMED", 1)


def i12(node: Node) -> None:
    """test_12_prefailed_excluded_from_default_query."""
    node.report("TEST_FAULT_PREFAILED_ONLY", WARN)
    assert "TEST_FAULT_PREFAILED_ONLY" not in [f.fault_code for f in node.listed([])]
    assert "TEST_FAULT_PREFAILED_ONLY" in [f.fault_code for f in node.listed(["PREFAILED"])]


def i13(node: Node) -> None:
    """test_13_multi_source_confirmation."""
    for source in ("/sensor1", "/sensor2", "/sensor3"):
        node.report("TEST_FAULT_MULTI_SRC", ERROR, source)
    fault = node.fault("TEST_FAULT_MULTI_SRC")
    assert fault.status == "CONFIRMED"
    assert len(fault.reporting_sources) == 3
    assert fault.occurrence_count == 1


def i14(node: Node) -> None:
    """test_14_critical_severity_immediate_confirmation."""
    _, events = node.report("TEST_FAULT_CRITICAL", CRITICAL)
    fault = node.fault("TEST_FAULT_CRITICAL")
    assert (fault.status, fault.occurrence_count) == ("CONFIRMED", 1)
    assert signatures(events) == (CONFIRMED_EV,)


def i15(node: Node) -> None:
    """test_15_passed_event_increments_counter: counter -2 → -1 → 0 → +1."""
    node.report("TEST_FAULT_PASSED", ERROR, "/node1")
    node.report("TEST_FAULT_PASSED", ERROR, "/node2")
    assert node.fault("TEST_FAULT_PASSED").status == "PREFAILED"
    counters = []
    for _ in range(3):
        node.report("TEST_FAULT_PASSED", 0, "/test_node", "", event_type=PASSED)
        counters.append(node.manager.storage.faults["TEST_FAULT_PASSED"].counter)
    assert counters == [-1, 0, 1]
    assert node.fault("TEST_FAULT_PASSED").status == "PREPASSED"


def i21(node: Node) -> None:
    """test_21_correlation_hierarchical_root_cause."""
    _, events = node.report("ESTOP_001", CRITICAL, "/estop_node")
    assert node.fault("ESTOP_001").status == "CONFIRMED"
    assert signatures(events) == (CONFIRMED_EV,)


SYMPTOMS = ("MOTOR_COMM_FL", "MOTOR_COMM_FR", "DRIVE_FAULT_1")


def i22(node: Node) -> None:
    """test_22_correlation_symptoms_muted: symptoms within the root's 2 s window are muted (no
    confirmed event) but their state still changes."""
    _, events = node.report("ESTOP_001", CRITICAL, "/estop_node")
    assert signatures(events) == (UPDATED_EV,)
    for code in SYMPTOMS:
        accepted, events = node.report(code, CRITICAL, "/motor_node", gap_ns=10 * NS_PER_MS)
        assert accepted
        assert events == []
        assert node.fault(code).status == "CONFIRMED"
        assert node.fault(code).muted
    correlation = node.manager.correlation
    assert correlation is not None
    assert correlation.muted_count > 0
    muted = {m.fault_code: m for m in correlation.muted_faults()}
    for code in SYMPTOMS:
        assert (muted[code].root_cause_code, muted[code].rule_id) == ("ESTOP_001", "estop_cascade")


def i23(node: Node) -> None:
    """test_23_correlation_auto_clear_with_root."""
    success, _, auto_cleared = node.clear("ESTOP_001")
    assert success
    assert auto_cleared
    assert set(auto_cleared) == set(SYMPTOMS)
    correlation = node.manager.correlation
    assert correlation is not None
    assert [m for m in correlation.muted_faults() if m.root_cause_code == "ESTOP_001"] == []
    assert all(node.fault(code).status == "CLEARED" for code in SYMPTOMS)
    [event] = events_of(node.manager)[-1:]
    assert (event.event_type, event.fault.fault_code) == ("fault_cleared", "ESTOP_001")
    assert set(event.auto_cleared_codes) == set(SYMPTOMS)


def i24(node: Node) -> None:
    """test_24_correlation_auto_cluster: two SENSOR_* CRITICAL reports 0.1 s apart."""
    _, first = node.report("SENSOR_LIDAR_FAIL", CRITICAL, "/sensor_node")
    _, second = node.report("SENSOR_IMU_TIMEOUT", CRITICAL, "/sensor_node", gap_ns=100 * NS_PER_MS)
    correlation = node.manager.correlation
    assert correlation is not None
    assert correlation.cluster_count > 0
    [cluster] = correlation.clusters()
    assert cluster.rule_id == "sensor_storm"
    assert cluster.count >= 2
    # show_as_single: the representative (first, equal severity) shows, the other is muted.
    assert cluster.representative_code == "SENSOR_LIDAR_FAIL"
    assert signatures(first) == (CONFIRMED_EV,)
    assert second == []


def i26(node: Node) -> None:
    """test_26_cleared_fault_can_be_reactivated."""
    node.report("TEST_REACTIVATION", CRITICAL, "/node1")
    node.clear("TEST_REACTIVATION")
    node.report("TEST_REACTIVATION", CRITICAL, "/node2")
    fault = node.fault("TEST_REACTIVATION")
    assert fault.status == "CONFIRMED"
    assert fault.occurrence_count == 2
    assert len(fault.reporting_sources) == 2


def i27(node: Node) -> None:
    """test_27_capture_pool_bounds_fault_storm, state part: 12 distinct CRITICAL faults are all
    accepted and confirmed (the capture-queue overflow is not modelled)."""
    codes = [f"STORM_FAULT_{i:02d}" for i in range(12)]
    for code in codes:
        assert node.report(code, CRITICAL, "/storm_node", gap_ns=NS_PER_MS)[0]
    confirmed = {f.fault_code for f in node.listed(["CONFIRMED"])}
    assert set(codes) <= confirmed


SEQUENCE: list[tuple[str, Callable[[Node], None]]] = [
    ("I-01", i01),
    ("I-02", i02),
    ("I-03", i03),
    ("I-04", i04),
    ("I-05", i05),
    ("I-06", i06),
    ("I-07", i07),
    ("I-08", i08),
    ("I-09", i09),
    ("I-10", i10),
    ("I-11", i11),
    ("I-12", i12),
    ("I-13", i13),
    ("I-14", i14),
    ("I-15", i15),
    ("I-21", i21),
    ("I-22", i22),
    ("I-23", i23),
    ("I-24", i24),
    ("I-26", i26),
    ("I-27", i27),
]


def _test_id(sid: str, step: Callable[[Node], None]) -> str:
    """``I-07-test_07_clear_fault_success``: scenario ID and upstream test name."""
    match = re.match(r"test_\d+_\w+", step.__doc__ or "")
    assert match is not None, sid
    return f"{sid}-{match.group(0)}"


@upstream(*(sid for sid, _ in SEQUENCE))
@pytest.mark.parametrize("index", range(len(SEQUENCE)), ids=[_test_id(s, f) for s, f in SEQUENCE])
def test_integration_sequence(index: int) -> None:
    """Replay upstream's shared-node sequence up to this test, then check it."""
    node = Node()
    for _, step in SEQUENCE[: index + 1]:
        step(node)


RI_CASES: tuple[Case, ...] = (
    Case(
        sid="RI-02",
        name="test_02_report_fault_is_stored",
        steps=(
            failed(
                "REPORTER_TEST_001",
                CRITICAL,
                "/test_reporter_node",
                status="CONFIRMED",
                events=(CONFIRMED_EV,),
            ),
        ),
    ),
    Case(
        sid="RI-03",
        name="test_03_multiple_reports_aggregate",
        steps=(
            failed("REPORTER_TEST_002", CRITICAL, "/node_a", events=(CONFIRMED_EV,)),
            failed("REPORTER_TEST_002", CRITICAL, "/node_b", events=(UPDATED_EV,)),
            failed(
                "REPORTER_TEST_002",
                CRITICAL,
                "/node_a",
                count=1,
                stored_severity=CRITICAL,
                sources=("/node_a", "/node_b"),
                events=(UPDATED_EV,),
            ),
        ),
    ),
    Case(
        sid="RI-04",
        name="test_04_source_id_tracked",
        steps=(
            failed(
                "REPORTER_TEST_003",
                CRITICAL,
                "/perception/lidar/scanner_node",
                sources=("/perception/lidar/scanner_node",),
                status="CONFIRMED",
            ),
        ),
    ),
)


@upstream(*(case.sid for case in RI_CASES))
@pytest.mark.parametrize("case", RI_CASES, ids=[case.test_id for case in RI_CASES])
def test_reporter_integration(case: Case) -> None:
    """RI-02..RI-04 (ros2_medkit_fault_reporter test_integration): a manager with defaults."""
    run_node(case)
