"""Upstream's snapshot and rosbag-capture rules, ported as data: topic resolution order,
sorted patterns, entity scope, the black box's subscribe set, sensor topics, eviction, naming.

Sources: test_snapshot_capture.cpp (TopicResolutionTest, EntityDefaultCaptureTest),
test_rosbag_capture.cpp (topic modes, RosbagHighBandwidthTopicTest), test_fault_manager.cpp
(snapshot cap), and snapshot_capture.cpp / rosbag_capture.cpp where the tests are silent.
"""

from __future__ import annotations

import pytest

from medkit_replay.evidence.graph import NodeGraph
from medkit_replay.evidence.rules import (
    RosbagConfig,
    SnapshotConfig,
    entity_rosbag_topics,
    entity_snapshot_topics,
    evict_capture_sets,
    is_sensor_topic,
    recording_name,
    resolve_configured,
    subscribed_topics,
)

# test_snapshots.yaml, as upstream's tests configure it
UPSTREAM = SnapshotConfig(
    fault_specific={"TEST_SNAPSHOT_FAULT": ("/test/temperature",)},
    patterns=(("MOTOR_.*", ("/test/motor_state",)),),
    default_topics=("/test/default_data",),
)

RESOLUTION = [
    # (config, fault code, topics, where they came from)
    (UPSTREAM, "TEST_SNAPSHOT_FAULT", ("/test/temperature",), "fault_specific"),
    (UPSTREAM, "MOTOR_OVERHEAT", ("/test/motor_state",), "pattern"),
    (UPSTREAM, "UNKNOWN_FAULT", ("/test/default_data",), "default_topics"),
    # fault_specific wins over a pattern that also matches
    (
        SnapshotConfig(fault_specific={"MOTOR_STALL": ("/a",)}, patterns=(("MOTOR_.*", ("/b",)),)),
        "MOTOR_STALL",
        ("/a",),
        "fault_specific",
    ),
    # patterns are tried in sorted order (std::map); the first full match wins
    (
        SnapshotConfig(patterns=(("MOTOR_.*", ("/motor",)), ("MOTOR_L.*", ("/left",)))),
        "MOTOR_LEFT",
        ("/motor",),
        "pattern",
    ),
    # a pattern must match the whole code (std::regex_match)
    (SnapshotConfig(patterns=(("MOTOR", ("/m",)),)), "MOTOR_LEFT", (), "none"),
    # nothing configured: entity default decides
    (SnapshotConfig(), "ANY", (), "none"),
    # an explicit empty entry is an opt-out, no fallback to default_topics
    (
        SnapshotConfig(fault_specific={"QUIET": ()}, default_topics=("/d",)),
        "QUIET",
        (),
        "fault_specific",
    ),
]


@pytest.mark.parametrize(("config", "code", "topics", "source"), RESOLUTION)
def test_resolution_order(
    config: SnapshotConfig, code: str, topics: tuple[str, ...], source: str
) -> None:
    resolution = resolve_configured(config, code)
    assert (resolution.topics, resolution.source) == (topics, source)
    assert resolution.explicit == (source != "none")


GRAPH = NodeGraph(
    publishes={
        "/motor_driver": frozenset({"/motor/state", "/rosout", "/parameter_events", "/tf"}),
        "/robot1/planner": frozenset({"/plan"}),
        "/tank_process": frozenset({"/tank/level"}),
        "/busy": frozenset(f"/t{i:02d}" for i in range(20)),
    },
    subscribes={"/motor_driver": frozenset({"/cmd_vel"})},
)

ENTITY_SNAPSHOT = [
    (["/motor_driver"], ("/motor/state", "/tf")),  # /rosout and /parameter_events left out
    (["/robot1/planner"], ("/plan",)),  # namespace + name
    (["tank_process"], ()),  # a bare plugin id never matches a root node of the same name
    (["/nobody"], ()),  # unresolvable source: nothing (no row)
    ([], ()),
    (["/busy"], tuple(f"/t{i:02d}" for i in range(16))),  # first 16 in name order
]


@pytest.mark.parametrize(("sources", "topics"), ENTITY_SNAPSHOT)
def test_entity_default_snapshot_topics(sources: list[str], topics: tuple[str, ...]) -> None:
    assert entity_snapshot_topics(GRAPH, sources) == topics


def test_entity_rosbag_scope_adds_tf_and_keeps_to_the_subscribed_set() -> None:
    subscribed = ["/motor/state", "/cmd_vel", "/tf", "/odom"]
    assert entity_rosbag_topics(GRAPH, ["/motor_driver"], subscribed) == {
        "/motor/state",
        "/cmd_vel",
        "/tf",
    }
    # the black box treats a bare id as a root-namespace node (rosbag_capture.cpp differs)
    assert entity_rosbag_topics(GRAPH, ["tank_process"], ["/tank/level", "/tf"]) == {
        "/tank/level",
        "/tf",
    }
    assert entity_rosbag_topics(GRAPH, ["/nobody"], subscribed) == set()


RECORDED = [
    "/odom",
    "/rosout",
    "/rosout_agg",
    "/parameter_events",
    "/camera/image_raw",
    "/scan/points",
    "/battery",
    "/waypoints",
]

SUBSCRIBE = [
    (RosbagConfig(topics="all"), ["/battery", "/odom", "/waypoints"]),
    (RosbagConfig(topics="auto"), ["/battery", "/odom", "/waypoints"]),
    (RosbagConfig(topics="entity"), ["/battery", "/odom", "/waypoints"]),
    (
        RosbagConfig(topics="all", exclude_sensor_topics=False),
        ["/battery", "/camera/image_raw", "/odom", "/scan/points", "/waypoints"],
    ),
    (RosbagConfig(topics="all", exclude_topics=("/odom",)), ["/battery", "/waypoints"]),
    (RosbagConfig(topics="explicit"), []),
    (RosbagConfig(topics="explicit", include_topics=("/a", "/b")), ["/a", "/b"]),
    (RosbagConfig(topics=" /odom, /battery ,,"), ["/battery", "/odom"]),
    # include_topics may add what a broad mode skipped; /rosout stays out of broad modes
    (
        RosbagConfig(topics="all", include_topics=("/rosout",)),
        ["/battery", "/odom", "/rosout", "/waypoints"],
    ),
    (RosbagConfig(topics="config"), ["/d", "/fs", "/p"]),
]


@pytest.mark.parametrize(("rosbag", "topics"), SUBSCRIBE)
def test_subscribe_set(rosbag: RosbagConfig, topics: list[str]) -> None:
    config = SnapshotConfig(
        rosbag=rosbag,
        default_topics=("/d",),
        fault_specific={"X": ("/fs",)},
        patterns=(("Y.*", ("/p",)),),
    )
    assert subscribed_topics(config, RECORDED) == topics


@pytest.mark.parametrize(
    ("topic", "sensor"),
    [
        ("/camera/image_raw", True),
        ("/image", True),
        ("/points", True),
        ("/camera/depth/points", True),
        ("/camera/image_raw/compressed", True),
        ("/waypoints", False),
        ("/setpoints", False),
        ("/keypoints", False),
        ("/joint_states", False),
        ("/cmd_vel", False),
    ],
)
def test_high_bandwidth_topics(topic: str, sensor: bool) -> None:
    assert is_sensor_topic(topic) is sensor


EVICTION = [
    # cap 4, three 2-topic captures: the oldest set goes whole
    ([(1, 2), (2, 2), (3, 2)], 4, {1}),
    # a single capture larger than the cap is kept whole
    ([(1, 6)], 4, set()),
    ([(1, 2), (2, 6)], 4, {1}),
    # cap 0 keeps everything
    ([(i, 2) for i in range(1, 11)], 0, set()),
    ([(1, 1), (2, 1), (3, 1)], 3, set()),
]


@pytest.mark.parametrize(("sets", "cap", "evicted"), EVICTION)
def test_max_per_fault_evicts_whole_capture_sets(
    sets: list[tuple[int, int]], cap: int, evicted: set[int]
) -> None:
    assert evict_capture_sets(sets, cap) == evicted


@pytest.mark.parametrize(
    ("code", "name"),
    [
        ("MOTOR_OVERHEAT", "fault_MOTOR_OVERHEAT_1700000001234"),
        ("../../etc/passwd", "fault_______etc_passwd_1700000001234"),
        ("a/b", "fault_a_b_1700000001234"),
        ("..", "fault_.._1700000001234".replace("..", "__")),
    ],
)
def test_recording_names_stay_one_safe_component(code: str, name: str) -> None:
    made = recording_name(code, 1_700_000_001_234_567_890)
    assert made == name
    assert "/" not in made and ".." not in made
