"""Capture planning from transitions, ported from upstream's rosbag-capture lifecycle tests
(RosbagCaptureIntegrationTest in test_rosbag_capture.cpp) and the node's capture trigger and
cooldown (fault_manager_node.cpp): shared post-roll, post-fault-only bags, clears during the
post-roll, auto_cleanup, max_bags_per_fault, lazy start, the attachment cap, the cooldown.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

from medkit_replay.evidence.graph import NodeGraph
from medkit_replay.evidence.plan import Plan, Segment, plan_evidence
from medkit_replay.evidence.rules import RosbagConfig, SnapshotConfig
from medkit_replay.model import ReportRecord, Status, Transition

if TYPE_CHECKING:
    from collections.abc import Iterable

S = 1_000_000_000


def at(seconds: float) -> int:
    return round(seconds * S)


def step(
    seconds: float,
    code: str,
    before: Status | None,
    after: Status,
    cause: str = "report",
    source: str = "/node",
) -> Transition:
    return Transition(
        t_ns=at(seconds),
        fault_code=code,
        from_status=before,
        to_status=after,
        cause=cause,  # type: ignore[arg-type]
        source_id=source if cause == "report" else None,
    )


def confirm(seconds: float, code: str, before: Status | None = None) -> Transition:
    return step(seconds, code, before, "CONFIRMED")


def clear(seconds: float, code: str, before: Status = "CONFIRMED") -> Transition:
    return step(seconds, code, before, "CLEARED", cause="clear")


class Messages:
    """A recording's message times per topic: the probe planning asks."""

    def __init__(self, times: dict[str, list[float]]) -> None:
        self.times = {topic: [at(t) for t in ts] for topic, ts in times.items()}

    def __call__(self, topics: Iterable[str], start_ns: int, end_ns: int) -> bool:
        return any(start_ns <= t <= end_ns for topic in topics for t in self.times.get(topic, []))


STEADY = Messages({"/odom": [i / 10 for i in range(2000)]})  # 10 Hz for 200 s

BAG = SnapshotConfig(enabled=False, rosbag=RosbagConfig(enabled=True, topics="all"))


def plan(
    transitions: list[Transition],
    config: SnapshotConfig = BAG,
    probe: Messages = STEADY,
    graph: NodeGraph | None = None,
    reports: Iterable[ReportRecord] = (),
) -> Plan:
    return plan_evidence(config, transitions, reports, ["/odom", "/tf"], graph, probe)


def test_a_fault_confirmed_during_the_post_roll_shares_the_recording() -> None:
    found = plan([confirm(10, "A"), confirm(10.5, "B")])
    (recording,) = found.recordings
    assert recording.fault_codes == ("A", "B")
    assert (recording.start_ns, recording.end_ns) == (at(5), at(11))
    assert recording.deleted is None


def test_a_confirmation_right_after_the_post_roll_gets_a_post_fault_only_recording() -> None:
    quiet = Messages({"/odom": [9.0, 10.5]})  # nothing between the first window's end and 11.2
    first, second = plan([confirm(10, "A"), confirm(11.2, "B")], probe=quiet).recordings
    assert (first.start_ns, first.end_ns) == (at(5), at(11))
    assert (second.start_ns, second.end_ns) == (at(11.2), at(12.2))
    assert second.segments == [Segment(at(11.2) + 1, at(12.2), None)]


def test_the_next_pre_roll_starts_where_the_previous_recording_ended() -> None:
    first, second = plan([confirm(10, "A"), confirm(13, "B")]).recordings
    assert second.start_ns == first.end_ns + 1


def test_no_history_and_no_post_roll_make_no_recording() -> None:
    config = replace(BAG, rosbag=RosbagConfig(enabled=True, topics="all", duration_after_sec=0.0))
    assert plan([confirm(10, "A")], config, probe=Messages({})).recordings == []
    (kept,) = plan([confirm(10, "A")], config).recordings
    assert (kept.start_ns, kept.end_ns) == (at(5), at(10))


def test_a_fault_cleared_during_the_post_roll_gets_no_row_but_the_bag_stays() -> None:
    (recording,) = plan([confirm(10, "A"), confirm(10.3, "B"), clear(10.6, "B")]).recordings
    assert recording.rows == ["A"]
    assert recording.deleted is None


def test_the_primary_cleared_during_the_post_roll_leaves_the_bag_to_its_attached_fault() -> None:
    (recording,) = plan([confirm(10, "A"), confirm(10.3, "B"), clear(10.6, "A")]).recordings
    assert recording.rows == ["B"]
    assert recording.fault_codes == ("A", "B")


def test_a_burst_fully_cleared_during_the_post_roll_discards_the_bag() -> None:
    (recording,) = plan([confirm(10, "A"), clear(10.5, "A")]).recordings
    assert recording.deleted == (
        at(11),
        "every fault of the recording was cleared during its post-roll",
    )


def test_acknowledging_deletes_the_recording_when_no_history_is_configured() -> None:
    (recording,) = plan([confirm(10, "A"), clear(20, "A")]).recordings
    assert recording.deleted == (at(20), "auto_cleanup: A was cleared")


def test_acknowledging_keeps_a_history_the_operator_configured() -> None:
    config = replace(BAG, rosbag=RosbagConfig(enabled=True, topics="all", max_bags_per_fault=3))
    (recording,) = plan([confirm(10, "A"), clear(20, "A")], config).recordings
    assert recording.deleted is None


def test_auto_cleanup_off_keeps_recordings_after_a_clear() -> None:
    config = replace(BAG, rosbag=RosbagConfig(enabled=True, topics="all", auto_cleanup=False))
    assert plan([confirm(10, "A"), clear(20, "A")], config).recordings[0].deleted is None


def test_clearing_one_fault_of_a_burst_keeps_the_shared_bag() -> None:
    (recording,) = plan([confirm(10, "A"), confirm(10.5, "B"), clear(20, "A")]).recordings
    assert recording.deleted is None  # B still holds it
    (gone,) = plan(
        [confirm(10, "A"), confirm(10.5, "B"), clear(20, "A"), clear(21, "B")]
    ).recordings
    assert gone.deleted == (at(21), "auto_cleanup: B was cleared")


def test_max_bags_per_fault_keeps_the_newest() -> None:
    transitions = [
        confirm(10, "A"),
        step(30, "A", "CONFIRMED", "HEALED"),
        confirm(80, "A", "HEALED"),
    ]
    old, new = plan(transitions).recordings
    assert old.deleted is not None and old.deleted[0] == at(81)
    assert "max_bags_per_fault 1" in old.deleted[1]
    assert new.deleted is None
    config = replace(BAG, rosbag=RosbagConfig(enabled=True, topics="all", max_bags_per_fault=0))
    assert all(r.deleted is None for r in plan(transitions, config).recordings)


def test_the_attachment_cap_stops_rows_past_32_faults() -> None:
    burst = [confirm(10, "A")] + [confirm(10 + i / 100, f"S{i:02d}") for i in range(1, 41)]
    (recording,) = plan(burst).recordings
    assert len(recording.rows) == 33  # the primary and 32 attached


def test_lazy_start_waits_for_a_fault_entering_prefailed() -> None:
    lazy = replace(BAG, rosbag=RosbagConfig(enabled=True, topics="all", lazy_start=True))
    # confirmed without ever being PREFAILED: the buffer never started, no recording
    assert plan([confirm(10, "A")], lazy).recordings == []
    (recording,) = plan([step(8, "B", None, "PREFAILED"), confirm(10, "A")], lazy).recordings
    assert recording.start_ns == at(8)  # the buffer holds only what came after the start


def test_auto_confirmations_capture_nothing() -> None:
    found = plan(
        [step(8, "A", None, "PREFAILED"), step(10, "A", "PREFAILED", "CONFIRMED", "auto_confirm")]
    )
    assert found.recordings == []


def test_the_cooldown_gates_recaptures_and_a_clear_resets_it() -> None:
    config = SnapshotConfig(default_topics=("/odom",))
    flapping = [
        confirm(10, "A"),
        step(20, "A", "CONFIRMED", "HEALED"),
        confirm(40, "A", "HEALED"),  # 30 s after the last capture: inside the 60 s cooldown
        clear(50, "A", "CONFIRMED"),
        confirm(55, "A", "CLEARED"),  # the clear forgot the cooldown
        step(56, "B", None, "PREFAILED"),
        confirm(57, "B", "PREFAILED"),
    ]
    captured = [(c.fault_code, c.t_ns, c.capture_id) for c in plan(flapping, config).captures]
    assert captured == [("A", at(10), 1), ("A", at(55), 2), ("B", at(57), 3)]
    no_cooldown = replace(config, recapture_cooldown_sec=0.0)
    assert len(plan(flapping, no_cooldown).captures) == 4


def test_re_reports_on_a_confirmed_fault_capture_nothing() -> None:
    config = SnapshotConfig(default_topics=("/odom",))
    found = plan([confirm(10, "A"), step(12, "A", "CONFIRMED", "CONFIRMED")], config)
    assert len(found.captures) == 1


def test_a_disabled_snapshot_capture_still_runs_the_cooldown_for_the_black_box() -> None:
    transitions = [
        confirm(10, "A"),
        step(20, "A", "CONFIRMED", "HEALED"),
        confirm(40, "A", "HEALED"),
    ]
    assert len(plan(transitions).recordings) == 1
    nothing = SnapshotConfig(enabled=False)
    assert plan(transitions, nothing) == Plan()


def test_entity_default_needs_the_graph_and_says_so_once() -> None:
    found = plan([confirm(10, "A"), confirm(11, "B")], SnapshotConfig())
    assert found.captures == []
    assert len(found.notes) == 1 and "A, B" in found.notes[0] and "--graph" in found.notes[0]


def _report(seconds: float, code: str, source: str) -> ReportRecord:
    return ReportRecord(
        t_ns=at(seconds),
        origin="script",
        topic=None,
        fault_code=code,
        event_type="FAILED",
        severity=2,
        description="",
        source_id=source,
        accepted=True,
        reject_reason=None,
    )


def test_entity_default_with_a_graph_takes_the_reporting_nodes_topics() -> None:
    graph = NodeGraph(publishes={"/driver": frozenset({"/odom", "/rosout"})})
    found = plan(
        [confirm(10, "A")],
        SnapshotConfig(),
        graph=graph,
        reports=[_report(10, "A", "/driver")],
    )
    (capture,) = found.captures
    assert capture.topics == ("/odom",) and capture.entity_scoped and not capture.background


def test_entity_scope_widens_from_the_attach_onwards() -> None:
    graph = NodeGraph(publishes={"/a": frozenset({"/odom"}), "/b": frozenset({"/scan"})})
    config = replace(BAG, rosbag=RosbagConfig(enabled=True, topics="entity"))
    found = plan_evidence(
        config,
        [confirm(10, "A"), confirm(10.5, "B")],
        [_report(10, "A", "/a"), _report(10.5, "B", "/b")],
        ["/odom", "/scan", "/tf", "/other"],
        graph,
        STEADY,
    )
    (recording,) = found.recordings
    assert recording.segments == [
        Segment(at(5), at(10), frozenset({"/odom", "/tf"})),
        Segment(at(10) + 1, at(10.5), frozenset({"/odom", "/tf"})),
        Segment(at(10.5) + 1, at(11), frozenset({"/odom", "/scan", "/tf"})),
    ]


def test_entity_mode_without_a_graph_records_everything_and_says_so() -> None:
    config = replace(BAG, rosbag=RosbagConfig(enabled=True, topics="entity"))
    found = plan([confirm(10, "A")], config)
    assert found.recordings[0].segments[0].topics is None
    assert any("entity mode" in note for note in found.notes)


def test_entity_default_off_captures_nothing_even_with_a_graph() -> None:
    graph = NodeGraph(publishes={"/driver": frozenset({"/odom"})})
    config = SnapshotConfig(entity_default=False)
    found = plan([confirm(10, "A")], config, graph=graph, reports=[_report(10, "A", "/driver")])
    assert found.captures == [] and found.notes == []


def test_an_explicit_empty_entry_opts_out_of_the_entity_default() -> None:
    graph = NodeGraph(publishes={"/driver": frozenset({"/odom"})})
    config = SnapshotConfig(fault_specific={"A": ()})
    found = plan([confirm(10, "A")], config, graph=graph, reports=[_report(10, "A", "/driver")])
    assert found.captures == []
