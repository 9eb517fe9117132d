"""Ports of upstream's node parameter tests (fault-manager.md §4.2, N-01..N-12 and the [I] ones).

Parameters go through medkit_replay.config exactly as a ROS 2 parameter file would; the
resulting FaultManagerConfig is then exercised on FaultManager.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

from medkit_replay.config.fault_manager import fault_manager_config
from medkit_replay.config.params import load_parameters
from medkit_replay.engine.debounce import DebounceConfig
from medkit_replay.engine.manager import FaultManager, FaultManagerConfig
from medkit_replay.engine.timeline import Timeline
from medkit_replay.model import NS_PER_MS, NS_PER_SEC, ReportRequest
from tests.engine.upstream_support import (
    ERROR,
    FAILED,
    PASSED,
    WARN,
    events_of,
    status_of,
    upstream,
)

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.releases import Release

S = NS_PER_SEC
T0 = 1_790_000_000 * S  # a 2026 bag time


def report(
    manager: FaultManager,
    t_ns: int,
    code: str,
    severity: int = ERROR,
    source: str = "/test_node",
    event_type: int = FAILED,
) -> bool:
    """One ReportFault request; returns ``accepted``."""
    return manager.report(
        ReportRequest(
            t_ns=t_ns,
            fault_code=code,
            event_type=event_type,
            severity=severity,
            description="Test fault",
            source_id=source,
        )
    )


# -- node parameters (N-01..N-12) ---------------------------------------------------------------


def node_config(
    tmp_path: Path, params: str = "", release: Release | None = None
) -> tuple[FaultManagerConfig, list[str]]:
    """The FaultManagerConfig of a parameter file whose fault_manager holds ``params``."""
    body = "".join(f"    {line}\n" for line in params.splitlines()) or "    {}\n"
    path = tmp_path / "params.yaml"
    path.write_text("fault_manager:\n  ros__parameters:\n" + body)
    return fault_manager_config(load_parameters([path]).node("fault_manager"), release)


def confirming_report(config: FaultManagerConfig) -> int:
    """How many FAILED ERROR reports from one source it takes to confirm a new fault."""
    manager = FaultManager(config)
    for n in range(1, 50):
        report(manager, T0 + n * S, "PROBE")
        if manager.storage.faults["PROBE"].status == "CONFIRMED":
            return n
    return -1


@upstream("N-01")
def test_n01_node_creation(tmp_path: Path) -> None:
    """N-01 FaultManagerNodeTest.NodeCreation, state part: a new manager holds no faults. (Node
    name and storage type are ROS plumbing.)"""
    config, warnings = node_config(tmp_path)
    assert warnings == []
    assert FaultManager(config).faults() == []


@upstream("N-02")
def test_n02_default_debounce_config(tmp_path: Path) -> None:
    """N-02 FaultManagerNodeTest.DefaultDebounceConfig: no overrides → conf -1."""
    config, _ = node_config(tmp_path)
    assert FaultManager(config).resolver.global_config.confirmation_threshold == -1
    assert confirming_report(config) == 1


@upstream("N-03")
def test_n03_custom_confirmation_threshold(tmp_path: Path) -> None:
    """N-03 CustomConfirmationThreshold: -5 → conf -5 (the 5th FAILED confirms)."""
    config, _ = node_config(tmp_path, "confirmation_threshold: -5")
    assert FaultManager(config).resolver.global_config.confirmation_threshold == -5
    assert confirming_report(config) == 5


@upstream("N-04")
def test_n04_confirmation_threshold_zero_sanitized_to_default(tmp_path: Path) -> None:
    """N-04 ConfirmationThresholdZeroSanitizedToDefault: 0 → -1."""
    config, _ = node_config(tmp_path, "confirmation_threshold: 0")
    assert FaultManager(config).resolver.global_config.confirmation_threshold == -1
    assert confirming_report(config) == 1


@upstream("N-05")
def test_n05_healing_enabled(tmp_path: Path) -> None:
    """N-05 HealingEnabled: true / 5 (a confirmed fault at -1 heals at the 6th PASSED)."""
    config, _ = node_config(tmp_path, "healing_enabled: true\nhealing_threshold: 5")
    global_config = FaultManager(config).resolver.global_config
    assert (global_config.healing_enabled, global_config.healing_threshold) == (True, 5)
    manager = FaultManager(config)
    report(manager, T0, "HEAL")
    statuses = []
    for i in range(6):
        report(manager, T0 + (i + 1) * S, "HEAL", event_type=PASSED)
        statuses.append(manager.storage.faults["HEAL"].status)
    assert statuses == ["CONFIRMED"] * 5 + ["HEALED"]


@upstream("N-06")
def test_n06_auto_confirm_after_sec(tmp_path: Path) -> None:
    """N-06 AutoConfirmAfterSec: 15.0 → 15 s; a PREFAILED fault confirms at the first 1 s tick
    at least 15 s after its last FAILED, silently."""
    config, _ = node_config(tmp_path, "auto_confirm_after_sec: 15.0\nconfirmation_threshold: -3")
    assert config.auto_confirm_after_ns == 15 * S
    manager = FaultManager(config)
    timeline = Timeline(manager)
    timeline.advance(T0)
    timeline.apply(
        ReportRequest(t_ns=T0, fault_code="AUTO", event_type=FAILED, severity=ERROR, source_id="/n")
    )
    timeline.advance(T0 + 14 * S)
    assert status_of(manager, "AUTO") == "PREFAILED"
    timeline.advance(T0 + 15 * S)
    assert status_of(manager, "AUTO") == "CONFIRMED"
    last = manager.output.transitions[-1]
    assert (last.cause, last.t_ns) == ("auto_confirm", T0 + 15 * S)
    assert events_of(manager) == []


def drive_near_misses(manager: FaultManager, count: int) -> int:
    """N-08's storage-direct drive: PUMP_PRESSURE_LOW WARN near misses; returns the series size."""
    config = DebounceConfig(confirmation_threshold=-1000, critical_immediate_confirm=False)
    for i in range(count):
        manager.storage.report(
            "PUMP_PRESSURE_LOW",
            FAILED,
            WARN,
            "pressure dipping",
            "/hydraulics/pump",
            1_700_000_000_000_000_000 + i * NS_PER_MS,
            config,
        )
    return len(manager.storage.near_misses["PUMP_PRESSURE_LOW"])


@pytest.mark.parametrize(
    ("params", "count", "retained"),
    [
        pytest.param("near_miss.max_per_fault: 4", 10, 4, id="N-08-AppliesNearMissRetentionBound"),
        pytest.param("", 205, 200, id="N-09-NearMissRetentionDefaultsToBounded"),
        pytest.param(
            "near_miss.max_per_fault: -5", 205, 200, id="N-10-NegativeNearMissBoundFallsBack"
        ),
        pytest.param(
            "near_miss.max_per_fault: 0", 205, 205, id="N-11-ZeroNearMissBoundIsUnlimited"
        ),
    ],
)
@upstream("N-08", "N-09", "N-10", "N-11")
def test_near_miss_retention_bound(tmp_path: Path, params: str, count: int, retained: int) -> None:
    """N-08..N-11: near_miss.max_per_fault (default 200, negative → 200, 0 = unlimited)."""
    config, _ = node_config(tmp_path, params)
    assert drive_near_misses(FaultManager(config), count) == retained


@upstream("N-inferred")
def test_n_inferred_parameter_fixups(tmp_path: Path) -> None:
    """N [I]: confirmation_threshold 3 → -3, healing_threshold -2 → 2, auto_confirm -1 → 0."""
    config, warnings = node_config(
        tmp_path,
        "confirmation_threshold: 3\nhealing_threshold: -2\nauto_confirm_after_sec: -1.0",
    )
    global_config = FaultManager(config).resolver.global_config
    assert (global_config.confirmation_threshold, global_config.healing_threshold) == (-3, 2)
    assert config.auto_confirm_after_ns == 0
    assert len(warnings) == 3
    assert confirming_report(config) == 3
    manager = FaultManager(config)
    report(manager, T0, "STUCK")
    assert manager.auto_confirm_tick(T0 + 10**6 * S) == []
