"""Correlation quirks a conformant port reproduces (correlation.md §6, §7, §11: Q1-Q11, X*).

Each scenario was observed on upstream's engine; t is ms from the scenario start.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.engine import FaultManager, FaultManagerConfig
from medkit_replay.engine.correlation import (
    CorrelationConfig,
    CorrelationEngine,
    CorrelationResult,
    CorrelationRule,
    Representative,
)
from medkit_replay.model import NS_PER_MS, ClearRequest, MutedFault, ReportRequest

if TYPE_CHECKING:
    from collections.abc import Mapping

T0 = 1_760_000_000 * 1_000_000_000


def ms(t_ms: int) -> int:
    """Scenario time in ms → bag time in ns."""
    return T0 + t_ms * NS_PER_MS


def hier(
    rule_id: str,
    roots: tuple[str, ...],
    *,
    symptoms: tuple[str, ...] = (),
    inline: tuple[str, ...] = (),
    window_ms: int = 500,
    mute: bool = True,
    auto_clear: bool = True,
) -> CorrelationRule:
    """A hierarchical rule."""
    return CorrelationRule(
        id=rule_id,
        name=rule_id,
        mode="hierarchical",
        root_cause_codes=roots,
        symptom_pattern_ids=symptoms,
        inline_symptom_codes=inline,
        window_ms=window_ms,
        mute_symptoms=mute,
        auto_clear_with_root=auto_clear,
    )


def clustering(
    rule_id: str,
    match: tuple[str, ...],
    *,
    min_count: int = 3,
    window_ms: int = 500,
    single: bool = True,
    rep: Representative = Representative.HIGHEST_SEVERITY,
) -> CorrelationRule:
    """An auto-cluster rule."""
    return CorrelationRule(
        id=rule_id,
        name=rule_id,
        mode="auto_cluster",
        match_pattern_ids=match,
        min_count=min_count,
        window_ms=window_ms,
        show_as_single=single,
        representative=rep,
    )


def engine_of(
    *rules: CorrelationRule, patterns: Mapping[str, tuple[str, ...]] | None = None
) -> CorrelationEngine:
    """An engine over the given rules and patterns."""
    return CorrelationEngine(
        CorrelationConfig(enabled=True, patterns=dict(patterns or {}), rules=tuple(rules))
    )


def fault(engine: CorrelationEngine, code: str, t_ms: int, sev: str = "ERROR") -> CorrelationResult:
    """`F code SEV` at t."""
    return engine.process_fault(code, sev, ms(t_ms))


def muted(code: str, root: str, rule: str, delay: int) -> MutedFault:
    """One expected muted entry."""
    return MutedFault(fault_code=code, root_cause_code=root, rule_id=rule, delay_ms=delay)


def root(rule: str) -> CorrelationResult:
    """A root-cause result."""
    return CorrelationResult(is_root_cause=True, rule_id=rule)


def symptom(rc: str, rule: str, delay: int, *, mute: bool = True) -> CorrelationResult:
    """A symptom result."""
    return CorrelationResult(should_mute=mute, root_cause_code=rc, rule_id=rule, delay_ms=delay)


def member(cid: str, *, mute: bool = False, retro: tuple[str, ...] = ()) -> CorrelationResult:
    """A cluster result."""
    return CorrelationResult(should_mute=mute, cluster_id=cid, retroactive_mute_codes=retro)


NOTHING = CorrelationResult()
MOTOR: dict[str, tuple[str, ...]] = {"motor": ("MOTOR_*",)}
ESTOP_MOTOR = hier("estop", ("ESTOP_001",), symptoms=("motor",), window_ms=1000)
COMM: dict[str, tuple[str, ...]] = {"comm": ("*_COMM_*", "*_TIMEOUT")}
COMM_STORM = clustering("comm_storm", ("comm",), min_count=3, window_ms=500)


# -- hierarchical ---------------------------------------------------------------------------


def test_q1_x01_root_rereport_resets_its_symptom_list() -> None:
    """Q1/X01: auto-clear covers only symptoms since the last root report; older stay muted."""
    engine = engine_of(ESTOP_MOTOR, patterns=MOTOR)
    assert fault(engine, "ESTOP_001", 0) == root("estop")
    assert fault(engine, "MOTOR_A", 10) == symptom("ESTOP_001", "estop", 10)
    assert fault(engine, "ESTOP_001", 20) == root("estop")
    # The oldest in-window entry (t0) is still the one measured from.
    assert fault(engine, "MOTOR_B", 30) == symptom("ESTOP_001", "estop", 30)
    assert engine.process_clear("ESTOP_001") == ["MOTOR_B"]
    assert engine.muted_faults() == [muted("MOTOR_A", "ESTOP_001", "estop", 10)]
    assert engine.process_clear("MOTOR_A") == []
    assert engine.muted_count == 0


def test_q2_x02_muted_entry_outlives_the_window() -> None:
    """Q2/X02: later unmuted reports and expiry leave the muted entry; only clears remove it."""
    engine = engine_of(ESTOP_MOTOR, patterns=MOTOR)
    fault(engine, "ESTOP_001", 0)
    assert fault(engine, "MOTOR_A", 100) == symptom("ESTOP_001", "estop", 100)
    assert fault(engine, "MOTOR_A", 5000) == NOTHING
    engine.cleanup_expired(ms(10_000))
    assert engine.muted_faults() == [muted("MOTOR_A", "ESTOP_001", "estop", 100)]
    engine.process_clear("MOTOR_A")
    assert engine.muted_count == 0


def test_q3_x03_reattribution_overwrites_the_muted_entry() -> None:
    """Q3/X03: a new attribution overwrites delay, root and rule of the muted entry."""
    engine = engine_of(
        hier("r1", ("ESTOP_001",), symptoms=("motor",), window_ms=1000),
        hier("r2", ("POWER_LOSS",), symptoms=("motor",), window_ms=1000),
        patterns=MOTOR,
    )
    fault(engine, "ESTOP_001", 0)
    assert fault(engine, "MOTOR_X", 100) == symptom("ESTOP_001", "r1", 100)
    assert fault(engine, "POWER_LOSS", 2000) == root("r2")
    assert fault(engine, "MOTOR_X", 2300) == symptom("POWER_LOSS", "r2", 300)
    assert engine.muted_faults() == [muted("MOTOR_X", "POWER_LOSS", "r2", 300)]


def test_q4_x06_mute_symptoms_false_still_attributes() -> None:
    """Q4/X06: not muted and not in `muted`, yet attributed and auto-cleared with the root."""
    engine = engine_of(hier("r", ("ESTOP_001",), symptoms=("motor",), mute=False), patterns=MOTOR)
    fault(engine, "ESTOP_001", 0)
    assert fault(engine, "MOTOR_A", 40) == symptom("ESTOP_001", "r", 40, mute=False)
    assert engine.muted_count == 0
    assert engine.muted_faults() == []
    assert engine.process_clear("ESTOP_001") == ["MOTOR_A"]


def test_q5_x05_auto_clear_false_returns_nothing_but_unmutes() -> None:
    """Q5/X05: auto_clear_with_root false → clear returns [] and un-mutes the symptoms."""
    engine = engine_of(
        hier("r", ("ESTOP_001",), symptoms=("motor",), auto_clear=False), patterns=MOTOR
    )
    fault(engine, "ESTOP_001", 0)
    fault(engine, "MOTOR_A", 10)
    fault(engine, "MOTOR_B", 20)
    assert engine.muted_count == 2
    assert engine.process_clear("ESTOP_001") == []
    assert engine.muted_count == 0


def test_x07_auto_clear_lists_symptoms_already_cleared() -> None:
    """X07 (§7.1): a symptom cleared on its own stays in its root's list."""
    engine = engine_of(ESTOP_MOTOR, patterns=MOTOR)
    fault(engine, "ESTOP_001", 0)
    fault(engine, "MOTOR_A", 10)
    fault(engine, "MOTOR_B", 20)
    assert engine.process_clear("MOTOR_A") == []
    assert engine.muted_faults() == [muted("MOTOR_B", "ESTOP_001", "estop", 20)]
    assert engine.process_clear("ESTOP_001") == ["MOTOR_A", "MOTOR_B"]


def test_x08_symptom_is_not_clustered() -> None:
    """X08 (§6, §10.1): a symptom is not clustered; once the window is over it may be."""
    engine = engine_of(
        hier("estop", ("ESTOP_001",), symptoms=("motor",), window_ms=500),
        clustering("motor_storm", ("motor",), min_count=2, rep=Representative.FIRST),
        patterns=MOTOR,
    )
    fault(engine, "ESTOP_001", 0)
    assert fault(engine, "MOTOR_A", 10) == symptom("ESTOP_001", "estop", 10)
    assert fault(engine, "MOTOR_B", 20) == symptom("ESTOP_001", "estop", 20)
    assert engine.cluster_count == 0
    assert fault(engine, "MOTOR_C", 600) == member("motor_storm_1")
    assert fault(engine, "MOTOR_A", 610) == member("motor_storm_1", mute=True)
    assert engine.cluster_count == 1
    assert engine.clusters()[0].fault_codes == ("MOTOR_C", "MOTOR_A")
    assert engine.muted_count == 2  # the hierarchical entries stay (Q2)


def test_x09_symptom_is_not_a_root_then_acts_as_one() -> None:
    """X09 (§6, Q3): a symptom is not checked as a root; later, as a root, it keeps its entry."""
    engine = engine_of(
        hier("r_estop", ("ESTOP",), inline=("POWER_LOSS",), window_ms=500),
        hier("r_power", ("POWER_LOSS",), symptoms=("motor",), window_ms=500),
        patterns=MOTOR,
    )
    assert fault(engine, "ESTOP", 0) == root("r_estop")
    assert fault(engine, "POWER_LOSS", 10) == symptom("ESTOP", "r_estop", 10)
    assert fault(engine, "MOTOR_A", 20) == NOTHING  # POWER_LOSS opened no window
    assert fault(engine, "POWER_LOSS", 1000) == root("r_power")
    assert fault(engine, "MOTOR_A", 1100) == symptom("POWER_LOSS", "r_power", 100)
    assert engine.muted_faults() == [
        muted("MOTOR_A", "POWER_LOSS", "r_power", 100),
        muted("POWER_LOSS", "ESTOP", "r_estop", 10),
    ]


def test_x10_root_that_matches_its_own_symptoms() -> None:
    """X10 (§6): the 2nd report of such a root is its own symptom; its clear lists itself."""
    engine = engine_of(hier("r", ("ESTOP_001",), inline=("ESTOP_*",), window_ms=1000))
    assert fault(engine, "ESTOP_001", 0) == root("r")
    assert fault(engine, "ESTOP_001", 100) == symptom("ESTOP_001", "r", 100)
    assert engine.muted_faults() == [muted("ESTOP_001", "ESTOP_001", "r", 100)]
    assert engine.process_clear("ESTOP_001") == ["ESTOP_001"]
    assert engine.muted_count == 0


def test_x11_oldest_pending_root_wins() -> None:
    """X11 (§6, §10.2): with several pending roots matching, the oldest entry wins."""
    engine = engine_of(
        hier("ra", ("A_ROOT",), inline=("S_*",), window_ms=1000),
        hier("rb", ("B_ROOT",), inline=("S_*",), window_ms=1000),
    )
    assert fault(engine, "B_ROOT", 0) == root("rb")
    assert fault(engine, "A_ROOT", 10) == root("ra")
    assert fault(engine, "S_1", 20) == symptom("B_ROOT", "rb", 20)
    assert engine.process_clear("A_ROOT") == []
    assert engine.process_clear("B_ROOT") == ["S_1"]


def test_x12_first_rule_owns_a_shared_root_code() -> None:
    """X12 (§6): two rules with one root code; only the first's symptoms are attributed."""
    engine = engine_of(
        hier("r1", ("ESTOP",), inline=("MOTOR_*",), window_ms=1000),
        hier("r2", ("ESTOP",), inline=("DRIVE_*",), window_ms=1000),
    )
    assert fault(engine, "ESTOP", 0) == root("r1")
    assert fault(engine, "DRIVE_X", 10) == NOTHING
    assert fault(engine, "MOTOR_X", 20) == symptom("ESTOP", "r1", 20)


def test_x13_x14_auto_clear_is_the_union_over_matching_rules() -> None:
    """§7.1 (X13/X14): auto-clear if ANY hierarchical rule of the root has it, expired or not."""
    engine = engine_of(
        hier("r1", ("ESTOP",), inline=("MOTOR_*",), auto_clear=False),
        hier("r2", ("ESTOP",), inline=("DRIVE_*",), auto_clear=True),
    )
    fault(engine, "ESTOP", 0)
    assert fault(engine, "MOTOR_A", 10) == symptom("ESTOP", "r1", 10)
    engine.cleanup_expired(ms(5000))  # the root's window is long over
    assert engine.process_clear("ESTOP") == ["MOTOR_A"]


def test_x15_negative_elapsed_wraps_the_delay() -> None:
    """X15 (§6): a symptom stamped before its root is in-window; delay wraps modulo 2^32.

    -50.5 ms truncates toward zero to -50 (floor division would give -51).
    """
    engine = engine_of(ESTOP_MOTOR, patterns=MOTOR)
    fault(engine, "ESTOP_001", 1000)
    result = engine.process_fault("MOTOR_A", "ERROR", ms(949) + 500_000)
    assert result == symptom("ESTOP_001", "estop", 4294967246)
    assert engine.muted_faults() == [muted("MOTOR_A", "ESTOP_001", "estop", 4294967246)]


def test_x28_cleared_root_mutes_nothing_more() -> None:
    """X28 (§7.2): process_clear drops every pending entry of the root."""
    engine = engine_of(ESTOP_MOTOR, patterns=MOTOR)
    fault(engine, "ESTOP_001", 0)
    fault(engine, "ESTOP_001", 5)
    assert fault(engine, "MOTOR_A", 10).should_mute is True
    assert engine.process_clear("ESTOP_001") == ["MOTOR_A"]
    assert fault(engine, "MOTOR_B", 20) == NOTHING
    assert engine.muted_count == 0


def test_x33_sub_millisecond_truncation() -> None:
    """X33 (§6): elapsed is truncated to whole ms; the window boundary is inclusive."""
    engine = engine_of(ESTOP_MOTOR, patterns=MOTOR)
    fault(engine, "ESTOP_001", 0)
    result = engine.process_fault("MOTOR_A", "ERROR", ms(1000) + 999_999)
    assert result == symptom("ESTOP_001", "estop", 1000)
    assert fault(engine, "MOTOR_B", 1001) == NOTHING


# -- auto-cluster ---------------------------------------------------------------------------


def test_q6_cluster_mutes_are_not_muted_entries() -> None:
    """Q6: cluster mutes never enter `muted` or muted_count."""
    engine = engine_of(COMM_STORM, patterns=COMM)
    fault(engine, "MOTOR_COMM_FL", 0)
    fault(engine, "SENSOR_TIMEOUT", 10)
    result = fault(engine, "DRIVE_COMM_ERROR", 20)
    assert result == member("comm_storm_1", mute=True, retro=("SENSOR_TIMEOUT",))
    assert engine.muted_count == 0
    assert engine.muted_faults() == []


def test_q6_node_cluster_mute_is_event_only() -> None:
    """Q6 at the node: the muted member is listed, not flagged muted, and has no event."""
    manager = FaultManager(
        FaultManagerConfig(
            correlation=CorrelationConfig(enabled=True, patterns=COMM, rules=(COMM_STORM,))
        )
    )
    for code, t in (("MOTOR_COMM_FL", 0), ("SENSOR_TIMEOUT", 10), ("DRIVE_COMM_ERROR", 20)):
        manager.report(
            ReportRequest(t_ns=ms(t), fault_code=code, event_type=0, severity=2, source_id="/n")
        )
    assert [e.fault.fault_code for e in manager.output.events] == [
        "MOTOR_COMM_FL",
        "SENSOR_TIMEOUT",
    ]
    listed = {f.fault_code: f for f in manager.faults()}
    assert set(listed) == {"MOTOR_COMM_FL", "SENSOR_TIMEOUT", "DRIVE_COMM_ERROR"}
    assert listed["DRIVE_COMM_ERROR"].status == "CONFIRMED"
    assert listed["DRIVE_COMM_ERROR"].muted is False
    assert listed["SENSOR_TIMEOUT"].muted is False  # the retro list changes nothing


def test_q7_x16_min_count_one_activates_at_the_second_code() -> None:
    """Q7/X16: the start path never checks min_count, so 1 behaves like 2."""
    engine = engine_of(clustering("r", ("comm",), min_count=1), patterns=COMM)
    assert fault(engine, "A_COMM_1", 0) == member("r_1")
    assert fault(engine, "A_COMM_1", 5) == member("r_1")  # duplicate: no activation
    assert engine.cluster_count == 0
    assert fault(engine, "B_COMM_2", 10) == member("r_1", mute=True)
    assert engine.cluster_count == 1


def test_q7_x37_a_repeated_code_never_activates_and_duplicates_change_nothing() -> None:
    """Q7/X37 (§6.3): duplicates leave last_at, severity and representative alone."""
    engine = engine_of(clustering("r", ("comm",), min_count=1), patterns=COMM)
    for t in (0, 10, 20):
        assert fault(engine, "A_COMM_1", t, "CRITICAL") == member("r_1")
    assert engine.cluster_count == 0
    assert fault(engine, "B_COMM_2", 30, "WARNING") == member("r_1", mute=True)
    assert fault(engine, "B_COMM_2", 40, "CRITICAL") == member("r_1", mute=True)
    assert fault(engine, "A_COMM_1", 50, "INFO") == member("r_1")
    (only,) = engine.clusters()
    assert (only.representative_code, only.representative_severity) == ("A_COMM_1", "CRITICAL")
    assert only.fault_codes == ("A_COMM_1", "B_COMM_2")
    assert (only.first_at_ns, only.last_at_ns) == (ms(0), ms(30))


def test_x17_most_recent_never_mutes_a_new_member() -> None:
    """X17 (§6): with most_recent only duplicates are ever muted."""
    engine = engine_of(
        clustering("r", ("comm",), min_count=2, rep=Representative.MOST_RECENT), patterns=COMM
    )
    assert fault(engine, "A_COMM_1", 0) == member("r_1")
    assert fault(engine, "B_COMM_2", 10) == member("r_1", retro=("A_COMM_1",))
    assert fault(engine, "C_COMM_3", 20) == member("r_1")
    assert fault(engine, "A_COMM_1", 30) == member("r_1", mute=True)
    assert fault(engine, "C_COMM_3", 40) == member("r_1")  # the representative itself
    assert engine.clusters()[0].representative_code == "C_COMM_3"


def test_x19_show_as_single_false_never_mutes() -> None:
    """X19 (§6): no mutes and no retro lists, but the cluster still forms."""
    engine = engine_of(clustering("r", ("comm",), min_count=2, single=False), patterns=COMM)
    assert fault(engine, "A_COMM_1", 0) == member("r_1")
    assert fault(engine, "B_COMM_2", 10, "CRITICAL") == member("r_1")
    assert fault(engine, "C_COMM_3", 20) == member("r_1")
    assert fault(engine, "A_COMM_1", 30) == member("r_1")
    assert engine.cluster_count == 1
    assert engine.clusters()[0].representative_code == "B_COMM_2"


def test_x20_first_matching_cluster_rule_only_and_a_global_counter() -> None:
    """X20 (§6.3, §10.5): later cluster rules never see a fault; ids share one counter."""
    engine = engine_of(
        clustering("ra", ("pa",), min_count=2),
        clustering("rb", ("pb",), min_count=2),
        clustering("rab", ("pab",), min_count=2),
        patterns={"pa": ("A_*",), "pb": ("B_*",), "pab": ("A_*", "B_*")},
    )
    assert fault(engine, "A_1", 0) == member("ra_1")
    assert fault(engine, "B_1", 10) == member("rb_2")
    assert fault(engine, "A_2", 20) == member("ra_1", mute=True)
    assert fault(engine, "B_2", 30) == member("rb_2", mute=True)
    assert [(c.cluster_id, c.rule_id) for c in engine.clusters()] == [
        ("ra_1", "ra"),
        ("rb_2", "rb"),
    ]


def test_q8_x22_several_active_clusters_per_rule() -> None:
    """Q8/X22 (§7.3): a code that rejoins a newer cluster leaves only that one when cleared."""
    engine = engine_of(COMM_STORM, patterns=COMM)
    fault(engine, "MOTOR_COMM_FL", 0)
    fault(engine, "SENSOR_TIMEOUT", 10)
    fault(engine, "DRIVE_COMM_ERROR", 20)
    assert fault(engine, "MOTOR_COMM_FL", 1000) == member("comm_storm_2")
    fault(engine, "SENSOR_TIMEOUT", 1010)
    assert fault(engine, "X_COMM_Y", 1020).cluster_id == "comm_storm_2"
    assert [c.cluster_id for c in engine.clusters()] == ["comm_storm_1", "comm_storm_2"]
    engine.process_clear("MOTOR_COMM_FL")
    first, second = engine.clusters()
    assert first.fault_codes == ("MOTOR_COMM_FL", "SENSOR_TIMEOUT", "DRIVE_COMM_ERROR")
    assert first.representative_code == "MOTOR_COMM_FL"
    assert second.fault_codes == ("SENSOR_TIMEOUT", "X_COMM_Y")
    assert (second.representative_code, second.representative_severity) == (
        "SENSOR_TIMEOUT",
        "ERROR",
    )
    assert engine.cluster_count == 2


def test_x22_cluster_ids_sort_as_strings() -> None:
    """§1.4/§10.4: clusters are listed by cluster_id in byte order (r_10 before r_2)."""
    engine = engine_of(clustering("r", ("comm",), min_count=2, window_ms=1), patterns=COMM)
    for n in range(10):
        fault(engine, f"A{n}_COMM_X", n * 10)
        fault(engine, f"B{n}_COMM_X", n * 10 + 1)
    assert [c.cluster_id for c in engine.clusters()] == [f"r_{i}" for i in (1, 10, *range(2, 10))]


def test_x26_a_root_code_is_never_clustered() -> None:
    """X26 (§6.2): root check runs before clustering."""
    engine = engine_of(
        hier("estop", ("ESTOP_*",), symptoms=("motor",)),
        clustering("storm", ("any",), min_count=2),
        patterns={"motor": ("MOTOR_*",), "any": ("*",)},
    )
    assert fault(engine, "ESTOP_001", 0) == root("estop")
    assert fault(engine, "ESTOP_002", 10) == root("estop")
    assert fault(engine, "ESTOP_001", 2000) == root("estop")
    assert engine.cluster_count == 0


def test_q9_x32_stale_representative_after_a_newer_window() -> None:
    """Q9/X32 (§7.3): the pending twin was replaced, so the cleared rep stays."""
    engine = engine_of(COMM_STORM, patterns=COMM)
    fault(engine, "MOTOR_COMM_FL", 0)
    fault(engine, "SENSOR_TIMEOUT", 10)
    fault(engine, "DRIVE_COMM_ERROR", 20, "WARNING")
    assert fault(engine, "A_COMM_B", 600) == member("comm_storm_2")
    engine.process_clear("MOTOR_COMM_FL")
    (stale,) = engine.clusters()
    assert stale.fault_codes == ("SENSOR_TIMEOUT", "DRIVE_COMM_ERROR")
    assert (stale.representative_code, stale.representative_severity) == ("MOTOR_COMM_FL", "ERROR")


def test_x38_representative_reassigned_without_a_cleanup_tick() -> None:
    """X38 (§8): E17 without the tick: the pending twin exists, so the rep is reassigned."""
    engine = engine_of(COMM_STORM, patterns=COMM)
    fault(engine, "MOTOR_COMM_FL", 0)
    fault(engine, "SENSOR_TIMEOUT", 10)
    fault(engine, "DRIVE_COMM_ERROR", 20, "WARNING")
    assert engine.process_clear("MOTOR_COMM_FL") == []
    (only,) = engine.clusters()
    assert only.fault_codes == ("SENSOR_TIMEOUT", "DRIVE_COMM_ERROR")
    assert (only.representative_code, only.representative_severity) == ("SENSOR_TIMEOUT", "ERROR")


def test_x35_the_cluster_window_does_not_slide() -> None:
    """X35 (§6.3.1): the window runs from the first member, not the latest."""
    engine = engine_of(COMM_STORM, patterns=COMM)
    assert fault(engine, "A_COMM_1", 0) == member("comm_storm_1")
    assert fault(engine, "B_COMM_2", 400) == member("comm_storm_1")
    assert fault(engine, "C_COMM_3", 800) == member("comm_storm_2")
    assert engine.cluster_count == 0


def test_cluster_window_boundary_is_inclusive() -> None:
    """§6: elapsed == window_ms is inside the cluster window."""
    engine = engine_of(COMM_STORM, patterns=COMM)
    fault(engine, "A_COMM_1", 0)
    fault(engine, "B_COMM_2", 250)
    assert fault(engine, "C_COMM_3", 500) == member("comm_storm_1", mute=True, retro=("B_COMM_2",))


def test_active_cluster_never_deactivates_and_dies_with_its_last_member() -> None:
    """§7.3: below min_count it stays active; empty, it is deleted."""
    engine = engine_of(COMM_STORM, patterns=COMM)
    for code, t in (("A_COMM_1", 0), ("B_COMM_2", 10), ("C_COMM_3", 20)):
        fault(engine, code, t)
    engine.process_clear("A_COMM_1")
    engine.process_clear("B_COMM_2")
    assert engine.cluster_count == 1
    assert engine.clusters()[0].fault_codes == ("C_COMM_3",)
    engine.process_clear("C_COMM_3")
    assert engine.cluster_count == 0


# -- node level: clears -------------------------------------------------------------------


def _manager(*rules: CorrelationRule, patterns: Mapping[str, tuple[str, ...]]) -> FaultManager:
    config = CorrelationConfig(enabled=True, patterns=dict(patterns), rules=tuple(rules))
    return FaultManager(FaultManagerConfig(correlation=config))


def _fail(manager: FaultManager, code: str, t_ms: int) -> None:
    manager.report(
        ReportRequest(t_ns=ms(t_ms), fault_code=code, event_type=0, severity=3, source_id="/n")
    )


def test_q10_skip_correlation_auto_clear_leaves_the_engine_alone() -> None:
    """Q10 (§1.3): the engine is not called: the root keeps muting, its entries remain."""
    manager = _manager(ESTOP_MOTOR, patterns=MOTOR)
    engine = manager.correlation
    assert engine is not None
    _fail(manager, "ESTOP_001", 0)
    _fail(manager, "MOTOR_A", 10)
    assert manager.clear(
        ClearRequest(t_ns=ms(20), fault_code="ESTOP_001", skip_correlation_auto_clear=True)
    )
    clear = manager.output.clears[-1]
    assert (clear.success, clear.auto_cleared_codes) == (True, ())
    assert clear.message == "Fault cleared: ESTOP_001"
    assert manager.storage.faults["MOTOR_A"].status == "CONFIRMED"
    _fail(manager, "MOTOR_B", 30)  # the root is still pending: muted, no event
    assert [(e.event_type, e.fault.fault_code) for e in manager.output.events] == [
        ("fault_confirmed", "ESTOP_001"),
        ("fault_cleared", "ESTOP_001"),
    ]
    assert engine.muted_faults() == [
        muted("MOTOR_A", "ESTOP_001", "estop", 10),
        muted("MOTOR_B", "ESTOP_001", "estop", 30),
    ]
    assert engine.process_clear("ESTOP_001") == ["MOTOR_A", "MOTOR_B"]


def test_clear_of_an_unknown_fault_still_runs_the_engine() -> None:
    """§1.3: process_clear runs before storage; a not-found clear still changes the engine."""
    manager = _manager(ESTOP_MOTOR, patterns=MOTOR)
    engine = manager.correlation
    assert engine is not None
    engine.process_fault("ESTOP_001", "CRITICAL", ms(0))  # the engine alone knows the root
    _fail(manager, "MOTOR_A", 10)
    assert manager.clear(ClearRequest(t_ns=ms(20), fault_code="ESTOP_001")) is False
    clear = manager.output.clears[-1]
    assert (clear.success, clear.auto_cleared_codes) == (False, ())
    assert engine.muted_count == 0
    assert manager.storage.faults["MOTOR_A"].status == "CONFIRMED"


def test_q11_auto_cleared_symptom_keeps_its_root_role() -> None:
    """Q11 (§1.3): no process_clear for auto-cleared symptoms: their own windows stay open."""
    manager = _manager(
        hier("r_estop", ("ESTOP_001",), inline=("POWER_*",), window_ms=1000),
        hier("r_power", ("POWER_LOSS",), symptoms=("motor",), window_ms=1000),
        patterns=MOTOR,
    )
    engine = manager.correlation
    assert engine is not None
    _fail(manager, "POWER_LOSS", 0)  # root of r_power
    _fail(manager, "ESTOP_001", 10)  # root of r_estop
    _fail(manager, "POWER_LOSS", 20)  # symptom of ESTOP_001 now
    assert manager.clear(ClearRequest(t_ns=ms(30), fault_code="ESTOP_001"))
    assert manager.output.clears[-1].auto_cleared_codes == ("POWER_LOSS",)
    assert manager.storage.faults["POWER_LOSS"].status == "CLEARED"
    _fail(manager, "MOTOR_A", 40)  # still a symptom of POWER_LOSS's t0 window
    assert engine.muted_faults() == [muted("MOTOR_A", "POWER_LOSS", "r_power", 40)]
    assert "MOTOR_A" not in [e.fault.fault_code for e in manager.output.events]


def test_q11_auto_cleared_symptom_keeps_its_cluster_membership() -> None:
    """Q11 (§1.3): an auto-cleared symptom stays listed in its cluster."""
    manager = _manager(
        hier("estop", ("ESTOP_001",), symptoms=("sensor",), window_ms=1000),
        clustering("storm", ("sensor",), min_count=2),
        patterns={"sensor": ("SENSOR_*",)},
    )
    engine = manager.correlation
    assert engine is not None
    _fail(manager, "SENSOR_A", 0)
    _fail(manager, "SENSOR_B", 10)
    _fail(manager, "ESTOP_001", 20)
    _fail(manager, "SENSOR_A", 30)  # now a symptom
    assert manager.clear(ClearRequest(t_ns=ms(40), fault_code="ESTOP_001"))
    assert manager.output.clears[-1].auto_cleared_codes == ("SENSOR_A",)
    assert manager.storage.faults["SENSOR_A"].status == "CLEARED"
    assert engine.clusters()[0].fault_codes == ("SENSOR_A", "SENSOR_B")


def test_passed_reports_never_reach_the_engine() -> None:
    """§1.2.3: a PASSED report of a symptom neither attributes nor mutes it."""
    manager = _manager(ESTOP_MOTOR, patterns=MOTOR)
    engine = manager.correlation
    assert engine is not None
    _fail(manager, "ESTOP_001", 0)
    _fail(manager, "MOTOR_A", 5)
    engine.process_clear("MOTOR_A")
    manager.report(ReportRequest(t_ns=ms(10), fault_code="MOTOR_A", event_type=1, source_id="/n"))
    assert engine.muted_count == 0
    assert engine.process_clear("ESTOP_001") == ["MOTOR_A"]
