"""Ports of upstream's per-entity threshold tests (fault-manager.md §4.6: R, Y, PE, EI).

Resolver tests use EntityThresholdResolver without the sanitiser (as upstream's resolver alone);
YAML tests read files written to tmp_path with medkit_replay.config's reader; PE and EI replay
reports with per-source configs through FaultStorage and FaultManager.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

from medkit_replay.config.entity_thresholds_file import load_entity_thresholds
from medkit_replay.engine.debounce import DebounceConfig
from medkit_replay.engine.manager import FaultManagerConfig
from medkit_replay.engine.thresholds import EntityOverride, EntityThresholdResolver
from tests.engine.upstream_support import (
    CONFIRMED_EV,
    ERROR,
    HEALED_EV,
    NO_EVENTS,
    UPDATED_EV,
    Case,
    failed,
    passed,
    run_node,
    run_storage,
    upstream,
)

if TYPE_CHECKING:
    from pathlib import Path

GLOBAL = DebounceConfig(confirmation_threshold=-1, healing_enabled=False, healing_threshold=3)


def triple(config: DebounceConfig) -> tuple[int, bool, int]:
    """(confirmation_threshold, healing_enabled, healing_threshold)."""
    return (config.confirmation_threshold, config.healing_enabled, config.healing_threshold)


# -- resolver (R-01..R-08) --------------------------------------------------------------------

RESOLVER_CASES = [
    pytest.param((), "/sensors/lidar", (-1, False, 3), id="R-01-EmptyResolverReturnsGlobal"),
    pytest.param(
        (EntityOverride(prefix="/sensors/lidar", confirmation_threshold=-1, healing_threshold=1),),
        "/sensors/lidar",
        (-1, False, 1),
        id="R-02-ExactMatch",
    ),
    pytest.param(
        (EntityOverride(prefix="/sensors/lidar", healing_threshold=1),),
        "/sensors/lidar/front",
        (-1, False, 1),
        id="R-03-PrefixMatch",
    ),
    pytest.param(
        (
            EntityOverride(prefix="/sensors", confirmation_threshold=-5),
            EntityOverride(prefix="/sensors/lidar", confirmation_threshold=-1),
        ),
        "/sensors/lidar/front",
        (-1, False, 3),
        id="R-04-LongestPrefixWins-lidar",
    ),
    pytest.param(
        (
            EntityOverride(prefix="/sensors", confirmation_threshold=-5),
            EntityOverride(prefix="/sensors/lidar", confirmation_threshold=-1),
        ),
        "/sensors/camera",
        (-5, False, 3),
        id="R-04-LongestPrefixWins-camera",
    ),
    pytest.param(
        (EntityOverride(prefix="/sensors/lidar", confirmation_threshold=-5),),
        "/powertrain/motor",
        (-1, False, 3),
        id="R-05-NoMatchReturnsGlobal",
    ),
    pytest.param(
        (EntityOverride(prefix="/sensors/lid", confirmation_threshold=-5),),
        "/sensors/lidar",
        (-1, False, 3),
        id="R-06-PrefixMatchRequiresPathBoundary-no-match",
    ),
    pytest.param(
        (EntityOverride(prefix="/sensors/lid", confirmation_threshold=-5),),
        "/sensors/lid/front",
        (-5, False, 3),
        id="R-06-PrefixMatchRequiresPathBoundary-match",
    ),
    pytest.param(
        (EntityOverride(prefix="/safety", healing_enabled=False),),
        "/safety/estop",
        (-1, False, 3),
        id="R-07-PartialOverrideMergesWithGlobal",
    ),
]


@upstream("R-01", "R-02", "R-03", "R-04", "R-05", "R-06", "R-07")
@pytest.mark.parametrize(("entries", "source_id", "expected"), RESOLVER_CASES)
def test_resolver(
    entries: tuple[EntityOverride, ...], source_id: str, expected: tuple[int, bool, int]
) -> None:
    """ResolverTest.*: longest path-boundary prefix of the source_id, field-wise merge."""
    resolver = EntityThresholdResolver(GLOBAL, entries, sanitize_entries=False)
    assert triple(resolver.resolve(source_id)) == expected


@upstream("R-08")
def test_r08_size_returns_entry_count() -> None:
    """R-08 ResolverTest.SizeReturnsEntryCount: 0, then 2."""
    assert len(EntityThresholdResolver(GLOBAL, (), sanitize_entries=False)) == 0
    entries = (
        EntityOverride(prefix="/a", confirmation_threshold=-2),
        EntityOverride(prefix="/b", healing_threshold=1),
    )
    assert len(EntityThresholdResolver(GLOBAL, entries, sanitize_entries=False)) == 2


# -- YAML loading (Y-01..Y-04 and the inferred additions) ---------------------------------------


def write(tmp_path: Path, text: str) -> Path:
    """An entity_thresholds file in tmp_path."""
    path = tmp_path / "entity_thresholds.yaml"
    path.write_text(text)
    return path


def by_prefix(entries: tuple[EntityOverride, ...]) -> dict[str, EntityOverride]:
    """Entries keyed by prefix."""
    return {entry.prefix: entry for entry in entries}


@upstream("Y-01")
def test_y01_load_valid_file(tmp_path: Path) -> None:
    """Y-01 YamlLoadTest.LoadValidFile: 3 entries; motor_left conf -5, heal 10, healing unset."""
    path = write(
        tmp_path,
        "/sensors/lidar:\n"
        "  confirmation_threshold: -1\n"
        "  healing_threshold: 1\n"
        "/powertrain/motor_left:\n"
        "  confirmation_threshold: -5\n"
        "  healing_threshold: 10\n"
        "/safety:\n"
        "  healing_enabled: false\n",
    )
    entries, _ = load_entity_thresholds(path)
    assert len(entries) == 3
    motor = by_prefix(entries)["/powertrain/motor_left"]
    assert motor.confirmation_threshold == -5
    assert motor.healing_threshold == 10
    assert motor.healing_enabled is None
    resolver = EntityThresholdResolver(GLOBAL, entries)
    assert len(resolver) == 3
    assert triple(resolver.resolve("/powertrain/motor_left")) == (-5, False, 10)


@upstream("Y-02")
def test_y02_missing_file_returns_empty(tmp_path: Path) -> None:
    """Y-02 YamlLoadTest.MissingFileReturnsEmpty."""
    entries, _ = load_entity_thresholds(tmp_path / "does_not_exist.yaml")
    assert entries == ()


@upstream("Y-03")
def test_y03_malformed_yaml_returns_empty(tmp_path: Path) -> None:
    """Y-03 YamlLoadTest.MalformedYamlReturnsEmpty."""
    entries, _ = load_entity_thresholds(write(tmp_path, "{{{{not valid yaml"))
    assert entries == ()


@upstream("Y-04")
def test_y04_positive_confirmation_threshold_auto_negated(tmp_path: Path) -> None:
    """Y-04 YamlLoadTest.PositiveConfirmationThresholdAutoNegated: /sensors conf 5 → -5."""
    entries, _ = load_entity_thresholds(write(tmp_path, "/sensors:\n  confirmation_threshold: 5\n"))
    assert by_prefix(entries)["/sensors"].confirmation_threshold == -5


@upstream("Y-inferred")
def test_y_inferred_negative_healing_threshold_negated(tmp_path: Path) -> None:
    """Y [I]: healing_threshold -4 is negated to 4 at load time."""
    entries, _ = load_entity_thresholds(write(tmp_path, "/sensors:\n  healing_threshold: -4\n"))
    assert by_prefix(entries)["/sensors"].healing_threshold == 4


@upstream("Y-inferred")
def test_y_inferred_zero_confirmation_kept_then_sanitised(tmp_path: Path) -> None:
    """Y [I]: conf 0 is kept at load; the node sanitises the merged value to -1."""
    entries, _ = load_entity_thresholds(write(tmp_path, "/sensors:\n  confirmation_threshold: 0\n"))
    assert by_prefix(entries)["/sensors"].confirmation_threshold == 0
    global_config = DebounceConfig(confirmation_threshold=-5)
    resolver = EntityThresholdResolver(global_config, entries)
    assert resolver.resolve("/sensors/imu").confirmation_threshold == -1


@upstream("Y-inferred")
def test_y_inferred_non_map_value_skips_that_prefix(tmp_path: Path) -> None:
    """Y [I]: a non-map value for a prefix skips that entry only."""
    entries, _ = load_entity_thresholds(
        write(
            tmp_path,
            "/first:\n  healing_threshold: 1\n/bad: 7\n/last:\n  confirmation_threshold: -2\n",
        )
    )
    assert sorted(by_prefix(entries)) == ["/first", "/last"]


# -- per-entity storage (PE-01..PE-06) ----------------------------------------------------------

LIDAR = EntityOverride(
    prefix="/sensors/lidar", confirmation_threshold=-1, healing_enabled=True, healing_threshold=1
)
MOTOR = EntityOverride(
    prefix="/powertrain/motor_left",
    confirmation_threshold=-5,
    healing_enabled=True,
    healing_threshold=10,
)
PE_RESOLVER = EntityThresholdResolver(GLOBAL, (LIDAR, MOTOR))
PE_NODE = FaultManagerConfig(debounce=GLOBAL, entity_overrides=(LIDAR, MOTOR))


def at(source_id: str) -> DebounceConfig:
    """The per-entity config upstream's PerEntityStorageTest passes for this source."""
    return PE_RESOLVER.resolve(source_id)


LIDAR_SRC = "/sensors/lidar"
MOTOR_SRC = "/powertrain/motor_left"

PE_CASES: tuple[Case, ...] = (
    Case(
        sid="PE-01",
        name="PerEntityStorageTest.LidarFaultConfirmsImmediately",
        node_config=PE_NODE,
        steps=(
            failed(
                "LIDAR_FAIL",
                ERROR,
                LIDAR_SRC,
                config=at(LIDAR_SRC),
                status="CONFIRMED",
                events=(CONFIRMED_EV,),
            ),
        ),
    ),
    Case(
        sid="PE-02",
        name="PerEntityStorageTest.MotorFaultNeedsDebouncing",
        node_config=PE_NODE,
        steps=(
            failed(
                "MOTOR_OVERHEAT",
                ERROR,
                MOTOR_SRC,
                "Motor hot",
                config=at(MOTOR_SRC),
                status="PREFAILED",
                ctr=-1,
                events=NO_EVENTS,
            ),
            *(
                failed(
                    "MOTOR_OVERHEAT",
                    ERROR,
                    MOTOR_SRC,
                    config=at(MOTOR_SRC),
                    status="PREFAILED",
                    ctr=ctr,
                    stored_description="Motor hot",
                    events=NO_EVENTS,
                )
                for ctr in (-2, -3, -4)
            ),
            failed(
                "MOTOR_OVERHEAT",
                ERROR,
                MOTOR_SRC,
                config=at(MOTOR_SRC),
                status="CONFIRMED",
                ctr=-5,
                events=(CONFIRMED_EV,),
            ),
        ),
    ),
    Case(
        sid="PE-03",
        name="PerEntityStorageTest.UnknownEntityUsesGlobalConfig",
        node_config=PE_NODE,
        steps=(
            failed(
                "UNKNOWN_FAULT",
                ERROR,
                "/some/unknown/entity",
                config=GLOBAL,
                status="CONFIRMED",
                events=(CONFIRMED_EV,),
            ),
        ),
    ),
    Case(
        sid="PE-04",
        name="PerEntityStorageTest.DifferentEntitiesSameFaultCode",
        node_config=PE_NODE,
        steps=(
            failed(
                "OVERHEAT",
                ERROR,
                MOTOR_SRC,
                config=at(MOTOR_SRC),
                status="PREFAILED",
                ctr=-1,
                events=NO_EVENTS,
            ),
            failed(
                "OVERHEAT",
                ERROR,
                LIDAR_SRC,
                config=at(LIDAR_SRC),
                status="CONFIRMED",
                ctr=-1,
                events=(CONFIRMED_EV,),
            ),
        ),
    ),
    Case(
        sid="PE-05",
        name="PerEntityStorageTest.LidarHealingWithThreshold1",
        node_config=PE_NODE,
        steps=(
            failed(
                "LIDAR_FAIL",
                ERROR,
                LIDAR_SRC,
                config=at(LIDAR_SRC),
                status="CONFIRMED",
                events=(CONFIRMED_EV,),
            ),
            passed(
                "LIDAR_FAIL",
                LIDAR_SRC,
                config=at(LIDAR_SRC),
                status="CONFIRMED",
                ctr=0,
                events=(UPDATED_EV,),
            ),
            passed(
                "LIDAR_FAIL",
                LIDAR_SRC,
                config=at(LIDAR_SRC),
                status="HEALED",
                ctr=1,
                events=(HEALED_EV,),
            ),
        ),
    ),
    Case(
        sid="PE-06",
        name="PerEntityStorageTest.BackwardCompatibleWithoutResolver",
        config=GLOBAL,
        steps=(failed("FAULT_1", ERROR, "/node1", status="CONFIRMED", events=(CONFIRMED_EV,)),),
    ),
)


@upstream(*(case.sid for case in PE_CASES))
@pytest.mark.parametrize("case", PE_CASES, ids=[case.test_id for case in PE_CASES])
def test_per_entity_storage(case: Case) -> None:
    """Storage with the per-entity config of each report's source."""
    run_storage(case)


@upstream(*(case.sid for case in PE_CASES))
@pytest.mark.parametrize("case", PE_CASES, ids=[case.test_id for case in PE_CASES])
def test_per_entity_node(case: Case) -> None:
    """FaultManager resolving the same overrides itself: same state, and its FaultEvents."""
    run_node(case)


# -- node integration with the YAML file (EI-01..EI-06) -----------------------------------------

EI_YAML = (
    "/sensors/lidar:\n"
    "  confirmation_threshold: -1\n"
    "  healing_enabled: true\n"
    "  healing_threshold: 1\n"
    "/powertrain/motor:\n"
    "  confirmation_threshold: -3\n"
    "  healing_threshold: 5\n"
)
EI_GLOBAL = DebounceConfig(confirmation_threshold=-5, healing_enabled=False, healing_threshold=10)
EI_OVERRIDES = (
    EntityOverride(
        prefix="/sensors/lidar",
        confirmation_threshold=-1,
        healing_enabled=True,
        healing_threshold=1,
    ),
    EntityOverride(prefix="/powertrain/motor", confirmation_threshold=-3, healing_threshold=5),
)

MOTOR_LEFT = "/powertrain/motor/left"
UNKNOWN_SRC = "/some/unknown/subsystem"
EI_CASE = Case(
    sid="EI-01..06",
    name="test_entity_thresholds_integration",
    node_config=FaultManagerConfig(debounce=EI_GLOBAL, entity_overrides=EI_OVERRIDES),
    steps=(
        # EI-01 test_01_lidar_confirms_immediately
        failed(
            "LIDAR.BLOCKED",
            ERROR,
            "/sensors/lidar/front",
            status="CONFIRMED",
            events=(CONFIRMED_EV,),
        ),
        # EI-02 test_02_motor_stays_prefailed
        failed("MOTOR.OVERHEAT", ERROR, MOTOR_LEFT, status="PREFAILED", events=NO_EVENTS),
        # EI-03 test_03_motor_confirms_at_threshold
        failed("MOTOR.OVERHEAT", ERROR, MOTOR_LEFT, status="PREFAILED", events=NO_EVENTS),
        failed(
            "MOTOR.OVERHEAT", ERROR, MOTOR_LEFT, status="CONFIRMED", ctr=-3, events=(CONFIRMED_EV,)
        ),
        # EI-04 test_04_unknown_entity_uses_global
        failed("UNKNOWN.FAULT", ERROR, UNKNOWN_SRC, status="PREFAILED", events=NO_EVENTS),
        # EI-05 test_05_unknown_entity_still_prefailed_at_3
        failed("UNKNOWN.FAULT", ERROR, UNKNOWN_SRC, status="PREFAILED", events=NO_EVENTS),
        failed("UNKNOWN.FAULT", ERROR, UNKNOWN_SRC, status="PREFAILED", ctr=-3, events=NO_EVENTS),
        # EI-06 test_06_unknown_entity_confirms_at_5
        failed("UNKNOWN.FAULT", ERROR, UNKNOWN_SRC, status="PREFAILED", ctr=-4, events=NO_EVENTS),
        failed(
            "UNKNOWN.FAULT", ERROR, UNKNOWN_SRC, status="CONFIRMED", ctr=-5, events=(CONFIRMED_EV,)
        ),
    ),
)


@upstream("EI-01", "EI-02", "EI-03", "EI-04", "EI-05", "EI-06")
def test_ei_entity_thresholds_integration() -> None:
    """EI-01..EI-06: node conf -5 (healing off, heal 10) with lidar and motor overrides; the six
    upstream tests share one node and run in order, so they are one sequence here."""
    run_node(EI_CASE)


@upstream("EI-01", "EI-02", "EI-03", "EI-04", "EI-05", "EI-06")
def test_ei_entity_file_reads_as_the_overrides(tmp_path: Path) -> None:
    """The EI entity file loads into exactly the overrides the sequence above uses."""
    entries, warnings = load_entity_thresholds(write(tmp_path, EI_YAML))
    assert entries == EI_OVERRIDES
    assert warnings == ()
