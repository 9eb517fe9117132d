"""What ``explain`` reads from the engine: correlation decisions as made, filter and band queries.

Observing changes nothing: the records are the same with or without a watcher.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.engine.correlation.rules import CorrelationConfig, CorrelationRule
from medkit_replay.engine.debounce import DebounceConfig
from medkit_replay.engine.local_filter import LocalFilter, LocalFilterConfig
from medkit_replay.engine.manager import FaultManager, FaultManagerConfig
from medkit_replay.engine.thresholds import EntityOverride, EntityThresholdResolver
from medkit_replay.model import NS_PER_SEC, ReportRequest

if TYPE_CHECKING:
    from medkit_replay.engine.correlation.engine import CorrelationResult

RULE = CorrelationRule(
    id="overheat",
    name="overheat",
    mode="hierarchical",
    window_ms=1000,
    root_cause_codes=("MOTOR_OVERHEAT",),
    inline_symptom_codes=("WHEEL_SLIP",),
)
CONFIG = FaultManagerConfig(correlation=CorrelationConfig(enabled=True, rules=(RULE,)))


def failed(t_s: float, code: str) -> ReportRequest:
    return ReportRequest(
        t_ns=round(t_s * NS_PER_SEC), fault_code=code, event_type=0, severity=2, source_id="/x"
    )


def test_the_watcher_sees_each_decision_and_changes_nothing() -> None:
    requests = [failed(1, "MOTOR_OVERHEAT"), failed(1.5, "WHEEL_SLIP"), failed(3, "WHEEL_SLIP")]
    plain, watched = FaultManager(CONFIG), FaultManager(CONFIG)
    seen: list[tuple[int, str, CorrelationResult]] = []
    watched.watch_correlation(lambda t, code, result: seen.append((t, code, result)))
    for request in requests:
        plain.report(request)
        watched.report(request)
    assert [
        (t, code, r.is_root_cause, r.root_cause_code, r.should_mute) for t, code, r in seen
    ] == [
        (1 * NS_PER_SEC, "MOTOR_OVERHEAT", True, "", False),
        (3 * NS_PER_SEC // 2, "WHEEL_SLIP", False, "MOTOR_OVERHEAT", True),
        (3 * NS_PER_SEC, "WHEEL_SLIP", False, "", False),  # the root's window had closed
    ]
    assert list(plain.output.reports) == list(watched.output.reports)
    assert list(plain.output.events) == list(watched.output.events)
    assert plain.faults() == watched.faults()


def test_the_filter_says_how_many_it_has_seen() -> None:
    local = LocalFilter(LocalFilterConfig(default_threshold=3, default_window_sec=10.0))
    assert local.tracked("X", passed=False) == 0
    assert not local.should_forward("X", 0, 1 * NS_PER_SEC)
    assert not local.should_forward("X", 0, 2 * NS_PER_SEC)
    assert local.tracked("X", passed=False) == 2 and local.tracked("X", passed=True) == 0
    assert not local.should_forward_passed("X", 3 * NS_PER_SEC)
    assert local.tracked("X", passed=True) == 1


def test_the_band_in_force_names_its_prefix() -> None:
    resolver = EntityThresholdResolver(
        DebounceConfig(),
        [EntityOverride(prefix="/robot", healing_threshold=5), EntityOverride(prefix="/robot/arm")],
    )
    assert resolver.prefix_for("/robot/arm/joint") == "/robot/arm"
    assert resolver.prefix_for("/robot/armrest") == "/robot"
    assert resolver.prefix_for("/other") is None
    assert resolver.resolve("/robot/leg").healing_threshold == 5
