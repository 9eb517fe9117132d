"""The black box at 0.6.0 (bdcc4ed0's rosbag_capture.cpp) beside 0.7.0, on the same transitions.

At 0.6.0 ``on_fault_confirmed`` skips a confirmation while a post-roll runs ("Already recording
post-fault data"), ``flush_to_bag`` makes no bag from an empty buffer, the row is stored when the
post-roll ends whatever happened to the fault meanwhile, and ``store_rosbag_file`` keeps one
recording per fault; and no freeze frame falls back to the reporting node's own topics
(snapshot_capture.cpp has no entity default before a702f94f). Upstream's lifecycle tests at
bdcc4ed0 are ported as rows: RosbagCaptureIntegrationTest.MultipleFaultsHandled (two faults
confirmed back to back) and FaultClearedBeforeConfirmed; test_rosbag_integration.test.py test_02
(auto-cleanup on clear).
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import pytest

from medkit_replay.evidence.graph import NodeGraph
from medkit_replay.evidence.rules import RosbagConfig, SnapshotConfig
from tests.evidence.test_plan import BAG, Messages, _report, at, clear, confirm, plan, step

if TYPE_CHECKING:
    from medkit_replay.model import Transition

OLD = replace(
    BAG,
    rosbag=RosbagConfig(
        enabled=True,
        topics="all",
        format="sqlite3",
        bag_history=False,
        post_roll_sharing=False,
        post_roll_only=False,
        cleanup_in_post_roll=False,
    ),
)
"""BAG as 0.6.0 reads it (see test_config_060 for the mapping from parameters)."""
RELEASES = {"0.6.0": OLD, "0.7.0": BAG}


Row = tuple[str, tuple[str, ...], bool]


def rows(config: SnapshotConfig, transitions: list[Transition]) -> list[Row]:
    """Each recording: its name, the faults with a row, whether it is kept at the end."""
    return [
        (r.name, tuple(r.rows), r.deleted is None) for r in plan(transitions, config).recordings
    ]


UPSTREAM_CASES: list[tuple[str, list[Transition], dict[str, list[Row]]]] = [
    (
        "RosbagCaptureIntegrationTest.MultipleFaultsHandled (B during A's post-roll)",
        [confirm(10, "A"), confirm(10.5, "B")],
        {
            "0.6.0": [("fault_A_10000", ("A",), True)],
            "0.7.0": [("fault_A_10000", ("A", "B"), True)],
        },
    ),
    (
        "test_rosbag_integration test_02_rosbag_auto_cleanup_on_clear (during the post-roll)",
        [confirm(10, "A"), clear(10.5, "A")],
        {"0.6.0": [("fault_A_10000", ("A",), True)], "0.7.0": [("fault_A_10000", (), False)]},
    ),
    (
        "test_rosbag_integration test_02_rosbag_auto_cleanup_on_clear (after it)",
        [confirm(10, "A"), clear(20, "A")],
        {"0.6.0": [("fault_A_10000", ("A",), False)], "0.7.0": [("fault_A_10000", ("A",), False)]},
    ),
    (
        "RosbagCaptureIntegrationTest.FaultClearedBeforeConfirmed",
        [step(8, "A", None, "PREFAILED"), clear(9, "A", "PREFAILED")],
        {"0.6.0": [], "0.7.0": []},
    ),
]


@pytest.mark.parametrize(
    ("transitions", "expected"),
    [case[1:] for case in UPSTREAM_CASES],
    ids=[case[0] for case in UPSTREAM_CASES],
)
def test_upstream_lifecycle_cases(
    transitions: list[Transition], expected: dict[str, list[Row]]
) -> None:
    for name, config in RELEASES.items():
        assert rows(config, transitions) == expected[name], name


def test_a_confirmation_during_a_post_roll_gets_no_recording_at_060() -> None:
    assert [
        r.fault_codes for r in plan([confirm(10, "A"), confirm(10.5, "B")], OLD).recordings
    ] == [("A",)]
    # after the post-roll ends the next fault gets its own recording, as at 0.7.0
    assert len(plan([confirm(10, "A"), confirm(11.5, "B")], OLD).recordings) == 2


def test_an_empty_buffer_makes_no_recording_at_060() -> None:
    quiet = Messages({"/odom": [9.0, 10.5]})  # nothing between the first window's end and 11.2
    transitions = [confirm(10, "A"), confirm(11.2, "B")]
    assert [r.fault_code for r in plan(transitions, BAG, quiet).recordings] == ["A", "B"]
    assert [r.fault_code for r in plan(transitions, OLD, quiet).recordings] == ["A"]


def test_one_recording_per_fault_at_060_replaced_by_the_next() -> None:
    transitions = [
        confirm(10, "A"),
        step(30, "A", "CONFIRMED", "HEALED"),
        confirm(80, "A", "HEALED"),
    ]
    old, new = plan(transitions, OLD).recordings
    assert old.deleted == (at(81), "one per fault: replaced by fault_A_80000 for A")
    assert new.deleted is None
    # max_bags_per_fault does not exist at 0.6.0: the config never carries another cap
    assert OLD.rosbag.max_bags_per_fault == 1


def test_no_entity_default_capture_at_060() -> None:
    graph = NodeGraph(publishes={"/driver": frozenset({"/odom"})})
    reports = [_report(10, "A", "/driver")]
    new = plan([confirm(10, "A")], SnapshotConfig(), graph=graph, reports=reports)
    assert [c.topics for c in new.captures] == [("/odom",)]
    old_config = replace(SnapshotConfig(), entity_default=False, freeze_frame_row=False)
    old = plan([confirm(10, "A")], old_config, graph=graph, reports=reports)
    assert old.captures == [] and old.notes == []  # nothing to capture, nothing to say
