"""Ports of upstream's storage-layer state-machine tests (fault-manager.md §4.1, S-01..S-25, S-29,
S-30, S-37, S-38, S-40, S-42; the healing and latch ones are in test_upstream_storage_healing).

Each scenario runs twice: against FaultStorage with the test's explicit config (the [A] values
and the internal counter), and through FaultManager to check the FaultEvents a node with the
same sanitised config would publish (the `ev:` [I] values).
"""

from __future__ import annotations

import pytest

from medkit_replay.engine.debounce import DebounceConfig, clamp, compute_status, is_valid, sanitize
from medkit_replay.engine.manager import FaultManager, FaultManagerConfig
from medkit_replay.engine.storage import FaultStorage
from medkit_replay.model import NS_PER_SEC, ReportRequest, Status
from tests.engine.upstream_support import (
    CLEARED_EV,
    CONFIRMED_EV,
    CRITICAL,
    ERROR,
    INFO,
    NO_EVENTS,
    UPDATED_EV,
    WARN,
    Case,
    clear,
    events_of,
    failed,
    passed,
    query,
    run_node,
    run_storage,
    status_of,
    upstream,
)

S = NS_PER_SEC
DEFAULTS = DebounceConfig()
CONF3 = DebounceConfig(confirmation_threshold=-3)

CASES: tuple[Case, ...] = (
    Case(
        sid="S-01",
        name="ReportNewFaultEvent",
        steps=(
            failed(
                "MOTOR_OVERHEAT",
                ERROR,
                "/powertrain/motor",
                "Motor temperature exceeded threshold",
                returns=True,
                size=1,
                status="CONFIRMED",
                ctr=-1,
                count=1,
                events=(CONFIRMED_EV,),
            ),
        ),
    ),
    Case(
        sid="S-02",
        name="PassedEventForNonExistentFaultIgnored",
        steps=(
            passed(
                "NON_EXISTENT",
                "/node1",
                ERROR,
                "Test",
                returns=False,
                size=0,
                status=None,
                events=NO_EVENTS,
            ),
        ),
    ),
    Case(
        sid="S-03",
        name="ReportExistingFaultEventUpdates",
        steps=(
            failed(
                "MOTOR_OVERHEAT",
                WARN,
                "/powertrain/motor1",
                "Initial report",
                status="CONFIRMED",
                events=(CONFIRMED_EV,),
            ),
            failed(
                "MOTOR_OVERHEAT",
                ERROR,
                "/powertrain/motor2",
                "Second report",
                returns=False,
                size=1,
                count=1,
                stored_severity=ERROR,
                sources=("/powertrain/motor1", "/powertrain/motor2"),
                stored_description="Second report",
                events=(UPDATED_EV,),
            ),
        ),
    ),
    Case(
        sid="S-04",
        name="ContinuouslyActiveFaultDoesNotInflateOccurrenceCount",
        steps=tuple(
            failed(
                "TANK_OVERFILL",
                ERROR,
                "/tank",
                "level = 95 > 80",
                count=1,
                status="CONFIRMED",
                events=(CONFIRMED_EV if i == 0 else UPDATED_EV,),
            )
            for i in range(25)
        ),
    ),
    Case(
        sid="S-05",
        name="ListFaultsDefaultReturnsConfirmedOnly",
        steps=(
            failed("FAULT_1", ERROR, "/node1", "Test"),
            query([], listed=("FAULT_1",), listed_status="CONFIRMED"),
        ),
    ),
    Case(
        sid="S-06",
        name="ListFaultsWithPrefailedStatus",
        config=CONF3,
        steps=(
            failed("FAULT_1", ERROR, "/node1", status="PREFAILED", ctr=-1, events=NO_EVENTS),
            query(["PREFAILED"], listed=("FAULT_1",), listed_status="PREFAILED"),
            query([], listed=()),
        ),
    ),
    Case(
        sid="S-07",
        name="ListFaultsFilterBySeverity",
        steps=(
            failed("FAULT_INFO", INFO, "/node1", "Info"),
            failed("FAULT_ERROR", ERROR, "/node1", "Error"),
            query(["CONFIRMED"], by_severity=True, severity=ERROR, listed=("FAULT_ERROR",)),
        ),
    ),
    Case(
        sid="S-08",
        name="ClearFault",
        steps=(
            failed("MOTOR_OVERHEAT", ERROR, "/node1", events=(CONFIRMED_EV,)),
            clear("MOTOR_OVERHEAT", returns=True, status="CLEARED", events=(CLEARED_EV,)),
        ),
    ),
    Case(
        sid="S-09",
        name="ClearNonExistentFault",
        steps=(
            clear(
                "NON_EXISTENT",
                returns=False,
                message="Fault not found: NON_EXISTENT",
                events=NO_EVENTS,
                size=0,
            ),
        ),
    ),
    Case(
        sid="S-10",
        name="GetClearedFaults",
        steps=(
            failed("FAULT_1", ERROR, "/node1"),
            clear("FAULT_1"),
            query(["CLEARED"], listed=("FAULT_1",), listed_status="CLEARED"),
        ),
    ),
    Case(
        sid="S-11",
        name="InvalidStatusDefaultsToConfirmed",
        steps=(
            failed("FAULT_1", ERROR, "/node1"),
            query(["INVALID_STATUS"], listed=("FAULT_1",), listed_status="CONFIRMED"),
        ),
    ),
    Case(
        sid="S-14",
        name="FaultStaysPrefailedAboveThreshold",
        config=CONF3,
        steps=(
            failed("FAULT_1", ERROR, "/node1", status="PREFAILED", ctr=-1, events=NO_EVENTS),
            failed(
                "FAULT_1", ERROR, "/node2", count=1, status="PREFAILED", ctr=-2, events=NO_EVENTS
            ),
        ),
    ),
    Case(
        sid="S-15",
        name="FaultConfirmsAtThreshold",
        config=CONF3,
        steps=(
            failed("FAULT_1", ERROR, "/node1", status="PREFAILED", ctr=-1, events=NO_EVENTS),
            failed("FAULT_1", ERROR, "/node2", status="PREFAILED", ctr=-2, events=NO_EVENTS),
            failed(
                "FAULT_1",
                ERROR,
                "/node3",
                count=1,
                status="CONFIRMED",
                ctr=-3,
                events=(CONFIRMED_EV,),
            ),
        ),
    ),
    Case(
        sid="S-16",
        name="ConfirmedFaultStaysConfirmed",
        steps=tuple(
            failed(
                "FAULT_1",
                ERROR,
                f"/node{i}",
                count=1,
                status="CONFIRMED",
                ctr=-1,
                events=(CONFIRMED_EV if i == 0 else UPDATED_EV,),
                sources=tuple(f"/node{j}" for j in range(i + 1)),
            )
            for i in range(4)
        ),
    ),
    Case(
        sid="S-17",
        name="MultiSourceConfirmsFault",
        steps=(
            failed("MOTOR_OVERHEAT", ERROR, "/sensor1"),
            failed("MOTOR_OVERHEAT", ERROR, "/sensor2"),
            failed(
                "MOTOR_OVERHEAT",
                ERROR,
                "/sensor3",
                status="CONFIRMED",
                sources=("/sensor1", "/sensor2", "/sensor3"),
                count=1,
            ),
        ),
    ),
    Case(
        sid="S-18",
        name="SameSourceMultipleReportsConfirms",
        steps=tuple(
            failed("FAULT_1", ERROR, "/node1", count=1, status="CONFIRMED", sources=("/node1",))
            for _ in range(3)
        ),
    ),
    Case(
        sid="S-19",
        name="ImmediateConfirmationWithThresholdZero",
        # Storage-level conf 0 is used unsanitised; the node sanitises it to -1: same outcome.
        config=DebounceConfig(confirmation_threshold=0),
        steps=(
            failed(
                "FAULT_1",
                ERROR,
                "/node1",
                count=1,
                status="CONFIRMED",
                ctr=-1,
                events=(CONFIRMED_EV,),
            ),
        ),
    ),
    Case(
        sid="S-20",
        name="CriticalSeverityBypassesDebounce",
        steps=(
            failed(
                "FAULT_1",
                CRITICAL,
                "/node1",
                "Critical test",
                count=1,
                status="CONFIRMED",
                events=(CONFIRMED_EV,),
            ),
        ),
    ),
    Case(
        sid="S-21",
        name="CriticalBypassCanBeDisabled",
        config=DebounceConfig(confirmation_threshold=-3, critical_immediate_confirm=False),
        node=False,  # the CRITICAL bypass is not configurable on the node
        steps=(failed("FAULT_1", CRITICAL, "/node1", status="PREFAILED", ctr=-1),),
    ),
    Case(
        sid="S-22",
        name="ClearedFaultCanBeReactivated",
        steps=(
            failed(
                "FAULT_1",
                ERROR,
                "/node1",
                "Initial",
                t_ns=100 * S,
                returns=True,
                status="CONFIRMED",
                count=1,
                first_ns=100 * S,
                events=(CONFIRMED_EV,),
            ),
            clear("FAULT_1", t_ns=100 * S + S // 2, status="CLEARED", events=(CLEARED_EV,)),
            failed(
                "FAULT_1",
                ERROR,
                "/node2",
                "Reactivated",
                t_ns=101 * S,
                returns=True,
                status="CONFIRMED",
                count=2,
                sources=("/node1", "/node2"),
                stored_description="Reactivated",
                first_ns=101 * S,
                last_ns=101 * S,
                events=(CONFIRMED_EV,),
            ),
        ),
    ),
    Case(
        sid="S-23",
        name="PassedEventForClearedFaultIgnored",
        steps=(
            failed("FAULT_1", ERROR, "/node1"),
            clear("FAULT_1"),
            passed(
                "FAULT_1",
                "/node1",
                returns=False,
                status="CLEARED",
                last_passed_ns=0,
                events=NO_EVENTS,
            ),
        ),
    ),
    Case(
        sid="S-24",
        name="ClearedFaultReactivationRestartsDebounce",
        config=CONF3,
        steps=(
            failed("FAULT_1", ERROR, "/node1", events=NO_EVENTS),
            failed("FAULT_1", ERROR, "/node2", events=NO_EVENTS),
            failed("FAULT_1", ERROR, "/node3", status="CONFIRMED", events=(CONFIRMED_EV,)),
            clear("FAULT_1", events=(CLEARED_EV,)),
            failed(
                "FAULT_1",
                ERROR,
                "/node4",
                status="PREFAILED",
                ctr=-1,
                count=2,
                returns=True,
                events=NO_EVENTS,
            ),
            failed("FAULT_1", ERROR, "/node5", status="PREFAILED", ctr=-2, events=NO_EVENTS),
            failed(
                "FAULT_1",
                ERROR,
                "/node6",
                status="CONFIRMED",
                ctr=-3,
                count=2,
                events=(CONFIRMED_EV,),
            ),
        ),
    ),
    Case(
        sid="S-25",
        name="PassedEventIncrementsCounter",
        config=CONF3,
        steps=(
            failed("FAULT_1", ERROR, "/node1", status="PREFAILED", ctr=-1, events=NO_EVENTS),
            failed("FAULT_1", ERROR, "/node2", status="PREFAILED", ctr=-2, events=NO_EVENTS),
            passed("FAULT_1", "/node1", status="PREFAILED", ctr=-1, events=NO_EVENTS),
            passed("FAULT_1", "/node1", status="PREFAILED", ctr=0, events=NO_EVENTS),
            passed("FAULT_1", "/node1", status="PREPASSED", ctr=1, events=NO_EVENTS),
        ),
    ),
)

NODE_CASES = tuple(case for case in CASES if case.node)


@upstream(*(case.sid for case in CASES))
@pytest.mark.parametrize("case", CASES, ids=[case.test_id for case in CASES])
def test_storage_scenario(case: Case) -> None:
    """Storage layer: returns, statuses, counters and fields after every step."""
    run_storage(case)


@upstream(*(case.sid for case in NODE_CASES))
@pytest.mark.parametrize("case", NODE_CASES, ids=[case.test_id for case in NODE_CASES])
def test_storage_scenario_node_events(case: Case) -> None:
    """The same scenario through FaultManager: FaultEvents per step, same state."""
    run_node(case)


@upstream("S-12")
def test_s12_default_debounce_config() -> None:
    """S-12 DefaultDebounceConfig: conf -1, healing off, heal 3, crit on; auto-confirm off."""
    assert DebounceConfig() == DebounceConfig(
        confirmation_threshold=-1,
        healing_enabled=False,
        healing_threshold=3,
        critical_immediate_confirm=True,
    )
    config = FaultManagerConfig()
    assert config.debounce == DebounceConfig()
    assert config.auto_confirm_after_ns == 0
    manager = FaultManager(config)
    assert manager.resolver.global_config == DebounceConfig()
    assert manager.auto_confirm_tick(10**6 * S) == []


@upstream("S-13")
def test_s13_set_debounce_config() -> None:
    """S-13 SetDebounceConfig: (conf -5, heal_en, heal 5, crit off, auto 10 s) reads back."""
    debounce = DebounceConfig(
        confirmation_threshold=-5,
        healing_enabled=True,
        healing_threshold=5,
        critical_immediate_confirm=False,
    )
    manager = FaultManager(FaultManagerConfig(debounce=debounce, auto_confirm_after_ns=10 * S))
    assert manager.config.debounce == debounce
    assert manager.config.auto_confirm_after_ns == 10 * S
    assert manager.resolver.global_config == debounce
    assert manager.resolver.resolve("/any/node") == debounce


def _prefailed_manager(auto_ns: int, t0: int) -> FaultManager:
    manager = FaultManager(FaultManagerConfig(debounce=CONF3, auto_confirm_after_ns=auto_ns))
    assert manager.report(
        ReportRequest(
            t_ns=t0, fault_code="FAULT_1", event_type=0, severity=ERROR, source_id="/node1"
        )
    )
    assert status_of(manager, "FAULT_1") == "PREFAILED"
    return manager


@upstream("S-29")
def test_s29_time_based_confirmation_disabled_by_default() -> None:
    """S-29 TimeBasedConfirmationDisabledByDefault: auto 0 → check at t+20 s confirms nothing."""
    t0 = 50 * S
    manager = _prefailed_manager(0, t0)
    assert manager.auto_confirm_tick(t0 + 20 * S) == []
    assert status_of(manager, "FAULT_1") == "PREFAILED"
    assert events_of(manager) == []


@upstream("S-30")
def test_s30_time_based_confirmation_when_enabled() -> None:
    """S-30 TimeBasedConfirmationWhenEnabled: conf -3, auto 10 s.

    check(t0+5 s) → []; check(t0+15 s) → [FAULT_1], CONFIRMED, counter still -1, and no
    FaultEvent (the timer path publishes none).
    """
    t0 = 50 * S
    manager = _prefailed_manager(10 * S, t0)
    assert manager.auto_confirm_tick(t0 + 5 * S) == []
    assert status_of(manager, "FAULT_1") == "PREFAILED"
    assert manager.auto_confirm_tick(t0 + 15 * S) == ["FAULT_1"]
    fault = manager.storage.faults["FAULT_1"]
    assert fault.status == "CONFIRMED"
    assert fault.counter == -1
    assert events_of(manager) == []
    last = manager.output.transitions[-1]
    assert (last.fault_code, last.from_status, last.to_status, last.cause, last.t_ns) == (
        "FAULT_1",
        "PREFAILED",
        "CONFIRMED",
        "auto_confirm",
        t0 + 15 * S,
    )


@upstream("S-37")
@pytest.mark.parametrize(("counter", "expected"), [(100, 2), (-100, -2), (1, 1)])
def test_s37_clamp_debounce_counter_bounds(counter: int, expected: int) -> None:
    """S-37 DebounceHelpers.ClampDebounceCounterBounds: band [-2, 2]."""
    band = DebounceConfig(confirmation_threshold=-2, healing_threshold=2)
    assert clamp(counter, band) == expected


@upstream("S-38")
def test_s38_sanitize_debounce_config_fixes_bad_thresholds() -> None:
    """S-38 DebounceHelpers.SanitizeDebounceConfigFixesBadThresholds."""
    assert is_valid(DebounceConfig())
    heal_zero = DebounceConfig(confirmation_threshold=-1, healing_threshold=0)
    assert is_valid(heal_zero)
    assert sanitize(heal_zero).healing_threshold == 0
    bad = DebounceConfig(confirmation_threshold=0, healing_threshold=-1)
    assert not is_valid(bad)
    fixed = sanitize(bad)
    assert fixed.confirmation_threshold < 0 <= fixed.healing_threshold
    assert (fixed.confirmation_threshold, fixed.healing_threshold) == (-1, 3)


@upstream("S-40")
@pytest.mark.parametrize(
    ("counter", "current", "expected"),
    [(2, "CONFIRMED", "CONFIRMED"), (-1, "HEALED", "HEALED"), (1, "PREFAILED", "PREPASSED")],
)
def test_s40_compute_debounce_status_latches(
    counter: int, current: Status, expected: Status
) -> None:
    """S-40 DebounceHelpers.ComputeDebounceStatusLatches: conf -3, heal 3, healing off."""
    config = DebounceConfig(confirmation_threshold=-3, healing_threshold=3)
    assert compute_status(counter, current, config) == expected


@upstream("S-42")
def test_s42_get_all_faults_returns_empty_for_empty_storage() -> None:
    """S-42 GetAllFaultsReturnsEmptyForEmptyStorage."""
    assert FaultStorage().faults == {}
    assert FaultManager(FaultManagerConfig()).faults() == []
