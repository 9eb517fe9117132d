"""Ports of upstream's storage and node tests at 0.6.0 (bdcc4ed0), run under release 0.6.0.

Tests whose body is the same at bdcc4ed0 and 505bc2d5 rerun the existing ports (each backend
its upstream twin names); tests that changed, and those whose port pins 505's intermediate
steps, are here as data with 0.6.0's expectations. ``ctr``, ``count`` and ``events`` of the
intermediate steps are [I] values (read off 0.6.0's code), as in the 505 ports.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import pytest

from medkit_replay.engine.debounce import DebounceConfig
from medkit_replay.engine.manager import FaultManager, FaultManagerConfig
from medkit_replay.model import NS_PER_SEC, ClearRequest
from medkit_replay.releases import release_named
from tests.engine import (
    test_upstream_sqlite,
    test_upstream_storage,
    test_upstream_storage_healing,
)
from tests.engine.test_upstream_node_params import node_config, report
from tests.engine.upstream_support import (
    CLEARED_EV,
    CONFIRMED_EV,
    CRITICAL,
    ERROR,
    NO_EVENTS,
    UPDATED_EV,
    WARN,
    Case,
    Step,
    clear,
    events_of,
    failed,
    passed,
    run_node,
    run_storage,
)

if TYPE_CHECKING:
    from collections.abc import Iterable
    from pathlib import Path

S = NS_PER_SEC
R060 = release_named("0.6.0")
DEFAULTS = DebounceConfig()
CONF3 = DebounceConfig(confirmation_threshold=-3)
HEAL3 = DebounceConfig(healing_enabled=True, healing_threshold=3)
MEMORY, SQLITE = "memory", "sqlite"

# -- unchanged between the two commits: the existing ports, rerun at 0.6.0 ---------------------

UNCHANGED: dict[str, tuple[str, ...]] = {
    # Case name -> backends whose upstream test (FaultStorageTest.<name> for memory,
    # SqliteFaultStorageTest.<name> for sqlite) has the same body at bdcc4ed0 and 505bc2d5.
    "ReportNewFaultEvent": (MEMORY, SQLITE),
    "PassedEventForNonExistentFaultIgnored": (MEMORY, SQLITE),
    "ListFaultsDefaultReturnsConfirmedOnly": (MEMORY, SQLITE),
    "ListFaultsWithPrefailedStatus": (MEMORY, SQLITE),
    "ListFaultsFilterBySeverity": (MEMORY, SQLITE),
    "ClearFault": (MEMORY, SQLITE),
    "ClearNonExistentFault": (MEMORY, SQLITE),
    "GetClearedFaults": (MEMORY, SQLITE),
    "InvalidStatusDefaultsToConfirmed": (MEMORY, SQLITE),
    "ImmediateConfirmationWithThresholdZero": (MEMORY, SQLITE),
    "CriticalSeverityBypassesDebounce": (MEMORY, SQLITE),
    "CriticalBypassCanBeDisabled": (MEMORY,),
    "PassedEventForClearedFaultIgnored": (MEMORY, SQLITE),
    "GetAllFaultsReturnsAllFaults": (MEMORY,),
    "PersistenceAcrossRestarts": (SQLITE,),
    "TimestampPrecision": (SQLITE,),
    "SqliteInMemoryTest.InMemoryDatabase": (SQLITE,),
    "ReportingSourcesJsonHandling": (SQLITE,),
    "ConfirmationPersistsAfterReopen": (SQLITE,),
}


def _unchanged_cases() -> Iterable[Case]:
    for module in (test_upstream_storage, test_upstream_storage_healing, test_upstream_sqlite):
        for case in module.CASES:
            for backend in UNCHANGED.get(case.name, ()):
                yield dataclasses.replace(case, release=R060, storage_type=backend)


RERUN = tuple(_unchanged_cases())


def _id(case: Case) -> str:
    return f"{case.test_id}-{case.storage_type}"


@pytest.mark.parametrize("case", RERUN, ids=[_id(c) for c in RERUN])
def test_unchanged_scenario_at_060(case: Case) -> None:
    """A test upstream did not change between the two commits passes at 0.6.0 too."""
    run_storage(case)
    if case.node:
        run_node(case)


def test_every_unchanged_name_is_a_port() -> None:
    """Each name of the table is a ported case, so no row above is silently skipped."""
    assert {c.name for c in RERUN} == set(UNCHANGED)


# -- changed at 505bc2d5: 0.6.0's expectations -------------------------------------------------


def _both(sid: str, name: str, steps: tuple[Step, ...], config: DebounceConfig) -> list[Case]:
    """One upstream test with an in-memory and an SQLite twin that expect the same."""
    return [
        Case(sid=sid, name=name, steps=steps, config=config, release=R060, storage_type=backend)
        for backend in (MEMORY, SQLITE)
    ]


def _one(
    sid: str, name: str, steps: tuple[Step, ...], config: DebounceConfig, backend: str
) -> Case:
    return Case(sid=sid, name=name, steps=steps, config=config, release=R060, storage_type=backend)


CHANGED: tuple[Case, ...] = (
    *_both(
        "S-03",
        "ReportExistingFaultEventUpdates",
        (
            failed("MOTOR_OVERHEAT", WARN, "/powertrain/motor1", "Initial report",
                   status="CONFIRMED", count=1, events=(CONFIRMED_EV,)),
            failed("MOTOR_OVERHEAT", ERROR, "/powertrain/motor2", "Second report",
                   returns=False, size=1, count=2, stored_severity=ERROR,
                   sources=("/powertrain/motor1", "/powertrain/motor2"), events=(UPDATED_EV,)),
        ),
        DEFAULTS,
    ),
    *_both(
        "S-13",
        "FaultStaysPrefailedAboveThreshold",
        (
            failed("FAULT_1", ERROR, "/node1", "Test", events=NO_EVENTS),
            failed("FAULT_1", ERROR, "/node2", "Test", count=2, status="PREFAILED", ctr=-2,
                   events=NO_EVENTS),
        ),
        CONF3,
    ),
    *_both(
        "S-14",
        "FaultConfirmsAtThreshold",
        (
            failed("FAULT_1", ERROR, "/node1", "Test"),
            failed("FAULT_1", ERROR, "/node2", "Test"),
            failed("FAULT_1", ERROR, "/node3", "Test", count=3, status="CONFIRMED", ctr=-3,
                   events=(CONFIRMED_EV,)),
        ),
        CONF3,
    ),
    _one(
        "S-15",
        "ConfirmedFaultStaysConfirmed",
        tuple(
            failed("FAULT_1", ERROR, f"/node{i}", "Test", count=i + 1, ctr=-(i + 1),
                   status="CONFIRMED", events=(CONFIRMED_EV if i == 0 else UPDATED_EV,))
            for i in range(4)
        ),
        DEFAULTS,
        MEMORY,
    ),
    _one(
        "S-17",
        "MultiSourceConfirmsFault",
        tuple(
            failed("MOTOR_OVERHEAT", ERROR, f"/sensor{i}", "Test", count=i, status="CONFIRMED",
                   sources=tuple(f"/sensor{n}" for n in range(1, i + 1)),
                   events=(CONFIRMED_EV if i == 1 else UPDATED_EV,))
            for i in (1, 2, 3)
        ),
        DEFAULTS,
        MEMORY,
    ),
    _one(
        "S-18",
        "SameSourceMultipleReportsConfirms",
        tuple(
            failed("FAULT_1", ERROR, "/node1", "Test", count=i, status="CONFIRMED",
                   sources=("/node1",))
            for i in (1, 2, 3)
        ),
        DEFAULTS,
        MEMORY,
    ),
    *_both(
        "S-22",
        "ClearedFaultCanBeReactivated",
        (
            failed("FAULT_1", ERROR, "/node1", "Initial", t_ns=100 * S, returns=True,
                   status="CONFIRMED", count=1, events=(CONFIRMED_EV,)),
            clear("FAULT_1", status="CLEARED", events=(CLEARED_EV,)),
            # Reactivation keeps first_occurred at 0.6.0 (67bdb9cb resets it).
            failed("FAULT_1", ERROR, "/node2", "Reactivated", t_ns=102 * S, returns=True,
                   status="CONFIRMED", count=2, sources=("/node1", "/node2"),
                   stored_description="Reactivated", first_ns=100 * S, last_ns=102 * S,
                   events=(CONFIRMED_EV,)),
        ),
        DEFAULTS,
    ),
    *_both(
        "S-24",
        "ClearedFaultReactivationRestartsDebounce",
        (
            failed("FAULT_1", ERROR, "/node1", "Test", events=NO_EVENTS),
            failed("FAULT_1", ERROR, "/node2", "Test", events=NO_EVENTS),
            failed("FAULT_1", ERROR, "/node3", "Test", status="CONFIRMED", count=3,
                   events=(CONFIRMED_EV,)),
            clear("FAULT_1", events=(CLEARED_EV,)),
            failed("FAULT_1", ERROR, "/node4", "Test", returns=True, status="PREFAILED",
                   ctr=-1, count=4, events=NO_EVENTS),
            failed("FAULT_1", ERROR, "/node5", "Test", status="PREFAILED", ctr=-2, count=5),
            failed("FAULT_1", ERROR, "/node6", "Test", status="CONFIRMED", ctr=-3, count=6,
                   events=(CONFIRMED_EV,)),
        ),
        CONF3,
    ),
    # Default conf -1: 2 FAILED, 3 PASSED ends PREPASSED on both backends, by different roads.
    _one(
        "S-25",
        "PassedEventIncrementsCounter",
        (
            failed("FAULT_1", ERROR, "/node1", "Test", status="CONFIRMED", ctr=-1),
            failed("FAULT_1", ERROR, "/node2", "Test", status="CONFIRMED", ctr=-2),
            passed("FAULT_1", "/node1", status="CONFIRMED", ctr=-1, events=(UPDATED_EV,)),
            passed("FAULT_1", "/node1", status="CONFIRMED", ctr=0, events=(UPDATED_EV,)),
            passed("FAULT_1", "/node1", status="PREPASSED", ctr=1, events=NO_EVENTS),
        ),
        DEFAULTS,
        MEMORY,
    ),
    _one(
        "SQ-25",
        "SqliteFaultStorageTest.PassedEventIncrementsCounter",
        (
            failed("FAULT_1", ERROR, "/node1", "Test", status="CONFIRMED", ctr=-1),
            failed("FAULT_1", ERROR, "/node2", "Test", status="CONFIRMED", ctr=-2),
            # SQLite's PASSED never looks at the confirmation threshold.
            passed("FAULT_1", "/node1", status="PREFAILED", ctr=-1, events=NO_EVENTS),
            passed("FAULT_1", "/node1", status="PREFAILED", ctr=0, events=NO_EVENTS),
            passed("FAULT_1", "/node1", status="PREPASSED", ctr=1, events=NO_EVENTS),
        ),
        DEFAULTS,
        SQLITE,
    ),
    _one(
        "S-27",
        "HealingDisabledByDefault",
        (
            failed("FAULT_1", ERROR, "/node1", "Test", events=(CONFIRMED_EV,)),
            passed("FAULT_1", "/node1", status="CONFIRMED", ctr=0, events=(UPDATED_EV,)),
            *(passed("FAULT_1", "/node1", status="PREPASSED", events=NO_EVENTS) for _ in range(8)),
            passed("FAULT_1", "/node1", status="PREPASSED", ctr=9, events=NO_EVENTS),
        ),
        DEFAULTS,
        MEMORY,
    ),
    *_both(
        "S-28",
        "HealingWhenEnabled",
        (
            failed("FAULT_1", ERROR, "/node1", "Test", events=(CONFIRMED_EV,)),
            passed("FAULT_1", "/node1", status="CONFIRMED", ctr=0, events=(UPDATED_EV,)),
            passed("FAULT_1", "/node1", status="PREPASSED", ctr=1, events=NO_EVENTS),
            passed("FAULT_1", "/node1", status="PREPASSED", ctr=2, events=NO_EVENTS),
            # HEALED, and no FaultEvent says so at 0.6.0 (d27fc3eb added fault_cleared).
            passed("FAULT_1", "/node1", status="HEALED", ctr=3, events=NO_EVENTS),
        ),
        HEAL3,
    ),
    _one(
        "S-31",
        "ConfirmedFaultCanHealWithPassedEvents",
        (
            failed("FAULT_1", ERROR, "/node0", "Test", events=(CONFIRMED_EV,)),
            failed("FAULT_1", ERROR, "/node1", "Test", ctr=-2, events=(UPDATED_EV,)),
            failed("FAULT_1", ERROR, "/node2", "Test", status="CONFIRMED", ctr=-3,
                   events=(UPDATED_EV,)),
            passed("FAULT_1", "/node1", status="CONFIRMED", ctr=-2, events=(UPDATED_EV,)),
            passed("FAULT_1", "/node1", status="CONFIRMED", ctr=-1, events=(UPDATED_EV,)),
            passed("FAULT_1", "/node1", status="CONFIRMED", ctr=0, events=(UPDATED_EV,)),
            passed("FAULT_1", "/node1", status="PREPASSED", ctr=1, events=NO_EVENTS),
            passed("FAULT_1", "/node1", status="PREPASSED", ctr=2, events=NO_EVENTS),
            passed("FAULT_1", "/node1", status="HEALED", ctr=3, events=NO_EVENTS),
        ),
        HEAL3,
        MEMORY,
    ),
    _one(
        "S-32",
        "HealedFaultCanRecurWithFailedEvents",
        (
            failed("FAULT_1", ERROR, "/node1", "Test", events=(CONFIRMED_EV,)),
            passed("FAULT_1", "/node1", events=(UPDATED_EV,)),
            passed("FAULT_1", "/node1"),
            passed("FAULT_1", "/node1"),
            passed("FAULT_1", "/node1", status="HEALED", ctr=3, events=NO_EVENTS),
            # The first FAILED leaves HEALED: nothing holds it at 0.6.0.
            failed("FAULT_1", ERROR, "/node2", "Recurrence", status="PREPASSED", ctr=2,
                   events=NO_EVENTS),
            failed("FAULT_1", ERROR, "/node2", "Recurrence", status="PREPASSED", ctr=1),
            failed("FAULT_1", ERROR, "/node2", "Recurrence", status="PREPASSED", ctr=0),
            failed("FAULT_1", ERROR, "/node2", "Recurrence", status="CONFIRMED", ctr=-1,
                   events=(CONFIRMED_EV,)),
            failed("FAULT_1", ERROR, "/node2", "Recurrence", events=(UPDATED_EV,)),
            failed("FAULT_1", ERROR, "/node2", "Recurrence", status="CONFIRMED", ctr=-3,
                   count=7, events=(UPDATED_EV,)),
        ),
        HEAL3,
        MEMORY,
    ),
)  # fmt: skip


@pytest.mark.parametrize("case", CHANGED, ids=[_id(c) for c in CHANGED])
def test_changed_scenario_at_060(case: Case) -> None:
    """0.6.0's own expectations of a test upstream changed after it, storage and node."""
    run_storage(case)
    run_node(case)


# -- node-level and time-based tests --------------------------------------------------------


@pytest.mark.parametrize("backend", [MEMORY, SQLITE])
def test_update_existing_fault_publishes_updated_event(backend: str) -> None:
    """FaultEventPublishingTest.UpdateExistingFaultPublishesUpdatedEvent at 0.6.0: the
    fault_updated of the second report carries occurrence_count 2 (1 at 505bc2d5)."""
    manager = FaultManager(FaultManagerConfig(release=R060, storage_type=backend))
    report(manager, 1 * S, "TEST_FAULT_2", WARN, "/test_node1")
    report(manager, 2 * S, "TEST_FAULT_2", ERROR, "/test_node2")
    events = events_of(manager)
    assert [e.event_type for e in events] == ["fault_confirmed", "fault_updated"]
    assert events[1].fault.fault_code == "TEST_FAULT_2"
    assert events[1].fault.occurrence_count == 2


@pytest.mark.parametrize("backend", [MEMORY, SQLITE])
@pytest.mark.parametrize("after_ns", [0, 10 * S])
def test_time_based_confirmation(backend: str, after_ns: int) -> None:
    """FaultStorageTest.TimeBasedConfirmationDisabledByDefault / ...WhenEnabled (and the SQLite
    twin) at 0.6.0: a PREFAILED fault confirms 10 s after its last FAILED, not at 5 s."""
    manager = FaultManager(
        FaultManagerConfig(
            debounce=CONF3, auto_confirm_after_ns=after_ns, release=R060, storage_type=backend
        )
    )
    t0 = 1_000 * S
    report(manager, t0, "FAULT_1", ERROR, "/node1")
    assert manager.auto_confirm_tick(t0 + 5 * S) == []
    confirmed = manager.auto_confirm_tick(t0 + 15 * S)
    assert confirmed == (["FAULT_1"] if after_ns else [])
    assert manager.storage.faults["FAULT_1"].status == ("CONFIRMED" if after_ns else "PREFAILED")


def test_confirmation_threshold_disabled(tmp_path: Path) -> None:
    """FaultManagerNodeParameterTest.ConfirmationThresholdDisabled at 0.6.0: storage_type
    memory, confirmation_threshold 0 stays 0 ("0 means immediate confirmation")."""
    config, _ = node_config(tmp_path, 'storage_type: "memory"\nconfirmation_threshold: 0', R060)
    assert config.storage_type == MEMORY
    assert config.debounce.confirmation_threshold == 0
    assert FaultManager(config).resolver.global_config.confirmation_threshold == 0


NODE_PARAMETERS = (
    # (upstream test, parameters, (conf, healing_enabled, heal, auto_confirm_after_ns))
    ("FaultManagerNodeTest.DefaultDebounceConfig", "", (-1, False, 3, 0)),
    ("FaultManagerNodeParameterTest.CustomConfirmationThreshold",
     'storage_type: "memory"\nconfirmation_threshold: -5', (-5, False, 3, 0)),
    ("FaultManagerNodeParameterTest.HealingEnabled",
     'storage_type: "memory"\nhealing_enabled: true\nhealing_threshold: 5', (-1, True, 5, 0)),
    ("FaultManagerNodeParameterTest.AutoConfirmAfterSec",
     'storage_type: "memory"\nauto_confirm_after_sec: 15.0', (-1, False, 3, 15 * S)),
)  # fmt: skip


@pytest.mark.parametrize(
    ("params", "expected"),
    [pytest.param(p, e, id=name) for name, p, e in NODE_PARAMETERS],
)
def test_node_parameters_at_060(
    tmp_path: Path, params: str, expected: tuple[int, bool, int, int]
) -> None:
    """The node parameter tests unchanged at bdcc4ed0, through the parameter file at 0.6.0."""
    config, _ = node_config(tmp_path, params, R060)
    debounce = FaultManager(config).resolver.global_config
    got = (
        debounce.confirmation_threshold,
        debounce.healing_enabled,
        debounce.healing_threshold,
        config.auto_confirm_after_ns,
    )
    assert got == expected


@pytest.mark.parametrize("backend", [MEMORY, SQLITE])
def test_event_publishing_at_060(backend: str) -> None:
    """FaultEventPublishingTest.NewFaultPublishesConfirmedEvent, ClearFaultPublishesClearedEvent,
    ClearNonExistentFaultNoEvent and EventContainsFullFaultData (unchanged at bdcc4ed0)."""
    manager = FaultManager(FaultManagerConfig(release=R060, storage_type=backend))
    report(manager, 1 * S, "TEST_FAULT_1")
    report(manager, 2 * S, "TEST_FAULT_3")
    assert manager.clear(ClearRequest(t_ns=3 * S, fault_code="TEST_FAULT_3"))
    assert not manager.clear(ClearRequest(t_ns=4 * S, fault_code="NON_EXISTENT_FAULT"))
    report(manager, 5 * S, "FULL_DATA_TEST", CRITICAL, "/sensor/temperature")
    shown = [
        (e.event_type, e.fault.fault_code, e.fault.status, e.fault.severity, e.auto_cleared_codes)
        for e in events_of(manager)
    ]
    assert shown == [
        ("fault_confirmed", "TEST_FAULT_1", "CONFIRMED", ERROR, ()),
        ("fault_confirmed", "TEST_FAULT_3", "CONFIRMED", ERROR, ()),
        ("fault_cleared", "TEST_FAULT_3", "CLEARED", ERROR, ()),
        ("fault_confirmed", "FULL_DATA_TEST", "CONFIRMED", CRITICAL, ()),
    ]
    full = events_of(manager)[-1].fault
    assert (full.description, full.occurrence_count) == ("Test fault", 1)
    assert full.reporting_sources == ("/sensor/temperature",)
