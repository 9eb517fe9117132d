"""The log bridge at ros2_medkit 0.6.0 (bdcc4ed0): upstream's tests of that commit on the
parameters whose reading later changed, as data, and each 0.6.0 difference beside 0.7.0.

At 0.6.0 ``severity_floor`` and ``max_tracked_nodes`` are narrowed to int before their checks
(5ea42890 reads them as int64), a negative ``report_cooldown_sec`` becomes 0.0, which turns
the cooldown off, and ``max_tracked_nodes < 1`` becomes 1, both in silence (91035bfe).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

from medkit_replay.bridges.log import LogBridge, LogBridgeConfig
from medkit_replay.config.bridges import log_bridge_config
from medkit_replay.errors import ConfigError
from medkit_replay.model import NS_PER_SEC
from medkit_replay.releases import release_named
from tests.bridges.test_log_bridge import failed, send

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence

    from medkit_replay.releases import Release

S = NS_PER_SEC
R060, R070 = release_named("0.6.0"), release_named("0.7.0")
WARN, ERROR, FATAL = 30, 40, 50


def configured(params: Mapping[str, object], release: Release) -> LogBridge:
    config, _ = log_bridge_config(params, release)
    return LogBridge(config)


# --- Ported: LogBridgeTest.Cooldown_* and ReporterBound_* @bdcc4ed0, read as 0.6.0 reads them ---

A, B = "LOG_X_aaaa1111", "LOG_X_bbbb2222"
Check = tuple[str, int, float, bool]
"""fault code, severity, seconds, whether ``cooldown_allows`` lets it through."""

COOLDOWN: list[tuple[str, dict[str, object], list[Check]]] = [
    (
        "Cooldown_FirstPassesThenSuppressedThenReopens",
        {},
        [(A, 2, 0.0, True), (A, 2, 1.0, False), (B, 2, 1.0, True), (A, 2, 6.0, True)],
    ),
    (
        "Cooldown_KeyedBySeverity_EscalationNotSuppressed",
        {},
        [(A, 2, 0.0, True), (A, 3, 1.0, True), (A, 2, 1.0, False)],
    ),
    ("Cooldown_ZeroDisables", {"report_cooldown_sec": 0.0}, [(A, 2, 0.0, True), (A, 2, 0.0, True)]),
]


@pytest.mark.parametrize(("upstream_test", "params", "checks"), COOLDOWN)
def test_cooldown_at_060(
    upstream_test: str, params: Mapping[str, object], checks: Sequence[Check]
) -> None:
    bridge = configured(params, R060)
    seen = [bridge.cooldown_allows(code, sev, round(t * S)) for code, sev, t, _ in checks]
    assert seen == [allowed for *_, allowed in checks], upstream_test


LRU: list[tuple[str, dict[str, object], list[str], list[str], list[str]]] = [
    (
        "ReporterReuse_SameSourceReturnsSameInstance",
        {},
        ["/planner_server", "/planner_server", "/amcl"],
        ["/planner_server", "/amcl"],
        [],
    ),
    (
        "ReporterBound_LruEviction",
        {"max_tracked_nodes": 2},
        ["/n1", "/n2", "/n1", "/n3", "/n1"],
        ["/n1", "/n3"],
        ["/n2"],
    ),
]


@pytest.mark.parametrize(("upstream_test", "params", "lookups", "kept", "evicted"), LRU)
def test_reporters_at_060(
    upstream_test: str,
    params: Mapping[str, object],
    lookups: Sequence[str],
    kept: Sequence[str],
    evicted: Sequence[str],
) -> None:
    reporters = configured(params, R060).reporters
    made = [reporters.get(source) for source in lookups]
    first = {source: made[lookups.index(source)] for source in kept}
    assert len(reporters) == len(kept), upstream_test
    assert all(source in reporters for source in kept), upstream_test
    assert not any(source in reporters for source in evicted), upstream_test
    assert all(reporters.get(source) is first[source] for source in kept), upstream_test


# --- report_cooldown_sec, 0.6.0 beside 0.7.0 (91035bfe) -------------------------------------


def test_a_negative_cooldown_turns_it_off_in_silence_at_060() -> None:
    params = {"report_cooldown_sec": -1.0}
    old, old_warnings = log_bridge_config(params, R060)
    new, new_warnings = log_bridge_config(params, R070)
    assert (old.report_cooldown_sec, old_warnings) == (0.0, [])
    assert new.report_cooldown_sec == 5.0
    assert new_warnings == [
        "log_bridge: report_cooldown_sec -1.00 must be finite and >= 0. Using default 5.0."
    ]
    repeats = [(round(t * S), "planner_server", ERROR, "no path") for t in (0.0, 1.0, 2.0)]
    code = LogBridge().fault_code("/planner_server", "no path")
    every = [failed(code, t, 2, "no path", "/planner_server") for t, *_ in repeats]
    for release, expected in ((R060, every), (R070, every[:1])):
        bridge = LogBridge(log_bridge_config(params, release)[0])
        assert [r for args in repeats for r in send(bridge, *args)] == expected, release.name


def test_minus_infinity_is_negative_too() -> None:
    config, warnings = log_bridge_config({"report_cooldown_sec": float("-inf")}, R060)
    assert (config.report_cooldown_sec, warnings) == (0.0, [])


@pytest.mark.parametrize("value", [float("nan"), float("inf"), 1e300])
def test_a_cooldown_060_cannot_convert_is_refused(value: float) -> None:
    # 0.6.0 passes it into an undefined nanosecond conversion; 0.7.0 replaces it.
    with pytest.raises(ConfigError, match=r"'report_cooldown_sec' must be a finite double") as err:
        log_bridge_config({"report_cooldown_sec": value}, R060)
    assert err.value.parameter == "report_cooldown_sec"
    assert "ros2_medkit 0.6.0" in str(err.value)
    config, warnings = log_bridge_config({"report_cooldown_sec": value}, R070)
    assert config.report_cooldown_sec == 5.0
    assert len(warnings) == 1


# --- integers narrowed before their checks at 0.6.0 (5ea42890) ---------------------------------

FLOOR = "log_bridge: severity_floor={named} out of range [0,50], clamping"
BOUND = "log_bridge: max_tracked_nodes {named} clamped to {used}"
NARROWED: list[tuple[str, str, int, int, int | None, int, int | None]] = [
    # parameter, its warning, a value; the 0.6.0 result and the value its warning names
    # (None: silent); the same at 0.7.0
    ("severity_floor", FLOOR, 2**32 + 40, 40, None, 50, 2**32 + 40),
    ("severity_floor", FLOOR, 2**32 + 30, 30, None, 50, 2**32 + 30),
    ("severity_floor", FLOOR, 2**31 + 10, 0, -(2**31) + 10, 50, 2**31 + 10),
    ("severity_floor", FLOOR, -1, 0, -1, 0, -1),
    ("max_tracked_nodes", BOUND, 0, 1, None, 1, 0),
    ("max_tracked_nodes", BOUND, -5, 1, None, 1, -5),
    ("max_tracked_nodes", BOUND, 2**32 + 2, 2, None, 2**31 - 1, 2**32 + 2),
    ("max_tracked_nodes", BOUND, 2**32, 1, None, 2**31 - 1, 2**32),
]


@pytest.mark.parametrize(
    ("name", "warning", "value", "old", "old_named", "new", "new_named"), NARROWED
)
def test_integers_are_narrowed_before_their_checks_at_060(
    name: str,
    warning: str,
    value: int,
    old: int,
    old_named: int | None,
    new: int,
    new_named: int | None,
) -> None:
    for release, used, named in ((R060, old, old_named), (R070, new, new_named)):
        config, warnings = log_bridge_config({name: value}, release)
        expected = [] if named is None else [warning.format(named=named, used=used)]
        assert (getattr(config, name), warnings) == (used, expected), release.name


def test_a_wrapped_floor_lets_errors_through_at_060() -> None:
    params = {"severity_floor": 2**32 + 40, "report_cooldown_sec": 0.0}
    old, new = configured(params, R060), configured(params, R070)
    assert send(old, 1, "planner_server", WARN, "slow") == []
    assert len(send(old, 2, "planner_server", ERROR, "no path")) == 1
    assert send(new, 2, "planner_server", ERROR, "no path") == []  # floor 50: FATAL only
    assert len(send(new, 3, "planner_server", FATAL, "dead")) == 1


def test_a_wrapped_bound_evicts_reporters_at_060() -> None:
    params = {"max_tracked_nodes": 2**32 + 1}  # 1 at 0.6.0
    warns = [("a", 1), ("b", 2), ("a", 3), ("a", 4)]
    out = {}
    for release in (R060, R070):
        bridge = configured(params, release)
        out[release.name] = [r for name, t in warns for r in send(bridge, t, name, WARN, "w")]
    code = LogBridge().fault_code("/a", "w")
    assert out["0.6.0"] == []  # /b evicted /a and its first count
    assert out["0.7.0"] == [failed(code, 4, 1, "w", "/a")]


def test_the_defaults_are_the_same() -> None:
    assert log_bridge_config({}, R060) == (LogBridgeConfig(), [])


def test_the_parameters_both_releases_share_are_read_alike() -> None:
    params: dict[str, object] = {
        "rosout_topic": "/robot/rosout",
        "severity_floor": 40,
        "code_prefix": "app log",
        "exclude_nodes": ["/a"],
        "include_only_nodes": ["/b"],
        "max_tracked_nodes": 8,
        "report_cooldown_sec": 2.5,
        "exclude_medkit_stack": False,
        "fault_reporter.local_filtering.default_window_sec": 3.0,
        "fault_reporter.local_filtering.default_threshold": 2**32 + 2,
    }
    old, new = log_bridge_config(params, R060), log_bridge_config(params, R070)
    assert old == new
    assert old[0].local_filter.default_threshold == 2  # the reporter narrows at both
