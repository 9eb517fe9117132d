"""The fault history serve answers from: filled by the one replay, checked against its report."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from medkit_replay.engine.correlation.engine import CorrelationEngine
from medkit_replay.history import CorrelationState, FaultHistory
from medkit_replay.model import MutedFault
from medkit_replay.pipeline import replay
from tests.gateway import values

if TYPE_CHECKING:
    from medkit_replay.model import FaultSnapshot, Status
    from medkit_replay.result import Result

ROOT = Path(__file__).resolve().parents[2]
MISSION = ROOT / "sample_bags" / "nav2_mission_mcap"
NAV2 = ROOT / "rules" / "nav2" / "fault_manager.yaml"
END = 2**62


def snapshot(code: str, status: Status = "PREFAILED", count: int = 1) -> FaultSnapshot:
    return dataclasses.replace(values.fault(code, status), occurrence_count=count)


def test_a_fault_is_unknown_before_it_is_reported_and_each_change_holds_from_its_time() -> None:
    history = FaultHistory()
    history.put(10, snapshot("B"))
    history.put(20, snapshot("B", "CONFIRMED", 2))
    history.put(20, snapshot("B", "CONFIRMED", 3))  # the same moment: the last one holds
    history.put(30, snapshot("B", "CONFIRMED", 3))  # unchanged: nothing new kept
    assert history.fault_at("B", 9) is None
    assert history.fault_at("B", 10) == snapshot("B")
    assert history.fault_at("B", 19) == snapshot("B")
    assert history.fault_at("B", 20) == snapshot("B", "CONFIRMED", 3)
    assert history.fault_at("A", END) is None
    assert len(history) == 2


def test_faults_come_in_fault_code_byte_order_whatever_order_they_appear_in() -> None:
    history = FaultHistory()
    for t, code in enumerate(["b", "B", "a_2", "a_10", "Z"]):
        history.put(t, snapshot(code))
    assert history.codes == ("B", "Z", "a_10", "a_2", "b")
    assert [f.fault_code for f in history.faults_at(2)] == ["B", "a_2", "b"]


def test_the_correlation_view_keeps_only_changes() -> None:
    history = FaultHistory()
    muted = CorrelationState(muted=(MutedFault(fault_code="S", root_cause_code="R", rule_id="r",
                                               delay_ms=5),))  # fmt: skip
    history.put_correlation(5, CorrelationState())  # nothing yet: not kept
    history.put_correlation(7, muted)
    history.put_correlation(9, muted)
    history.put_correlation(12, CorrelationState())
    assert history.correlation_at(6) == CorrelationState()
    assert history.correlation_at(7) == history.correlation_at(11) == muted
    assert history.correlation_at(12) == CorrelationState()
    assert history.change_times == (7, 12)


@pytest.fixture(scope="module")
def replayed() -> tuple[Result, FaultHistory]:
    history = FaultHistory()
    return replay([MISSION], [NAV2], history=history), history


def test_the_history_at_the_end_is_the_report(replayed: tuple[Result, FaultHistory]) -> None:
    result, history = replayed
    assert tuple(history.faults_at(END)) == result.faults
    state = history.correlation_at(END)
    assert (state.muted, state.clusters) == (result.muted_faults, result.clusters)
    assert state.muted  # the mission mutes symptoms under these rules: the view was exercised


def test_every_transition_is_the_state_the_history_gives(
    replayed: tuple[Result, FaultHistory],
) -> None:
    result, history = replayed
    last: dict[tuple[str, int], str] = {}
    for transition in result.transitions:
        last[transition.fault_code, transition.t_ns] = transition.to_status
        before = history.fault_at(transition.fault_code, transition.t_ns - 1)
        if transition.from_status is None:
            assert before is None
        else:
            assert before is not None and before.status == transition.from_status
    for (code, t_ns), status in last.items():
        found = history.fault_at(code, t_ns)
        assert found is not None and found.status == status
    assert len(last) > 10


def test_every_event_carries_the_state_the_history_gives(
    replayed: tuple[Result, FaultHistory],
) -> None:
    result, history = replayed
    last = {(e.fault.fault_code, e.t_ns): e.fault for e in result.events}
    for (code, t_ns), fault in last.items():
        found = history.fault_at(code, t_ns)
        assert found is not None
        assert (found.status, found.occurrence_count, found.last_occurred_ns) == (
            fault.status, fault.occurrence_count, fault.last_occurred_ns,
        )  # fmt: skip


def test_a_replay_with_a_history_writes_the_same_report(
    replayed: tuple[Result, FaultHistory],
) -> None:
    from medkit_replay.outputs.json_report import dumps  # noqa: PLC0415

    result, _ = replayed
    plain = replay([MISSION], [NAV2])
    assert dumps(plain) == dumps(result)


def test_the_nodes_seen_are_every_reporting_source_and_logging_node() -> None:
    from rosbags.highlevel import AnyReader  # noqa: PLC0415
    from rosbags.typesys import Stores, get_typestore  # noqa: PLC0415

    history = FaultHistory()
    bridges = ROOT / "rules" / "nav2" / "bridges.yaml"  # the log bridge on
    result = replay([MISSION], [NAV2, bridges], history=history)
    with AnyReader([MISSION], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        rosout = [c for c in reader.connections if c.topic == "/rosout"]
        loggers = {
            "/" + str(getattr(reader.deserialize(raw, c.msgtype), "name", "")).replace(".", "/")
            for c, _, raw in reader.messages(connections=rosout)
        }
    reporters = {r.source_id for r in result.reports}
    assert loggers - reporters  # nodes that logged without a report are seen too
    assert history.sources == loggers | reporters


def test_the_cleanup_timer_never_changes_the_correlation_view(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # Why the history does not watch it: only reports and clears change the view recorded.
    ticked = CorrelationEngine.cleanup_expired
    ticks = []

    def checked(engine: CorrelationEngine, now_ns: int) -> None:
        before = (engine.muted_faults(), engine.clusters())
        ticked(engine, now_ns)
        assert (engine.muted_faults(), engine.clusters()) == before
        ticks.append(now_ns)

    monkeypatch.setattr(CorrelationEngine, "cleanup_expired", checked)
    history = FaultHistory()
    result = replay([MISSION], [NAV2], history=history)
    assert ticks and result.muted_faults  # the timer ran with muted symptoms held
