"""Upstream's test_correlation_engine.cpp (E01-E28) and integration tests 21-25, ported.

Times are ms from the scenario start (correlation.md §13.0), fed to the engine as bag-time ns.
"""

from __future__ import annotations

from medkit_replay.engine import DebounceConfig, FaultManager, FaultManagerConfig
from medkit_replay.engine.correlation import (
    CorrelationConfig,
    CorrelationEngine,
    CorrelationResult,
    CorrelationRule,
    Representative,
)
from medkit_replay.model import (
    NS_PER_MS,
    ClearRequest,
    Cluster,
    MutedFault,
    ReportRequest,
    RetroactiveMute,
)

# A bag-time origin far from zero, so that nothing depends on times starting at 0.
T0 = 1_760_000_000 * 1_000_000_000

# -- shared configs (§13.1) -----------------------------------------------------------------

CFG_HIER = CorrelationConfig(
    enabled=True,
    default_window_ms=500,
    patterns={"drive_faults": ("DRIVE_*",), "motor_errors": ("MOTOR_COMM_*", "MOTOR_TIMEOUT_*")},
    rules=(
        CorrelationRule(
            id="estop_cascade",
            name="E-Stop Cascade",
            mode="hierarchical",
            root_cause_codes=("ESTOP_001",),
            symptom_pattern_ids=("motor_errors", "drive_faults"),
            window_ms=1000,
            mute_symptoms=True,
            auto_clear_with_root=True,
        ),
    ),
)

CFG_CLUSTER = CorrelationConfig(
    enabled=True,
    patterns={"comm_errors": ("*_COMM_*", "*_TIMEOUT")},
    rules=(
        CorrelationRule(
            id="comm_storm",
            name="Communication Storm",
            mode="auto_cluster",
            match_pattern_ids=("comm_errors",),
            min_count=3,
            window_ms=500,
            show_as_single=True,
            representative=Representative.HIGHEST_SEVERITY,
        ),
    ),
)

CFG_MIXED = CorrelationConfig(
    enabled=True,
    patterns={"motor_errors": ("MOTOR_*",), "sensor_errors": ("SENSOR_*",)},
    rules=(
        CorrelationRule(
            id="estop_rule",
            name="estop_rule",
            mode="hierarchical",
            root_cause_codes=("ESTOP_001",),
            symptom_pattern_ids=("motor_errors",),
            window_ms=500,
        ),
        CorrelationRule(
            id="sensor_cluster",
            name="sensor_cluster",
            mode="auto_cluster",
            match_pattern_ids=("sensor_errors",),
            min_count=2,
            window_ms=500,
            representative=Representative.FIRST,
        ),
    ),
)


def _err3(representative: Representative) -> CorrelationConfig:
    return CorrelationConfig(
        enabled=True,
        patterns={"errors": ("*_ERROR",)},
        rules=(
            CorrelationRule(
                id="test_cluster",
                name="test_cluster",
                mode="auto_cluster",
                match_pattern_ids=("errors",),
                min_count=3,
                window_ms=500,
                show_as_single=True,
                representative=representative,
            ),
        ),
    )


CFG_ERR_FIRST3 = _err3(Representative.FIRST)
CFG_ERR_RECENT3 = _err3(Representative.MOST_RECENT)

CFG_INTEGRATION = CorrelationConfig(
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


# -- helpers ----------------------------------------------------------------------------------


def ms(t_ms: int) -> int:
    """Scenario time in ms → bag time in ns."""
    return T0 + t_ms * NS_PER_MS


def fault(engine: CorrelationEngine, code: str, severity: str, t_ms: int) -> CorrelationResult:
    """`F code SEV` at t."""
    return engine.process_fault(code, severity, ms(t_ms))


def muted(code: str, root: str, rule: str, delay: int) -> MutedFault:
    """One expected muted entry."""
    return MutedFault(fault_code=code, root_cause_code=root, rule_id=rule, delay_ms=delay)


def cluster(
    cluster_id: str,
    rule: str,
    name: str,
    rep: tuple[str, str],
    codes: tuple[str, ...],
    first_ms: int,
    last_ms: int,
) -> Cluster:
    """One expected active cluster; name and label are always equal."""
    return Cluster(
        cluster_id=cluster_id,
        rule_id=rule,
        rule_name=name,
        label=name,
        representative_code=rep[0],
        representative_severity=rep[1],
        fault_codes=codes,
        count=len(codes),
        first_at_ns=ms(first_ms),
        last_at_ns=ms(last_ms),
    )


def root(rule: str) -> CorrelationResult:
    """A root-cause result: nothing but is_root_cause and rule_id."""
    return CorrelationResult(is_root_cause=True, rule_id=rule)


def symptom(rc: str, rule: str, delay: int, *, mute: bool = True) -> CorrelationResult:
    """A symptom result."""
    return CorrelationResult(should_mute=mute, root_cause_code=rc, rule_id=rule, delay_ms=delay)


def member(cid: str, *, mute: bool = False, retro: tuple[str, ...] = ()) -> CorrelationResult:
    """A cluster result."""
    return CorrelationResult(should_mute=mute, cluster_id=cid, retroactive_mute_codes=retro)


NOTHING = CorrelationResult()

# -- 13.4 engine ---------------------------------------------------------------------------


def test_e01_root_cause_recognized() -> None:
    """E01 RootCauseRecognized: mute F, root T, rule [A]; rc empty, delay 0, cid empty [I]."""
    engine = CorrelationEngine(CFG_HIER)
    assert fault(engine, "ESTOP_001", "CRITICAL", 0) == root("estop_cascade")


def test_e02_symptom_muted() -> None:
    """E02 SymptomMuted [A]; delay 0 and the entry's rule [I]."""
    engine = CorrelationEngine(CFG_HIER)
    assert fault(engine, "ESTOP_001", "CRITICAL", 0) == root("estop_cascade")
    result = fault(engine, "MOTOR_COMM_FL", "ERROR", 0)
    assert result == symptom("ESTOP_001", "estop_cascade", 0)
    assert engine.muted_count == 1
    assert engine.muted_faults() == [muted("MOTOR_COMM_FL", "ESTOP_001", "estop_cascade", 0)]


def test_e03_multiple_symptoms_muted() -> None:
    """E03 MultipleSymptomsMuted: count [A]; list ordered by code [I]."""
    engine = CorrelationEngine(CFG_HIER)
    fault(engine, "ESTOP_001", "CRITICAL", 0)
    fault(engine, "MOTOR_COMM_FL", "ERROR", 0)
    fault(engine, "MOTOR_COMM_FR", "ERROR", 0)
    fault(engine, "DRIVE_FAULT", "ERROR", 0)
    assert engine.muted_count == 3
    assert engine.muted_faults() == [
        muted("DRIVE_FAULT", "ESTOP_001", "estop_cascade", 0),
        muted("MOTOR_COMM_FL", "ESTOP_001", "estop_cascade", 0),
        muted("MOTOR_COMM_FR", "ESTOP_001", "estop_cascade", 0),
    ]


def test_e04_symptom_before_root_cause_not_correlated() -> None:
    """E04 SymptomBeforeRootCauseNotCorrelated [A]; every field empty [I]."""
    engine = CorrelationEngine(CFG_HIER)
    assert fault(engine, "MOTOR_COMM_FL", "ERROR", 0) == NOTHING
    assert engine.muted_count == 0


def test_e05_symptom_after_window_not_correlated() -> None:
    """E05 SymptomAfterWindowNotCorrelated [A]; rc and rule empty [I]."""
    engine = CorrelationEngine(CFG_HIER)
    fault(engine, "ESTOP_001", "CRITICAL", 0)
    assert fault(engine, "MOTOR_COMM_FL", "ERROR", 1500) == NOTHING
    assert engine.muted_count == 0


def test_e06_clear_root_cause_clears_symptoms() -> None:
    """E06 ClearRootCauseClearsSymptoms [A]; attribution order [I]."""
    engine = CorrelationEngine(CFG_HIER)
    fault(engine, "ESTOP_001", "CRITICAL", 0)
    fault(engine, "MOTOR_COMM_FL", "ERROR", 0)
    fault(engine, "MOTOR_COMM_FR", "ERROR", 0)
    assert engine.muted_count == 2
    auto = engine.process_clear("ESTOP_001")
    assert len(auto) == 2
    assert "MOTOR_COMM_FL" in auto
    assert "MOTOR_COMM_FR" in auto
    assert auto == ["MOTOR_COMM_FL", "MOTOR_COMM_FR"]
    assert engine.muted_count == 0


def test_e07_unrelated_fault_not_correlated() -> None:
    """E07 UnrelatedFaultNotCorrelated [A]."""
    engine = CorrelationEngine(CFG_HIER)
    fault(engine, "ESTOP_001", "CRITICAL", 0)
    assert fault(engine, "SENSOR_TIMEOUT", "ERROR", 0) == NOTHING
    assert engine.muted_count == 0


def test_e08_inline_symptom_codes_muted() -> None:
    """E08 InlineSymptomCodesMuted [A]; rule and rc of DRIVE_FAULT, muted list [I]."""
    config = CorrelationConfig(
        enabled=True,
        rules=(
            CorrelationRule(
                id="estop_inline",
                name="estop_inline",
                root_cause_codes=("ESTOP_001",),
                inline_symptom_codes=("MOTOR_*", "DRIVE_*"),
                window_ms=1000,
                mute_symptoms=True,
            ),
        ),
    )
    engine = CorrelationEngine(config)
    assert fault(engine, "ESTOP_001", "CRITICAL", 0) == root("estop_inline")
    assert fault(engine, "MOTOR_COMM_FL", "ERROR", 0) == symptom("ESTOP_001", "estop_inline", 0)
    assert fault(engine, "DRIVE_FAULT", "ERROR", 0) == symptom("ESTOP_001", "estop_inline", 0)
    assert fault(engine, "SENSOR_ERROR", "ERROR", 0) == NOTHING
    assert engine.muted_count == 2
    assert [m.fault_code for m in engine.muted_faults()] == ["DRIVE_FAULT", "MOTOR_COMM_FL"]


def test_e09_mixed_pattern_and_inline_symptoms() -> None:
    """E09 MixedPatternAndInlineSymptoms [A]; rc and rule of both entries [I]."""
    config = CorrelationConfig(
        enabled=True,
        patterns={"sensor_errors": ("SENSOR_*",)},
        rules=(
            CorrelationRule(
                id="estop_mixed",
                name="estop_mixed",
                root_cause_codes=("ESTOP_001",),
                symptom_pattern_ids=("sensor_errors",),
                inline_symptom_codes=("MOTOR_*",),
                window_ms=1000,
            ),
        ),
    )
    engine = CorrelationEngine(config)
    fault(engine, "ESTOP_001", "CRITICAL", 0)
    assert fault(engine, "SENSOR_TIMEOUT", "ERROR", 0).should_mute is True
    assert fault(engine, "MOTOR_FAULT", "ERROR", 0).should_mute is True
    assert engine.muted_count == 2
    assert engine.muted_faults() == [
        muted("MOTOR_FAULT", "ESTOP_001", "estop_mixed", 0),
        muted("SENSOR_TIMEOUT", "ESTOP_001", "estop_mixed", 0),
    ]


def test_e10_auto_cluster_triggers_at_min_count() -> None:
    """E10 AutoClusterTriggersAtMinCount: mutes and counts [A]; ids, retro, cluster [I]."""
    engine = CorrelationEngine(CFG_CLUSTER)
    assert fault(engine, "MOTOR_COMM_FL", "ERROR", 0) == member("comm_storm_1")
    assert engine.cluster_count == 0
    assert fault(engine, "SENSOR_TIMEOUT", "ERROR", 0) == member("comm_storm_1")
    assert engine.cluster_count == 0
    result = fault(engine, "DRIVE_COMM_ERROR", "WARNING", 0)
    assert result == member("comm_storm_1", mute=True, retro=("SENSOR_TIMEOUT",))
    assert engine.cluster_count == 1
    assert engine.clusters() == [
        cluster(
            "comm_storm_1",
            "comm_storm",
            "Communication Storm",
            ("MOTOR_COMM_FL", "ERROR"),
            ("MOTOR_COMM_FL", "SENSOR_TIMEOUT", "DRIVE_COMM_ERROR"),
            0,
            0,
        )
    ]


def test_e11_auto_cluster_not_triggered_below_min_count() -> None:
    """E11 AutoClusterNotTriggeredBelowMinCount [A]; ids and mutes [I]."""
    engine = CorrelationEngine(CFG_CLUSTER)
    assert fault(engine, "MOTOR_COMM_FL", "ERROR", 0) == member("comm_storm_1")
    assert fault(engine, "SENSOR_TIMEOUT", "ERROR", 0) == member("comm_storm_1")
    assert engine.cluster_count == 0
    assert engine.clusters() == []


def test_e12_auto_cluster_highest_severity_representative() -> None:
    """E12 AutoClusterHighestSeverityRepresentative: one cluster, rep [A]; the rest [I]."""
    engine = CorrelationEngine(CFG_CLUSTER)
    assert fault(engine, "MOTOR_COMM_FL", "WARNING", 0) == member("comm_storm_1")
    assert fault(engine, "SENSOR_TIMEOUT", "CRITICAL", 0) == member("comm_storm_1")
    result = fault(engine, "DRIVE_COMM_ERROR", "ERROR", 0)
    assert result == member("comm_storm_1", mute=True, retro=("MOTOR_COMM_FL",))
    clusters = engine.clusters()
    assert len(clusters) == 1
    assert clusters[0].representative_code == "SENSOR_TIMEOUT"
    assert clusters[0].representative_severity == "CRITICAL"
    assert clusters == [
        cluster(
            "comm_storm_1",
            "comm_storm",
            "Communication Storm",
            ("SENSOR_TIMEOUT", "CRITICAL"),
            ("MOTOR_COMM_FL", "SENSOR_TIMEOUT", "DRIVE_COMM_ERROR"),
            0,
            0,
        )
    ]


def test_e13_auto_cluster_first_representative() -> None:
    """E13 AutoClusterFirstRepresentative: one cluster, rep FIRST_ERROR [A]; the rest [I]."""
    config = CorrelationConfig(
        enabled=True,
        patterns={"errors": ("*_ERROR",)},
        rules=(
            CorrelationRule(
                id="test_cluster",
                name="test_cluster",
                mode="auto_cluster",
                match_pattern_ids=("errors",),
                min_count=2,
                representative=Representative.FIRST,
            ),
        ),
    )
    engine = CorrelationEngine(config)
    assert fault(engine, "FIRST_ERROR", "WARNING", 0) == member("test_cluster_1")
    assert fault(engine, "SECOND_ERROR", "CRITICAL", 0) == member("test_cluster_1", mute=True)
    assert engine.clusters() == [
        cluster(
            "test_cluster_1",
            "test_cluster",
            "test_cluster",
            ("FIRST_ERROR", "WARNING"),
            ("FIRST_ERROR", "SECOND_ERROR"),
            0,
            0,
        )
    ]


def test_e14_auto_cluster_window_expires() -> None:
    """E14 AutoClusterWindowExpires: no cluster [A]; the old pending one is replaced [I]."""
    engine = CorrelationEngine(CFG_CLUSTER)
    fault(engine, "MOTOR_COMM_FL", "ERROR", 0)
    fault(engine, "SENSOR_TIMEOUT", "ERROR", 100)
    assert fault(engine, "DRIVE_COMM_ERROR", "ERROR", 600) == member("comm_storm_2")
    assert engine.cluster_count == 0
    # The new pending cluster holds DRIVE_COMM_ERROR alone: two more codes activate it.
    fault(engine, "A_COMM_B", "ERROR", 610)
    assert engine.cluster_count == 0
    assert fault(engine, "C_COMM_D", "ERROR", 620).cluster_id == "comm_storm_2"
    assert [c.fault_codes for c in engine.clusters()] == [
        ("DRIVE_COMM_ERROR", "A_COMM_B", "C_COMM_D")
    ]


def test_e15_cleanup_expired_removes_pending_root_causes() -> None:
    """E15 CleanupExpiredRemovesPendingRootCauses (rebased from now-2000) [A]."""
    engine = CorrelationEngine(CFG_HIER)
    fault(engine, "ESTOP_001", "CRITICAL", 0)
    assert fault(engine, "MOTOR_COMM_FL", "ERROR", 2000) == NOTHING
    assert engine.muted_count == 0
    engine.cleanup_expired(ms(2000))
    assert fault(engine, "MOTOR_TIMEOUT_RR", "ERROR", 2000) == NOTHING
    assert engine.muted_count == 0


def test_e16_cleanup_expired_removes_pending_clusters() -> None:
    """E16 CleanupExpiredRemovesPendingClusters [A]; the new id comm_storm_2 [I]."""
    engine = CorrelationEngine(CFG_CLUSTER)
    fault(engine, "MOTOR_COMM_FL", "ERROR", 0)
    fault(engine, "SENSOR_TIMEOUT", "ERROR", 10)
    assert engine.cluster_count == 0
    engine.cleanup_expired(ms(1000))
    assert fault(engine, "DRIVE_COMM_ERROR", "ERROR", 1000) == member("comm_storm_2")
    assert engine.cluster_count == 0


def test_e17_cleanup_expired_does_not_break_active_cluster() -> None:
    """E17 CleanupExpiredDoesNotBreakActiveCluster: counts [A]; stale rep (Q9) [I]."""
    engine = CorrelationEngine(CFG_CLUSTER)
    fault(engine, "MOTOR_COMM_FL", "ERROR", 0)
    fault(engine, "SENSOR_TIMEOUT", "ERROR", 10)
    result = fault(engine, "DRIVE_COMM_ERROR", "WARNING", 20)
    assert result == member("comm_storm_1", mute=True, retro=("SENSOR_TIMEOUT",))
    assert engine.cluster_count == 1
    assert engine.clusters()[0].representative_code == "MOTOR_COMM_FL"
    engine.cleanup_expired(ms(1000))
    assert engine.cluster_count == 1
    assert engine.process_clear("MOTOR_COMM_FL") == []
    assert engine.cluster_count == 1
    clusters = engine.clusters()
    assert len(clusters) == 1
    assert len(clusters[0].fault_codes) == 2
    assert clusters == [
        cluster(
            "comm_storm_1",
            "comm_storm",
            "Communication Storm",
            ("MOTOR_COMM_FL", "ERROR"),  # stale: the pending twin is gone
            ("SENSOR_TIMEOUT", "DRIVE_COMM_ERROR"),
            0,
            20,
        )
    ]


def test_e18_hierarchical_and_cluster_coexist() -> None:
    """E18 HierarchicalAndClusterCoexist: counts [A]; results and cluster [I]."""
    engine = CorrelationEngine(CFG_MIXED)
    assert fault(engine, "ESTOP_001", "CRITICAL", 0) == root("estop_rule")
    assert fault(engine, "MOTOR_COMM_FL", "ERROR", 0) == symptom("ESTOP_001", "estop_rule", 0)
    assert engine.muted_count == 1
    assert fault(engine, "SENSOR_LIDAR", "ERROR", 0) == member("sensor_cluster_1")
    assert fault(engine, "SENSOR_IMU", "ERROR", 0) == member("sensor_cluster_1", mute=True)
    assert engine.cluster_count == 1
    assert engine.muted_count == 1
    assert engine.clusters() == [
        cluster(
            "sensor_cluster_1",
            "sensor_cluster",
            "sensor_cluster",
            ("SENSOR_LIDAR", "ERROR"),
            ("SENSOR_LIDAR", "SENSOR_IMU"),
            0,
            0,
        )
    ]


def test_e19_duplicate_fault_code() -> None:
    """E19 DuplicateFaultCode: muted_count >= 1 [A]; exactly 1, listed once [I]."""
    engine = CorrelationEngine(CFG_HIER)
    fault(engine, "ESTOP_001", "CRITICAL", 0)
    fault(engine, "MOTOR_COMM_FL", "ERROR", 0)
    assert fault(engine, "MOTOR_COMM_FL", "ERROR", 0) == symptom("ESTOP_001", "estop_cascade", 0)
    assert engine.muted_count >= 1
    assert engine.muted_count == 1
    # The root's symptom list holds the code once.
    assert engine.process_clear("ESTOP_001") == ["MOTOR_COMM_FL"]


def test_e20_empty_engine_queries() -> None:
    """E20 EmptyEngineQueries [A]."""
    engine = CorrelationEngine(CFG_HIER)
    assert engine.muted_count == 0
    assert engine.cluster_count == 0
    assert engine.muted_faults() == []
    assert engine.clusters() == []


def test_e21_clear_non_existent_fault() -> None:
    """E21 ClearNonExistentFault [A]."""
    engine = CorrelationEngine(CFG_HIER)
    assert engine.process_clear("NONEXISTENT") == []


def test_e22_auto_cluster_retroactive_muting() -> None:
    """E22 AutoClusterRetroactiveMuting [A]; the id sensor_cluster_1 [I]."""
    config = CorrelationConfig(
        enabled=True,
        patterns={"sensor_errors": ("SENSOR_*",)},
        rules=(
            CorrelationRule(
                id="sensor_cluster",
                name="sensor_cluster",
                mode="auto_cluster",
                match_pattern_ids=("sensor_errors",),
                min_count=3,
                window_ms=500,
                show_as_single=True,
                representative=Representative.FIRST,
            ),
        ),
    )
    engine = CorrelationEngine(config)
    first = fault(engine, "SENSOR_001", "ERROR", 0)
    assert first.cluster_id != ""
    assert first == member("sensor_cluster_1")
    assert fault(engine, "SENSOR_002", "ERROR", 10) == member("sensor_cluster_1")
    third = fault(engine, "SENSOR_003", "ERROR", 20)
    assert third == member("sensor_cluster_1", mute=True, retro=("SENSOR_002",))
    assert engine.cluster_count == 1
    clusters = engine.clusters()
    assert len(clusters[0].fault_codes) == 3
    assert clusters[0].representative_code == "SENSOR_001"


def test_e23_clear_fault_removes_from_pending_cluster() -> None:
    """E23 ClearFaultRemovesFromPendingCluster: counts [A]; rejoin and reassign [I]."""
    engine = CorrelationEngine(CFG_CLUSTER)
    fault(engine, "MOTOR_COMM_FL", "ERROR", 0)
    fault(engine, "SENSOR_TIMEOUT", "ERROR", 10)
    assert engine.cluster_count == 0
    assert engine.process_clear("MOTOR_COMM_FL") == []
    assert fault(engine, "DRIVE_COMM_ERROR", "ERROR", 20) == member("comm_storm_1")
    assert engine.cluster_count == 0
    # Two codes now ([SENSOR_TIMEOUT, DRIVE_COMM_ERROR]); a third activates, rep reassigned.
    fault(engine, "X_COMM_Y", "ERROR", 30)
    assert engine.clusters() == [
        cluster(
            "comm_storm_1",
            "comm_storm",
            "Communication Storm",
            ("SENSOR_TIMEOUT", "ERROR"),
            ("SENSOR_TIMEOUT", "DRIVE_COMM_ERROR", "X_COMM_Y"),
            0,
            30,
        )
    ]


def test_e24_clear_representative_reassigns_pending_cluster() -> None:
    """E24 ClearRepresentativeReassignsPendingCluster: rep [A]; results, codes, id [I]."""
    engine = CorrelationEngine(CFG_ERR_FIRST3)
    fault(engine, "FIRST_ERROR", "CRITICAL", 0)
    fault(engine, "SECOND_ERROR", "ERROR", 10)
    assert engine.process_clear("FIRST_ERROR") == []
    assert fault(engine, "THIRD_ERROR", "ERROR", 20) == member("test_cluster_1")
    result = fault(engine, "FOURTH_ERROR", "ERROR", 30)
    assert result == member("test_cluster_1", mute=True, retro=("THIRD_ERROR",))
    assert engine.cluster_count == 1
    clusters = engine.clusters()
    assert len(clusters) == 1
    assert clusters[0].representative_code == "SECOND_ERROR"
    assert clusters[0].representative_severity == "ERROR"
    assert clusters == [
        cluster(
            "test_cluster_1",
            "test_cluster",
            "test_cluster",
            ("SECOND_ERROR", "ERROR"),
            ("SECOND_ERROR", "THIRD_ERROR", "FOURTH_ERROR"),
            0,
            30,
        )
    ]


def test_e25_clear_all_faults_removes_pending_cluster() -> None:
    """E25 ClearAllFaultsRemovesPendingCluster: no cluster [A]; new id comm_storm_2 [I]."""
    engine = CorrelationEngine(CFG_CLUSTER)
    fault(engine, "MOTOR_COMM_FL", "ERROR", 0)
    fault(engine, "SENSOR_TIMEOUT", "ERROR", 10)
    engine.process_clear("MOTOR_COMM_FL")
    engine.process_clear("SENSOR_TIMEOUT")
    assert fault(engine, "DRIVE_COMM_NEW", "ERROR", 100) == member("comm_storm_2")
    assert fault(engine, "MOTOR_COMM_NEW", "ERROR", 110) == member("comm_storm_2")
    assert engine.cluster_count == 0


def test_e26_clear_most_recent_representative_reassigns_active_cluster() -> None:
    """E26 ClearMostRecentRepresentativeReassignsActiveCluster: reps [A]; retro, codes [I]."""
    engine = CorrelationEngine(CFG_ERR_RECENT3)
    fault(engine, "FIRST_ERROR", "WARNING", 0)
    fault(engine, "SECOND_ERROR", "ERROR", 10)
    result = fault(engine, "THIRD_ERROR", "CRITICAL", 20)
    assert result == member("test_cluster_1", retro=("FIRST_ERROR", "SECOND_ERROR"))
    assert engine.cluster_count == 1
    clusters = engine.clusters()
    assert len(clusters) == 1
    assert (clusters[0].representative_code, clusters[0].representative_severity) == (
        "THIRD_ERROR",
        "CRITICAL",
    )
    engine.process_clear("THIRD_ERROR")
    clusters = engine.clusters()
    assert len(clusters) == 1
    assert clusters[0].representative_code == "SECOND_ERROR"
    assert clusters[0].representative_severity == "ERROR"
    assert clusters[0].fault_codes == ("FIRST_ERROR", "SECOND_ERROR")
    assert clusters[0].count == 2


def test_e27_clear_highest_severity_representative_reassigns() -> None:
    """E27 ClearHighestSeverityRepresentativeReassigns: reps [A]; retro, codes [I]."""
    engine = CorrelationEngine(CFG_CLUSTER)
    fault(engine, "MOTOR_COMM_FL", "WARNING", 0)
    fault(engine, "SENSOR_TIMEOUT", "CRITICAL", 10)
    result = fault(engine, "DRIVE_COMM_ERROR", "ERROR", 20)
    assert result == member("comm_storm_1", mute=True, retro=("MOTOR_COMM_FL",))
    clusters = engine.clusters()
    assert len(clusters) == 1
    assert clusters[0].representative_code == "SENSOR_TIMEOUT"
    engine.process_clear("SENSOR_TIMEOUT")
    clusters = engine.clusters()
    assert len(clusters) == 1
    assert clusters[0].representative_code == "DRIVE_COMM_ERROR"
    assert clusters[0].representative_severity == "ERROR"
    assert clusters[0].fault_codes == ("MOTOR_COMM_FL", "DRIVE_COMM_ERROR")


def test_e28_cleanup_expired_removes_fault_to_cluster_entries() -> None:
    """E28 CleanupExpiredRemovesFaultToClusterEntries: one cluster of 3 [A]; details [I]."""
    engine = CorrelationEngine(CFG_CLUSTER)
    fault(engine, "MOTOR_COMM_FL", "ERROR", 0)
    fault(engine, "SENSOR_TIMEOUT", "ERROR", 10)
    assert engine.cluster_count == 0
    engine.cleanup_expired(ms(1000))
    assert fault(engine, "MOTOR_COMM_FL", "ERROR", 1000) == member("comm_storm_2")
    assert fault(engine, "SENSOR_TIMEOUT", "ERROR", 1010) == member("comm_storm_2")
    result = fault(engine, "DRIVE_COMM_ERROR", "ERROR", 1020)
    assert result == member("comm_storm_2", mute=True, retro=("SENSOR_TIMEOUT",))
    assert engine.cluster_count == 1
    clusters = engine.clusters()
    assert len(clusters) == 1
    assert len(clusters[0].fault_codes) == 3
    assert clusters == [
        cluster(
            "comm_storm_2",
            "comm_storm",
            "Communication Storm",
            ("MOTOR_COMM_FL", "ERROR"),
            ("MOTOR_COMM_FL", "SENSOR_TIMEOUT", "DRIVE_COMM_ERROR"),
            1000,
            1020,
        )
    ]


# -- 13.5 node level (test_integration.test.py tests 21-25) ---------------------------------


def _report(manager: FaultManager, code: str, t_ms: int) -> bool:
    return manager.report(
        ReportRequest(
            t_ns=ms(t_ms),
            fault_code=code,
            event_type=0,
            severity=3,
            description=f"{code} failed",
            source_id="/test_node",
        )
    )


def test_integration_21_to_25_correlation_through_the_fault_manager() -> None:
    """§13.5: integration tests 21-25 on CFG_INTEGRATION with confirmation_threshold -3.

    Upstream asserts loosely [A]; exact engine values, events and messages are [I].
    """
    manager = FaultManager(
        FaultManagerConfig(
            debounce=DebounceConfig(confirmation_threshold=-3), correlation=CFG_INTEGRATION
        )
    )
    engine = manager.correlation
    assert engine is not None
    events = manager.output.events

    # test_21: the root cause confirms at once (CRITICAL) and is listed CONFIRMED [A].
    assert _report(manager, "ESTOP_001", 0)
    assert manager.storage.faults["ESTOP_001"].status == "CONFIRMED"
    # test_22: re-report (another pending entry, symptom list reset) then three symptoms.
    assert _report(manager, "ESTOP_001", 50)
    for code, t in (("MOTOR_COMM_FL", 60), ("MOTOR_COMM_FR", 70), ("DRIVE_FAULT_1", 80)):
        assert _report(manager, code, t)
        assert manager.storage.faults[code].status == "CONFIRMED"
    assert [(e.t_ns, e.event_type, e.fault.fault_code) for e in events] == [
        (ms(0), "fault_confirmed", "ESTOP_001"),
        (ms(50), "fault_updated", "ESTOP_001"),
    ]  # no fault_confirmed for the three muted symptoms [I]

    # ListFaults(statuses=[CONFIRMED], include_muted=true) [A]/[I]: delays from the t0 entry.
    assert engine.muted_count > 0
    assert engine.muted_faults() == [
        muted("DRIVE_FAULT_1", "ESTOP_001", "estop_cascade", 80),
        muted("MOTOR_COMM_FL", "ESTOP_001", "estop_cascade", 60),
        muted("MOTOR_COMM_FR", "ESTOP_001", "estop_cascade", 70),
    ]
    confirmed = [f.fault_code for f in manager.faults() if f.status == "CONFIRMED"]
    assert confirmed == ["DRIVE_FAULT_1", "ESTOP_001", "MOTOR_COMM_FL", "MOTOR_COMM_FR"]
    snapshot = {f.fault_code: f for f in manager.faults()}
    assert snapshot["MOTOR_COMM_FL"].muted is True
    assert snapshot["MOTOR_COMM_FL"].root_cause_code == "ESTOP_001"

    # test_23: clearing the root auto-clears its symptoms.
    assert manager.clear(ClearRequest(t_ns=ms(100), fault_code="ESTOP_001")) is True
    clear = manager.output.clears[-1]
    assert clear.success is True
    assert clear.auto_cleared_codes == ("MOTOR_COMM_FL", "MOTOR_COMM_FR", "DRIVE_FAULT_1")
    assert clear.message == "Fault cleared: ESTOP_001 (auto-cleared 3 symptoms)"
    assert events[-1].event_type == "fault_cleared"
    assert events[-1].fault.fault_code == "ESTOP_001"
    assert events[-1].auto_cleared_codes == ("MOTOR_COMM_FL", "MOTOR_COMM_FR", "DRIVE_FAULT_1")
    assert [e.event_type for e in events].count("fault_cleared") == 1  # none per symptom
    assert not [m for m in engine.muted_faults() if m.root_cause_code == "ESTOP_001"]
    assert engine.muted_count == 0
    for code in ("ESTOP_001", "MOTOR_COMM_FL", "MOTOR_COMM_FR", "DRIVE_FAULT_1"):
        assert manager.storage.faults[code].status == "CLEARED"

    # test_24: a sensor storm of two codes clusters; the second is muted.
    assert _report(manager, "SENSOR_LIDAR_FAIL", 200)
    assert _report(manager, "SENSOR_IMU_TIMEOUT", 300)
    assert [(e.t_ns, e.event_type, e.fault.fault_code) for e in list(events)[-2:]] == [
        (ms(100), "fault_cleared", "ESTOP_001"),
        (ms(200), "fault_confirmed", "SENSOR_LIDAR_FAIL"),
    ]  # no fault_confirmed for SENSOR_IMU_TIMEOUT
    assert manager.output.retroactive_mutes == []  # retro=[] at activation
    assert engine.cluster_count > 0
    clusters = engine.clusters()
    assert clusters[0].rule_id == "sensor_storm"
    assert clusters[0].count >= 2
    assert clusters == [
        cluster(
            "sensor_storm_1",
            "sensor_storm",
            "Sensor Storm",
            ("SENSOR_LIDAR_FAIL", "CRITICAL"),
            ("SENSOR_LIDAR_FAIL", "SENSOR_IMU_TIMEOUT"),
            200,
            300,
        )
    ]
    listed = {f.fault_code: f for f in manager.faults()}
    assert listed["SENSOR_LIDAR_FAIL"].status == "CONFIRMED"
    assert listed["SENSOR_IMU_TIMEOUT"].status == "CONFIRMED"
    assert listed["SENSOR_IMU_TIMEOUT"].muted is False  # cluster mutes are event-only
    assert listed["SENSOR_IMU_TIMEOUT"].cluster_ids == ("sensor_storm_1",)

    # test_25: the counts stay available without the lists.
    assert (engine.muted_count, engine.cluster_count) == (0, 1)


def test_integration_retroactive_mutes_are_information_only() -> None:
    """§1.2/§12 [I]: retroactive_mute_codes are recorded, but change no state and no event."""
    manager = FaultManager(FaultManagerConfig(correlation=CFG_CLUSTER))
    for code, t in (("MOTOR_COMM_FL", 0), ("SENSOR_TIMEOUT", 10), ("DRIVE_COMM_ERROR", 20)):
        manager.report(
            ReportRequest(t_ns=ms(t), fault_code=code, event_type=0, severity=2, source_id="/node")
        )
    assert manager.output.retroactive_mutes == [
        RetroactiveMute(t_ns=ms(20), cluster_id="comm_storm_1", fault_codes=("SENSOR_TIMEOUT",))
    ]
    assert [(e.event_type, e.fault.fault_code) for e in manager.output.events] == [
        ("fault_confirmed", "MOTOR_COMM_FL"),
        ("fault_confirmed", "SENSOR_TIMEOUT"),
    ]
    assert [f.muted for f in manager.faults()] == [False, False, False]
