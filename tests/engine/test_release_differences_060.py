"""Each fault-manager difference between 0.6.0 and 0.7.0: the same requests under both releases.

One test per difference of docs/releases.md ("Fault manager"), D1..D9, each showing the
outcome that differs; the upstream commit that changed it is named in the docstring.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Literal

import pytest

from medkit_replay.config.effective import effective_config
from medkit_replay.config.replay_options import ReplayOptions
from medkit_replay.engine.debounce import DebounceConfig
from medkit_replay.engine.manager import FaultManager, FaultManagerConfig
from medkit_replay.errors import ConfigError
from medkit_replay.model import NS_PER_SEC, ClearRequest, ReportRequest
from medkit_replay.pipeline import replay
from medkit_replay.releases import RELEASES, Release, release_named
from tests.engine.test_upstream_node_params import node_config

if TYPE_CHECKING:
    from medkit_replay.model import Status

S = NS_PER_SEC
T0 = 1_790_000_000 * S
R060, R070 = release_named("0.6.0"), release_named("0.7.0")
ERROR, CRITICAL = 2, 3
Op = Literal["F", "P", "C", "CRIT"]
CONF3 = DebounceConfig(confirmation_threshold=-3)
HEAL3 = DebounceConfig(healing_enabled=True, healing_threshold=3)
EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "nav2_mission.jsonl"


def run(
    ops: str,
    release: Release,
    debounce: DebounceConfig | None = None,
    storage_type: str = "sqlite",
    auto_confirm_after_ns: int = 0,
) -> FaultManager:
    """Requests for fault ``X`` one second apart: F(AILED), P(ASSED), C(lear), ! (CRITICAL)."""
    manager = FaultManager(
        FaultManagerConfig(
            debounce=debounce or DebounceConfig(),
            release=release,
            storage_type=storage_type,
            auto_confirm_after_ns=auto_confirm_after_ns,
        )
    )
    for n, op in enumerate(ops.replace(" ", "")):
        t_ns = T0 + n * S
        if op == "C":
            manager.clear(ClearRequest(t_ns=t_ns, fault_code="X"))
            continue
        manager.report(
            ReportRequest(
                t_ns=t_ns,
                fault_code="X",
                event_type=1 if op == "P" else 0,
                severity=CRITICAL if op == "!" else ERROR,
                description="",
                source_id="/node",
            )
        )
    return manager


def state(manager: FaultManager) -> tuple[Status, int]:
    fault = manager.storage.faults["X"]
    return fault.status, fault.counter


def events(manager: FaultManager) -> list[tuple[str, Status, int]]:
    return [(e.event_type, e.fault.status, e.fault.occurrence_count) for e in manager.output.events]


def statuses(manager: FaultManager) -> list[tuple[Status | None, Status, str]]:
    return [(t.from_status, t.to_status, t.cause) for t in manager.output.transitions]


# -- D1: counter clamp and the CONFIRMED/HEALED latch (49b2ec56, 6920ba42, b48c9052) ----------


@pytest.mark.parametrize("storage_type", ["sqlite", "memory"])
def test_d1_passed_downgrades_a_confirmed_fault_at_060(storage_type: str) -> None:
    """Conf -1, healing off: F P P ends PREPASSED at 0.6.0, CONFIRMED (latched) at 0.7.0."""
    assert state(run("FPP", R060, storage_type=storage_type)) == ("PREPASSED", 1)
    assert state(run("FPP", R070, storage_type=storage_type)) == ("CONFIRMED", 1)


def test_d1_critical_confirm_falls_back_and_confirms_twice_at_060() -> None:
    """Conf -3: CRITICAL then two ERRORs: PREFAILED in between and a second fault_confirmed."""
    old, new = run("!FF", R060, CONF3), run("!FF", R070, CONF3)
    assert [(b, a) for b, a, _ in statuses(old)] == [
        (None, "CONFIRMED"),
        ("CONFIRMED", "PREFAILED"),
        ("PREFAILED", "CONFIRMED"),
    ]
    assert [e[0] for e in events(old)] == ["fault_confirmed", "fault_confirmed"]
    assert [(b, a) for b, a, _ in statuses(new)] == [(None, "CONFIRMED")]
    assert [e[0] for e in events(new)] == ["fault_confirmed", "fault_updated", "fault_updated"]


def test_d1_runaway_counters() -> None:
    """No clamp at 0.6.0: a FAILED run-up delays healing, a PASSED heartbeat delays confirming."""
    heal = "FFFFF" + "P" * 7
    assert state(run(heal, R060, HEAL3)) == ("PREPASSED", 2)
    assert state(run(heal, R070, HEAL3)) == ("HEALED", 3)
    confirm = "F" + "P" * 10 + "F" * 6
    assert state(run(confirm, R060, CONF3)) == ("PREPASSED", 3)
    assert state(run(confirm, R070, CONF3)) == ("CONFIRMED", -3)


def test_d1_healed_left_by_one_failed_at_060() -> None:
    """HEALED then one FAILED: PREPASSED at 0.6.0, still HEALED (latched) at 0.7.0."""
    assert state(run("FPPPP F", R060, HEAL3)) == ("PREPASSED", 2)
    assert state(run("FPPPP F", R070, HEAL3)) == ("HEALED", 2)


# -- D2: occurrence_count (67bdb9cb) ------------------------------------------------------------


def test_d2_every_failed_counts_at_060() -> None:
    """Three FAILED on a confirmed fault: events carry counts 1, 2, 3 at 0.6.0; 1, 1, 1 at 0.7.0;
    a reactivation after a clear counts at both."""
    assert [e[2] for e in events(run("FFF", R060))] == [1, 2, 3]
    assert [e[2] for e in events(run("FFF", R070))] == [1, 1, 1]
    assert run("FFFCF", R060).storage.faults["X"].occurrence_count == 4
    assert run("FFFCF", R070).storage.faults["X"].occurrence_count == 2


# -- D3: PASSED moves last_occurred (d27fc3eb) --------------------------------------------------


def test_d3_passed_redates_a_fault_at_060() -> None:
    old, new = run("FP", R060).storage.faults["X"], run("FP", R070).storage.faults["X"]
    assert (old.last_occurred_ns, old.last_passed_ns) == (T0 + S, T0 + S)
    assert (new.last_occurred_ns, new.last_passed_ns) == (T0, T0 + S)


# -- D4: reactivation and first_occurred (67bdb9cb) ---------------------------------------------


def test_d4_reactivation_keeps_first_occurred_at_060() -> None:
    assert run("FCF", R060).storage.faults["X"].first_occurred_ns == T0
    assert run("FCF", R070).storage.faults["X"].first_occurred_ns == T0 + 2 * S


# -- D5: no event on healing (d27fc3eb) ---------------------------------------------------------


def test_d5_healing_publishes_nothing_at_060() -> None:
    old, new = events(run("FPPPP", R060, HEAL3)), events(run("FPPPP", R070, HEAL3))
    assert all(kind != "fault_cleared" for kind, _, _ in old)
    assert old == [("fault_confirmed", "CONFIRMED", 1), ("fault_updated", "CONFIRMED", 1)]
    assert new[-1] == ("fault_cleared", "HEALED", 1)


# -- D6: auto-confirm without the latch ----------------------------------------------------------


def test_d6_auto_confirmed_fault_falls_back_and_confirms_again_at_060() -> None:
    """Conf -3, auto-confirm 10 s: the timer confirms, a FAILED takes it back to PREFAILED at
    0.6.0 (the counter is -2) and the timer confirms it a second time."""
    after = 10 * S
    for release, expected in (
        (R060, ["auto_confirm", "report", "auto_confirm"]),
        (R070, ["auto_confirm"]),
    ):
        manager = run("F", release, CONF3, auto_confirm_after_ns=after)
        manager.auto_confirm_tick(T0 + after)
        manager.report(
            ReportRequest(
                t_ns=T0 + after + S,
                fault_code="X",
                event_type=0,
                severity=ERROR,
                description="",
                source_id="/node",
            )
        )
        manager.auto_confirm_tick(T0 + 2 * after + S)
        changes = [cause for _, _, cause in statuses(manager)][1:]
        assert changes == expected, release.name


# -- D7: threshold sanitising (6920ba42, e9697424) ----------------------------------------------


_config = node_config


def test_d7_confirmation_threshold_zero_is_kept_at_060(tmp_path: Path) -> None:
    old, old_warnings = _config(tmp_path, "confirmation_threshold: 0", R060)
    new, new_warnings = _config(tmp_path, "confirmation_threshold: 0", R070)
    assert old.debounce.confirmation_threshold == 0
    assert not any("invalid" in w for w in old_warnings)
    assert new.debounce.confirmation_threshold == 0  # the manager sanitises it
    assert any("confirmation_threshold 0 is invalid" in w for w in new_warnings)
    # At 0.6.0 counter 0 is confirmed: PREPASSED at 1, a FAILED back to 0 confirms again.
    kinds_old = [e[0] for e in events(run("FPPF", R060, old.debounce))]
    kinds_new = [e[0] for e in events(run("FPPF", R070, new.debounce))]
    assert kinds_old == ["fault_confirmed", "fault_updated", "fault_confirmed"]
    assert kinds_new == ["fault_confirmed", "fault_updated", "fault_updated", "fault_updated"]


def test_d7_entity_threshold_zero_is_kept_at_060(tmp_path: Path) -> None:
    (tmp_path / "entities.yaml").write_text("/robot:\n  confirmation_threshold: 0\n")
    body = 'confirmation_threshold: -3\nentity_thresholds.config_file: "entities.yaml"'
    resolved = {
        release.name: FaultManager(_config(tmp_path, body, release)[0]).resolver.resolve(
            "/robot/arm"
        )
        for release in (R060, R070)
    }
    assert resolved["0.6.0"].confirmation_threshold == 0
    assert resolved["0.7.0"].confirmation_threshold == -1


def test_d7_wrapped_threshold_is_not_replaced_at_060(tmp_path: Path) -> None:
    """-(2**31 + 1) wraps to a positive int32: kept at 0.6.0, sanitised to -1 at 0.7.0."""
    old, old_warnings = _config(tmp_path, f"confirmation_threshold: {-(2**31) - 1}", R060)
    new, _ = _config(tmp_path, f"confirmation_threshold: {-(2**31) - 1}", R070)
    assert old.debounce.confirmation_threshold == 2**31 - 1
    assert any(f"using {2**31 - 1}" in w for w in old_warnings)
    assert FaultManager(old).resolver.global_config.confirmation_threshold == 2**31 - 1
    assert FaultManager(new).resolver.global_config.confirmation_threshold == -1


# -- D8: near misses (aeb1e9d7) -----------------------------------------------------------------


def test_d8_no_near_misses_at_060(tmp_path: Path) -> None:
    assert run("FF", R060, CONF3).storage.near_misses == {}
    assert len(run("FF", R070, CONF3).storage.near_misses["X"]) == 2
    # The parameter is undeclared at 0.6.0: a bad value is not even read.
    _, old_warnings = _config(tmp_path, "near_miss.max_per_fault: -5", R060)
    _, new_warnings = _config(tmp_path, "near_miss.max_per_fault: -5", R070)
    assert not any("near_miss" in w for w in old_warnings)
    assert any("near_miss.max_per_fault -5" in w for w in new_warnings)


# -- D9: the two backends at 0.6.0 (6920ba42) ---------------------------------------------------


def test_d9_passed_after_a_failed_run_up() -> None:
    """Conf -1, 3 FAILED then 1 PASSED: in-memory CONFIRMED (fault_updated), SQLite PREFAILED;
    one rule for both at 0.7.0."""
    memory, sqlite = run("FFFP", R060, storage_type="memory"), run("FFFP", R060)
    assert state(memory) == ("CONFIRMED", -2)
    assert events(memory)[-1] == ("fault_updated", "CONFIRMED", 3)
    assert state(sqlite) == ("PREFAILED", -2)
    assert len(events(sqlite)) == 3
    assert state(run("FFFP", R070, storage_type="memory")) == state(run("FFFP", R070))


def test_d9_failed_after_a_passed_run_up() -> None:
    """Healing on: a FAILED leaving the counter at or above healing is HEALED in memory and
    PREPASSED in SQLite at 0.6.0."""
    ops = "F PPPP PPP F"
    assert state(run(ops, R060, HEAL3, storage_type="memory")) == ("HEALED", 5)
    assert state(run(ops, R060, HEAL3)) == ("PREPASSED", 5)
    assert state(run(ops, R070, HEAL3, storage_type="memory")) == ("HEALED", 2)
    assert state(run(ops, R070, HEAL3)) == ("HEALED", 2)


def test_storage_type_parameter(tmp_path: Path) -> None:
    """storage_type as upstream reads it: sqlite by default, an unknown name is in-memory."""
    for release in RELEASES.values():
        assert _config(tmp_path, "", release)[0].storage_type == "sqlite"
        assert _config(tmp_path, 'storage_type: "memory"', release)[0].storage_type == "memory"
        config, warnings = _config(tmp_path, 'storage_type: "redis"', release)
        assert config.storage_type == "memory"
        assert any("storage_type 'redis' is unknown" in w for w in warnings)
        with pytest.raises(ConfigError, match="storage_type"):
            _config(tmp_path, "storage_type: 3", release)


def test_storage_type_is_not_a_report_key() -> None:
    """The report's configuration keeps its keys at every release."""
    shown = effective_config(FaultManagerConfig(storage_type="memory"), ReplayOptions(), ())
    fault_manager = shown["fault_manager"]
    assert isinstance(fault_manager, dict)
    assert "storage_type" not in fault_manager
    assert "release" not in fault_manager


def test_replay_of_the_example_mission_under_each_release(tmp_path: Path) -> None:
    """The parameter reaches the engine: the example mission's near misses are gone at 0.6.0."""
    results = {}
    for name in ("0.6.0", "0.7.0"):
        config = tmp_path / f"{name}.yaml"
        config.write_text(
            "medkit_replay:\n  ros__parameters:\n"
            f'    upstream_release: "{name}"\n'
            "fault_manager:\n  ros__parameters:\n    confirmation_threshold: -3\n"
        )
        results[name] = replay([EXAMPLE], [config])
    assert results["0.6.0"].near_misses == ()
    assert results["0.7.0"].near_misses != ()


def test_d9_new_fault_under_a_wrapped_healing_threshold(tmp_path: Path) -> None:
    """healing_threshold 2**31 wraps to INT32_MIN, kept at 0.6.0: in-memory storage checks
    healing on a new fault and creates it HEALED, SQLite (FAILED: no healing check) PREFAILED;
    0.7.0 sanitises it to 3."""
    body = "confirmation_threshold: -3\nhealing_enabled: true\nhealing_threshold: 2147483648"
    old, _ = _config(tmp_path, body, R060)
    assert old.debounce.healing_threshold == -(2**31)
    assert state(run("F", R060, old.debounce, storage_type="memory")) == ("HEALED", -1)
    assert state(run("F", R060, old.debounce)) == ("PREFAILED", -1)
    new, _ = _config(tmp_path, body, R070)
    assert state(run("F", R070, new.debounce, storage_type="memory")) == ("PREFAILED", -1)


def test_d9_both_thresholds_zero() -> None:
    """Conf 0, heal 0, healing on (0.6.0 keeps both): F then P is CONFIRMED in memory, HEALED in
    SQLite; 0.7.0 (conf sanitised to -1 by the manager) heals it on both."""
    zero = DebounceConfig(confirmation_threshold=0, healing_enabled=True, healing_threshold=0)
    assert state(run("FP", R060, zero, storage_type="memory")) == ("CONFIRMED", 0)
    assert state(run("FP", R060, zero)) == ("HEALED", 0)
    assert state(run("FP", R070, zero, storage_type="memory")) == ("HEALED", 0)
    assert state(run("FP", R070, zero)) == ("HEALED", 0)
