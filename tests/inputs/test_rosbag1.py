"""ROS 1 bags: each topic kind in its ROS 2 shape, the status and level mappings, chunk compression.

Bags are written in tmp_path with rosbags' rosbag1 Writer (tests/inputs/ros1_builders.py).
"""

from __future__ import annotations

import uuid
from typing import TYPE_CHECKING, Any

import numpy as np
import pytest

from medkit_replay import replay
from medkit_replay.bridges.action_status import NetState, derive_state
from medkit_replay.inputs import Message, open_recording
from medkit_replay.inputs.ros1.messages import (
    GOAL_ID_NAMESPACE,
    GOAL_STATUS_TO_ROS2,
    goal_status,
    log_level,
    status_topic,
)
from medkit_replay.msgdefs import base_typestore
from tests.inputs.builders import diag, goal_status as goal_status2, log, write_bag
from tests.inputs.ros1_builders import diag1, log1, status1, string1, write_bag1
from tests.speed.support import plain

if TYPE_CHECKING:
    from pathlib import Path

    from tests.inputs.ros1_builders import Rec1

T = 1_700_000_000 * 10**9
S = 10**9
PENDING, ACTIVE, PREEMPTED, SUCCEEDED, ABORTED = 0, 1, 2, 3, 4
REJECTED, PREEMPTING, RECALLING, RECALLED, LOST = 5, 6, 7, 8, 9
DEBUG, INFO, WARN, ERROR, FATAL = 1, 2, 4, 8, 16


def read(path: Path, **options: Any) -> tuple[list[Message], list[str]]:
    with open_recording([path], **options) as recording:
        return list(recording.messages()), list(recording.warnings)


def class_of(value: object) -> type:
    """``type(value)``, without narrowing what mypy knows of ``value``."""
    return type(value)


def config(tmp_path: Path, text: str, name: str = "params.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


# -- each topic kind, in the shape the bridges read ---------------------------------------------


def test_diagnostics_arrive_as_ros2_diagnostic_arrays(tmp_path: Path) -> None:
    bag = write_bag1(tmp_path / "d.bag", [diag1(T, "motor: Temp", 2, "91 C", "mc/left")])
    (message,), warnings = read(bag)
    assert warnings == []
    assert (message.t_ns, message.topic, message.role) == (T, "/diagnostics", "diagnostics")
    assert message.msgtype == "diagnostic_msgs/msg/DiagnosticArray"
    types = base_typestore().types
    msg: Any = message.msg
    # As the CDR decoder does: the heads for the bridge, the full message when read.
    assert msg.heads == [(2, "motor: Temp", "91 C", "mc/left")]
    assert class_of(msg.header) is types["std_msgs/msg/Header"]
    assert not hasattr(msg.header, "seq")
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id) == (
        T // S,
        0,
        "base",
    )
    (status,) = msg.status
    assert class_of(status) is types["diagnostic_msgs/msg/DiagnosticStatus"]
    assert (status.level, status.name, status.message, status.hardware_id) == (
        2,
        "motor: Temp",
        "91 C",
        "mc/left",
    )
    assert [(kv.key, kv.value) for kv in status.values] == [("temp", "91")]


def test_goal_status_arrays_arrive_on_the_ros2_status_topic(tmp_path: Path) -> None:
    bag = write_bag1(tmp_path / "a.bag", [status1(T, ("/client-1-5.0", ACTIVE), ("g2", ABORTED))])
    (message,), _ = read(bag)
    assert message.topic == "/navigate/_action/status"
    assert message.msgtype == "action_msgs/msg/GoalStatusArray"
    assert message.role == "action_status"
    msg: Any = message.msg
    assert type(message.msg) is base_typestore().types["action_msgs/msg/GoalStatusArray"]
    first, second = msg.status_list
    assert [first.status, second.status] == [2, 6]  # EXECUTING, ABORTED
    expected = uuid.uuid5(GOAL_ID_NAMESPACE, "/client-1-5.0").bytes
    assert isinstance(first.goal_info.goal_id.uuid, np.ndarray)
    assert bytes(first.goal_info.goal_id.uuid) == expected
    assert first.goal_info.stamp.sec == T // S - 1  # the GoalID's stamp


def test_log_lines_arrive_as_rcl_interfaces_logs(tmp_path: Path) -> None:
    bag = write_bag1(tmp_path / "l.bag", [log1(T, ERROR, "lost it", "/ns/planner")])
    (message,), _ = read(bag, rosout=True)
    assert (message.topic, message.msgtype, message.role) == (
        "/rosout",
        "rcl_interfaces/msg/Log",
        "rosout",
    )
    msg: Any = message.msg
    assert type(message.msg) is base_typestore().types["rcl_interfaces/msg/Log"]
    assert (msg.level, msg.name, msg.msg, msg.file, msg.function, msg.line) == (
        40,
        "/ns/planner",
        "lost it",
        "node.cpp",
        "loop",
        42,
    )
    assert msg.stamp.sec == T // S


def test_other_topics_are_listed_not_read(tmp_path: Path) -> None:
    recs = [diag1(T), string1(T + 1), log1(T + 2)]
    bag = write_bag1(tmp_path / "o.bag", recs)
    messages, warnings = read(bag)  # no log bridge: /rosout is not read
    assert [m.topic for m in messages] == ["/diagnostics"]
    assert warnings == []
    with open_recording([bag]) as recording:
        list(recording.messages())
        (summary,) = recording.inputs
    assert summary.storage == "rosbag1"
    assert summary.message_count == 3
    assert (summary.start_ns, summary.end_ns) == (T, T + 2)
    assert [(t.topic, t.type, t.role, t.messages) for t in summary.topics] == [
        ("/chatter", "std_msgs/msg/String", None, 1),
        ("/diagnostics", "diagnostic_msgs/msg/DiagnosticArray", "diagnostics", 1),
        ("/rosout", "rosgraph_msgs/msg/Log", None, 1),
    ]


def test_an_extra_topic_is_delivered_as_ros1_decodes_it(tmp_path: Path) -> None:
    bag = write_bag1(tmp_path / "x.bag", [string1(T, text="hello")])
    (message,), _ = read(bag, extra_topics=["/chatter"])
    assert (message.topic, message.msgtype, message.role) == (
        "/chatter",
        "std_msgs/msg/String",
        "extra",
    )
    assert message.msg.data == "hello"  # type: ignore[attr-defined]


def test_a_diagnostics_topic_of_another_type_is_named_in_a_warning(tmp_path: Path) -> None:
    bag = write_bag1(tmp_path / "w.bag", [string1(T, topic="/diagnostics")])
    messages, warnings = read(bag)
    assert messages == []
    assert warnings == [
        f"{bag}: topic /diagnostics has type 'std_msgs/msg/String', not "
        "diagnostic_msgs/msg/DiagnosticArray; not read"
    ]


# -- the mappings -------------------------------------------------------------------------------

STATUS_CASES = [
    # actionlib code, action_msgs code, the bridge's net state (canceled_is_fault false)
    (PENDING, 1, NetState.UNKNOWN),
    (ACTIVE, 2, NetState.UNKNOWN),
    (PREEMPTED, 5, NetState.HEALTHY),
    (SUCCEEDED, 4, NetState.HEALTHY),
    (ABORTED, 6, NetState.FAILED),
    (REJECTED, 0, NetState.UNKNOWN),
    (PREEMPTING, 3, NetState.UNKNOWN),
    (RECALLING, 3, NetState.UNKNOWN),
    (RECALLED, 5, NetState.HEALTHY),
    (LOST, 0, NetState.UNKNOWN),
    (42, 0, NetState.UNKNOWN),
]


@pytest.mark.parametrize(("code", "ros2", "net"), STATUS_CASES)
def test_each_actionlib_status_code(tmp_path: Path, code: int, ros2: int, net: NetState) -> None:
    assert goal_status(code) == ros2
    bag = write_bag1(tmp_path / "s.bag", [status1(T, ("g", code))])
    (message,), _ = read(bag)
    goals = message.msg.status_list  # type: ignore[attr-defined]
    assert [g.status for g in goals] == [ros2]
    assert derive_state(goals, canceled_is_fault=False) is net


def test_every_actionlib_code_is_mapped() -> None:
    assert sorted(GOAL_STATUS_TO_ROS2) == list(range(10))


@pytest.mark.parametrize(("code", "fault"), [
    (ABORTED, "ACTION_NAVIGATE_ABORTED"),
    (PREEMPTED, "ACTION_NAVIGATE_CANCELED"),
    (RECALLED, "ACTION_NAVIGATE_CANCELED"),
    (SUCCEEDED, None),
    (REJECTED, None),
    (LOST, None),
    (PENDING, None),
    (ACTIVE, None),
    (PREEMPTING, None),
    (RECALLING, None),
])  # fmt: skip
def test_each_status_code_through_the_action_status_bridge(
    tmp_path: Path, code: int, fault: str | None
) -> None:
    bag = write_bag1(tmp_path / "s.bag", [status1(T, ("g", ACTIVE)), status1(T + S, ("g", code))])
    cancel = config(
        tmp_path, "action_status_bridge:\n  ros__parameters:\n    canceled_is_fault: true\n"
    )
    result = replay([bag], [cancel])
    assert [f.fault_code for f in result.faults] == ([fault] if fault else [])
    if fault:
        (report,) = result.reports
        assert report.topic == "/navigate/_action/status"
        assert report.source_id == "/navigate"  # the action name, as for a ROS 2 bag


def test_a_succeeded_goal_heals_an_aborted_action(tmp_path: Path) -> None:
    recs = [status1(T, ("a", ABORTED)), status1(T + 20 * S, ("b", SUCCEEDED))]
    result = replay([write_bag1(tmp_path / "h.bag", recs)])
    assert [(r.event_type, r.fault_code) for r in result.reports] == [
        ("FAILED", "ACTION_NAVIGATE_ABORTED"),
        ("PASSED", "ACTION_NAVIGATE_ABORTED"),
    ]


@pytest.mark.parametrize(
    ("ros1", "ros2"),
    [(DEBUG, 10), (INFO, 20), (WARN, 30), (ERROR, 40), (FATAL, 50), (0, 0), (3, 20), (6, 30),
     (24, 50), (32, 60), (127, 70)],
)  # fmt: skip
def test_each_log_level(tmp_path: Path, ros1: int, ros2: int) -> None:
    assert log_level(ros1) == ros2
    assert log_level(-128) == 80  # a byte of 0x80, as rosbags decodes it
    bag = write_bag1(tmp_path / "l.bag", [log1(T, ros1)])
    (message,), _ = read(bag, rosout=True)
    assert message.msg.level == ros2  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("level", "severity"),
    [(DEBUG, None), (INFO, None), (WARN, 1), (ERROR, 2), (FATAL, 3)],
)
def test_each_log_level_through_the_log_bridge(
    tmp_path: Path, level: int, severity: int | None
) -> None:
    recs = [log1(T + k * S, level, "motor stalled", "/base/driver") for k in range(3)]
    floor = config(tmp_path, "log_bridge:\n  ros__parameters:\n    severity_floor: 30\n")
    result = replay([write_bag1(tmp_path / "l.bag", recs)], [floor])
    faults = [(f.fault_code, f.severity, f.reporting_sources) for f in result.faults]
    if severity is None:
        assert faults == []
    else:
        # A ROS 1 node name is its full name: the source is /base/driver, not /base.
        ((code, got, sources),) = faults
        assert (code.startswith("LOG_BASE_DRIVER_"), got, sources) == (
            True,
            severity,
            ("/base/driver",),
        )


def test_rosout_agg_is_read_only_when_it_is_the_rosout_topic(tmp_path: Path) -> None:
    recs = [log1(T, ERROR, topic="/rosout_agg")]
    bag = write_bag1(tmp_path / "agg.bag", recs)
    default = config(tmp_path, "log_bridge:\n  ros__parameters:\n    severity_floor: 30\n")
    assert replay([bag], [default]).faults == ()
    agg = config(
        tmp_path,
        "log_bridge:\n  ros__parameters:\n    rosout_topic: /rosout_agg\n",
        "agg.yaml",
    )
    (fault,) = replay([bag], [agg]).faults
    assert fault.fault_code.startswith("LOG_NODE_")


def test_status_topic_names() -> None:
    assert status_topic("/move_base/status") == "/move_base/_action/status"
    assert status_topic("/ns/arm/status") == "/ns/arm/_action/status"
    assert status_topic("/status") == "/_action/status"  # no action name: not an action
    assert status_topic("/odom") == "/odom"


def test_a_bare_status_topic_is_no_action(tmp_path: Path) -> None:
    bag = write_bag1(tmp_path / "b.bag", [status1(T, ("g", ABORTED), topic="/status")])
    assert read(bag) == ([], [])


# -- the same traffic as a ROS 2 bag gives the same report --------------------------------------


def ros1_and_ros2_traffic() -> tuple[list[Rec1], list[Any]]:
    ros1: list[Rec1] = []
    ros2: list[Any] = []
    for k in range(12):
        t = T + k * S
        level = 2 if 3 <= k < 7 else 0
        ros1.append(diag1(t, "motor: Temp", level, "hot" if level else "ok"))
        ros2.append(diag(t, "motor: Temp", level, "hot" if level else "ok"))
    for t, code1, code2 in ((T + 2 * S, ABORTED, 6), (T + 9 * S, SUCCEEDED, 4)):
        ros1.append(status1(t + 1, ("g", code1)))
        ros2.append(goal_status2(t + 1, code2))
    for t, level1, level2, text in (
        (T + 4 * S, FATAL, 50, "overheat"),
        (T + 5 * S, ERROR, 40, "lost"),
    ):
        ros1.append(log1(t + 2, level1, f"driver {text} 3", "/driver"))
        ros2.append(log(t + 2, level2, f"driver {text} 3", "driver"))
    return sorted(ros1, key=lambda r: r.t_ns), sorted(ros2, key=lambda r: r.t_ns)


def test_ros1_traffic_replays_as_the_same_ros2_traffic(tmp_path: Path) -> None:
    ros1, ros2 = ros1_and_ros2_traffic()
    bag1 = write_bag1(tmp_path / "r1.bag", ros1)
    bag2 = write_bag(tmp_path / "r2", ros2, storage="mcap")
    params = config(tmp_path, "log_bridge:\n  ros__parameters:\n    severity_floor: 30\n")
    one, two = replay([bag1], [params]), replay([bag2], [params])
    assert one.faults == two.faults
    assert list(one.reports) == list(two.reports)
    assert list(one.transitions) == list(two.transitions)
    assert list(one.events) == list(two.events)
    assert len(one.faults) == 4
    assert one.warnings == two.warnings == ()


# -- chunk compression --------------------------------------------------------------------------


def normalised(messages: list[Message]) -> list[tuple[int, str, str, str]]:
    return [(m.t_ns, m.topic, m.msgtype, repr(plain(m.msg))) for m in messages]


def many(count: int = 300) -> list[Rec1]:
    recs: list[Rec1] = []
    for k in range(count):
        t = T + k * 10**7
        recs += [diag1(t, f"s{k % 7}", k % 3), string1(t + 1)]
        if k % 10 == 0:
            recs += [log1(t + 2, ERROR, f"line {k}"), status1(t + 3, (f"g{k}", k % 10))]
    return recs


@pytest.mark.parametrize("chunks", ["bz2", "lz4"])
def test_compressed_chunks_give_the_same_messages(tmp_path: Path, chunks: Any) -> None:
    plain = write_bag1(tmp_path / "plain.bag", many(), "none", chunk_bytes=4096)
    packed = write_bag1(tmp_path / f"{chunks}.bag", many(), chunks, chunk_bytes=4096)
    expected, warnings = read(plain, rosout=True)
    assert len(expected) == 300 + 30 + 30
    assert warnings == []
    got, warnings = read(packed, rosout=True)
    assert warnings == []
    assert normalised(got) == normalised(expected)
    assert packed.stat().st_size < plain.stat().st_size


def test_messages_out_of_order_across_chunks_come_out_in_order(tmp_path: Path) -> None:
    # A recorder writes in arrival order; log times may step back a little across chunks.
    recs = [diag1(T + (k ^ 1) * S, f"s{k}") for k in range(40)]
    bag = write_bag1(tmp_path / "o.bag", recs, "lz4", chunk_bytes=256)
    messages, warnings = read(bag)
    assert [m.t_ns for m in messages] == sorted(T + k * S for k in range(40))
    assert warnings == []


def test_a_type_recorded_with_another_md5sum_is_decoded_with_a_warning(tmp_path: Path) -> None:
    from rosbags.rosbag1 import Writer  # noqa: PLC0415

    from tests.inputs.ros1_builders import TS1  # noqa: PLC0415

    rec = diag1(T)
    path = tmp_path / "md5.bag"
    with Writer(path) as writer:
        msgdef = TS1.generate_msgdef(rec.msgtype, ros_version=1)[0]
        connection = writer.add_connection(
            "/diagnostics", rec.msgtype, msgdef=msgdef, md5sum="0123456789abcdef" * 2
        )
        writer.write(connection, T, bytes(TS1.serialize_ros1(rec.msg, rec.msgtype)))
    (message,), warnings = read(path)
    assert message.msg.heads == [(2, "motor", "hot", "hw")]  # type: ignore[attr-defined]
    assert warnings == [
        f"{path}: topic /diagnostics: type diagnostic_msgs/DiagnosticArray recorded with md5sum "
        "'0123456789abcdef0123456789abcdef', not the standard one; decoded with the standard "
        "definition"
    ]


# -- uncompressed chunks read through their index data ------------------------------------------


def big_frames(count: int = 60) -> list[Rec1]:
    """Diagnostics and logs between large unread messages, as a camera-heavy bag holds them."""
    recs: list[Rec1] = []
    for k in range(count):
        t = T + k * 10**8
        recs += [string1(t, "/camera", "x" * 20_000), diag1(t + 1, f"s{k}", k % 3)]
        recs += [diag1(t + 2, f"t{k}")] if k % 2 else [log1(t + 2, ERROR, f"line {k}")]
    return recs


def read_counting(path: Path, monkeypatch: pytest.MonkeyPatch, *, use_index: bool) -> Any:
    from medkit_replay.inputs.ros1.file import Bag1File  # noqa: PLC0415

    total = [0]
    original = Bag1File._read_at

    def counting(self: Bag1File, pos: int, size: int) -> bytes:
        data = original(self, pos, size)
        total[0] += len(data)
        return data

    monkeypatch.setattr(Bag1File, "_read_at", counting)
    messages, warnings = read(path, rosout=True, use_index=use_index)
    return normalised(messages), warnings, total[0]


def test_uncompressed_chunks_are_read_through_their_index(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    bag = write_bag1(tmp_path / "frames.bag", big_frames(), chunk_bytes=100_000)
    indexed, warnings, indexed_bytes = read_counting(bag, monkeypatch, use_index=True)
    whole, whole_warnings, whole_bytes = read_counting(bag, monkeypatch, use_index=False)
    assert (indexed, warnings) == (whole, whole_warnings)
    assert len(indexed) == 120
    assert whole_bytes > bag.stat().st_size * 0.9
    assert indexed_bytes < bag.stat().st_size * 0.1  # the frames are never read


def test_damaged_index_data_falls_back_to_the_whole_chunk(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from tests.inputs.ros1_builders import patched, records  # noqa: PLC0415

    bag = write_bag1(tmp_path / "frames.bag", big_frames(), chunk_bytes=100_000)
    expected = read_counting(bag, monkeypatch, use_index=False)[:2]
    index_data = [r for r in records(bag) if r.op == 0x04]
    for k, record in enumerate(index_data[:12]):
        # An entry's offset (its last 4 bytes), then its time, pointed elsewhere.
        for where in (record.data_start + 8, record.data_start + 4):
            damaged = patched(bag, tmp_path / f"idx_{k}_{where}.bag", where, b"\x10\x00\x00\x00")
            assert read_counting(damaged, monkeypatch, use_index=True)[:2] == expected
