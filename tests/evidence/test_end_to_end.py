"""Evidence end to end on a generated robot recording (odometry, battery, TF, a camera, /rosout)
merged with scripted ReportFault/ClearFault requests: freeze frames equal the expected messages,
recordings hold the source's messages byte for byte in their windows, hostile input is refused.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from rosbags.rosbag2 import Reader, StoragePlugin

from medkit_replay.cli import main
from tests.evidence.robot import CAMERA_BYTES, Robot, at, write_config, write_robot

NS = 1_000_000_000
Run = tuple[Robot, dict[str, Any], Path]


@pytest.fixture(scope="module", params=["mcap", "sqlite3"])
def run(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Run:
    fmt: str = request.param
    root = tmp_path_factory.mktemp(f"robot_{fmt}")
    storage = StoragePlugin.MCAP if fmt == "mcap" else StoragePlugin.SQLITE3
    robot = write_robot(root, storage)
    config = write_config(root, fmt)
    out = root / "report.json"
    evidence = root / "evidence"
    argv = [
        "analyze",
        str(robot.bag),
        str(robot.script),
        "--config",
        str(config),
        "--graph",
        str(robot.graph),
        "--evidence",
        str(evidence),
        "--json",
        str(out),
        "--quiet",
    ]
    assert main(argv) == 0
    return robot, json.loads(out.read_text()), evidence


def test_freeze_frames_are_the_expected_messages(run: Run) -> None:
    _, report, _ = run
    first, battery_fault, last = report["snapshots"]
    assert (first["fault_code"], first["capture_id"], first["t_ns"]) == (
        "MOTOR_OVERCURRENT",
        1,
        at(10),
    )
    # on demand: the first message after the confirmation on each configured topic; the camera
    # frame (230 kB) is over max_message_size and /not_recorded has no publisher
    assert [(t["topic"], t["message_t_ns"]) for t in first["topics"]] == [
        ("/odom", at(10.05)),
        ("/battery", at(10.15)),
        ("/tf", at(10.0) + 1000),
    ]
    odom, battery, tf = (t["data"] for t in first["topics"])
    assert battery == {
        "capacity": ".nan",
        "cell_temperature": None,
        "cell_voltage": None,
        "charge": ".nan",
        "current": -1.25,
        "design_capacity": 20,
        "header": {"frame_id": "battery", "stamp": {"nanosec": 150_000_000, "sec": 1_700_000_010}},
        "location": "base",
        "percentage": 0.798500001,
        "power_supply_health": 1,
        "power_supply_status": 2,
        "power_supply_technology": 3,
        "present": True,
        "serial_number": 12345,
        "temperature": ".nan",
        "voltage": 24.5,
    }
    assert list(odom) == ["child_frame_id", "header", "pose", "twist"]
    assert odom["pose"]["pose"]["position"] == {"x": 10.05, "y": 0.5, "z": 0}
    assert odom["pose"]["covariance"] == [0] * 36
    assert odom["twist"]["twist"]["angular"] == {"x": 0, "y": 0, "z": -0.1}
    assert tf == {
        "transforms": [
            {
                "child_frame_id": "odom",
                "header": {"frame_id": "map", "stamp": {"nanosec": 1000, "sec": 1_700_000_010}},
                "transform": {
                    "rotation": {"w": 1, "x": 0, "y": 0, "z": 0},
                    "translation": {"x": 1, "y": 2, "z": 0},
                },
            }
        ]
    }
    # entity default from the node graph: what /battery_monitor publishes, /rosout left out
    assert battery_fault["fault_code"].startswith("LOG_BATTERY_MONITOR_")
    assert [t["topic"] for t in battery_fault["topics"]] == ["/battery"]
    # the report-driven reconfirmation at 20.1 s fell in the cooldown: nothing captured;
    # the clear at 22 s reset the cooldown
    back = [
        (t["t_ns"], t["from_status"], t["cause"])
        for t in report["transitions"]
        if t["fault_code"] == "MOTOR_OVERCURRENT" and t["to_status"] == "CONFIRMED"
    ]
    assert back == [
        (at(10), None, "report"),
        (at(20.1), "HEALED", "report"),
        (at(25), "CLEARED", "report"),
    ]
    assert (last["capture_id"], last["t_ns"]) == (3, at(25))
    # the clear dropped capture 1's rows; capture 3 is the freeze frame now
    assert [(c["retained"], c["freeze_frame"]) for c in report["snapshots"]] == [
        (False, False),
        (True, True),
        (True, True),
    ]


def _messages(bag: Path, topics: set[str], start: int, end: int) -> list[tuple[str, int, bytes]]:
    with Reader(bag) as reader:
        return [
            (c.topic, t, bytes(raw))
            for c, t, raw in reader.messages()
            if c.topic in topics and start <= t <= end
        ]


def test_recordings_hold_the_source_messages_byte_for_byte(run: Run) -> None:
    robot, report, evidence = run
    recordings = report["recordings"]
    assert [r["recording_id"] for r in recordings] == [
        "fault_MOTOR_OVERCURRENT_1700000010000",
        recordings[1]["recording_id"],
        "fault_MOTOR_OVERCURRENT_1700000025000",
    ]
    cleared, _, kept = recordings
    assert cleared["deleted_ns"] == at(22) and cleared["path"] is None
    assert not (evidence / cleared["recording_id"]).exists()  # only with --evidence-all
    assert (kept["start_ns"], kept["end_ns"]) == (at(20), at(26))
    folder = Path(kept["path"])
    with Reader(folder) as reader:
        copied = [(c.topic, t, bytes(raw)) for c, t, raw in reader.messages()]
        types = {c.topic: (c.msgtype, c.msgdef.data) for c in reader.connections}
    # sensor topics and /rosout are left out of a broad recording by default
    assert {t for t, _, _ in copied} == {"/odom", "/battery", "/tf"}
    assert copied == _messages(robot.bag, {"/odom", "/battery", "/tf"}, at(20), at(26))
    with Reader(robot.bag) as source:
        originals = {c.topic: (c.msgtype, c.msgdef.data) for c in source.connections}
    assert all(types[topic] == originals[topic] for topic in types)
    assert kept["messages"] == len(copied)
    assert kept["bytes"] == sum(len(raw) for _, _, raw in copied)
    assert {t["topic"]: t["messages"] for t in kept["topics"]} == {
        topic: sum(1 for t, _, _ in copied if t == topic) for topic in ("/battery", "/odom", "/tf")
    }


def test_a_written_recording_is_analysed_like_any_bag(run: Run, tmp_path: Path) -> None:
    _, report, _ = run
    folder = report["recordings"][2]["path"]
    out = tmp_path / "clip.json"
    assert main(["analyze", folder, "--json", str(out), "--quiet"]) == 0
    clip = json.loads(out.read_text())
    assert clip["inputs"][0]["message_count"] == report["recordings"][2]["messages"]


def test_evidence_all_writes_the_deleted_recordings_too(tmp_path: Path) -> None:
    robot = write_robot(tmp_path)
    config = write_config(tmp_path)
    out = tmp_path / "everything"
    argv = ["analyze", str(robot.bag), str(robot.script), "--config", str(config)]
    assert main([*argv, "--evidence", str(out), "--evidence-all", "--quiet"]) == 0
    assert (out / "fault_MOTOR_OVERCURRENT_1700000010000" / "metadata.yaml").is_file()
    assert not list(out.glob(".medkit-replay-partial*"))


def test_a_huge_message_is_skipped_not_serialized(tmp_path: Path) -> None:
    from tests.evidence.robot import TS, odometry  # noqa: PLC0415

    huge = odometry(at(10.01), 1.0)
    huge.child_frame_id = "x" * (10 * 1024 * 1024)
    extra = [("/odom", "nav_msgs/msg/Odometry", at(10.01), huge)]
    robot = write_robot(tmp_path, extra=extra)
    config = write_config(tmp_path)
    out = tmp_path / "r.json"
    argv = ["analyze", str(robot.bag), str(robot.script), "--config", str(config)]
    assert main([*argv, "--json", str(out), "--quiet"]) == 0
    first = json.loads(out.read_text())["snapshots"][0]
    # on demand takes the first message after the confirmation: too big, so /odom is skipped
    assert [t["topic"] for t in first["topics"]] == ["/battery", "/tf"]
    assert out.stat().st_size < 1024 * 1024
    assert len(TS.serialize_cdr(huge, "nav_msgs/msg/Odometry")) > 10 * 1024 * 1024


def test_background_capture_takes_the_last_message_before(tmp_path: Path) -> None:
    robot = write_robot(tmp_path)
    config = write_config(tmp_path, extra="medkit_replay:\n  ros__parameters: {}\n")
    text = config.read_text().replace(
        "    snapshots:\n", "    snapshots:\n      background_capture: true\n"
    )
    config.write_text(text)
    out = tmp_path / "r.json"
    argv = ["analyze", str(robot.bag), str(robot.script), "--config", str(config)]
    assert main([*argv, "--json", str(out), "--quiet"]) == 0
    first = json.loads(out.read_text())["snapshots"][0]
    assert [(t["topic"], t["message_t_ns"]) for t in first["topics"]] == [
        ("/odom", at(10.0)),
        ("/battery", at(9.15)),
        ("/tf", at(9.9) + 1000),
    ]


def test_no_path_escapes_the_evidence_folder(tmp_path: Path) -> None:
    from tests.evidence.robot import battery  # noqa: PLC0415

    hostile = "/../../../escape"  # a legal-looking topic name is never a path
    extra = [(hostile, "sensor_msgs/msg/BatteryState", at(21), battery(at(21), 0.5))]
    robot = write_robot(tmp_path, extra=extra)
    config = write_config(tmp_path)
    script = tmp_path / "dots.jsonl"
    lines = [  # upstream refuses these codes; a folder name is made safe all the same
        {
            "t_ns": at(10),
            "op": "report",
            "fault_code": "..",
            "event_type": "FAILED",
            "source_id": "/x",
        },
        {
            "t_ns": at(12),
            "op": "report",
            "fault_code": "../..",
            "event_type": "FAILED",
            "source_id": "/x",
        },
        *(json.loads(line) for line in robot.script.read_text().splitlines()),
    ]
    lines.sort(key=lambda line: line["t_ns"])
    script.write_text("".join(json.dumps(line) + "\n" for line in lines))
    evidence = tmp_path / "nested" / "evidence"
    before = set(tmp_path.parent.rglob("*"))
    argv = [
        "analyze",
        str(robot.bag),
        str(script),
        "--config",
        str(config),
        "--evidence",
        str(evidence),
    ]
    assert main([*argv, "--quiet"]) == 0
    created = set(tmp_path.parent.rglob("*")) - before
    assert created and all(p == evidence.parent or evidence in (p, *p.parents) for p in created)
    with Reader(evidence / "fault_MOTOR_OVERCURRENT_1700000025000") as reader:
        assert hostile in {c.topic for c in reader.connections}


def test_the_camera_is_never_decoded_for_a_recording(run: Run) -> None:
    _, report, _ = run
    assert all(t["topic"] != "/camera/image_raw" for r in report["recordings"] for t in r["topics"])
    assert CAMERA_BYTES > 65536


def test_max_bag_size_splits_a_recording_into_files(tmp_path: Path) -> None:
    robot = write_robot(tmp_path)
    config = write_config(tmp_path)
    text = config.read_text().replace(
        "        topics: all\n",
        "        topics: all\n        exclude_sensor_topics: false\n        max_bag_size_mb: 1\n",
    )
    config.write_text(text)
    out, evidence = tmp_path / "r.json", tmp_path / "evidence"
    argv = ["analyze", str(robot.bag), str(robot.script), "--config", str(config)]
    assert main([*argv, "--evidence", str(evidence), "--json", str(out), "--quiet"]) == 0
    kept = json.loads(out.read_text())["recordings"][2]
    folder = Path(kept["path"])
    files = sorted(p.name for p in folder.glob("*.mcap"))
    assert len(files) >= 6  # 30 camera frames of 230 kB in 1 MB files
    assert files[0] == f"{folder.name}_0.mcap"
    topics = {"/odom", "/battery", "/tf", "/camera/image_raw"}
    with Reader(folder) as reader:
        copied = [(c.topic, t, bytes(raw)) for c, t, raw in reader.messages()]
        assert reader.message_count == kept["messages"] == len(copied)
    assert copied == _messages(robot.bag, topics, at(20), at(26))


def test_a_truncated_recording_gives_a_note_not_a_traceback(tmp_path: Path) -> None:
    robot = write_robot(tmp_path)
    config = write_config(tmp_path)
    (file,) = robot.bag.glob("*.mcap")
    data = file.read_bytes()
    file.write_bytes(data[: len(data) // 2])
    out = tmp_path / "r.json"
    argv = ["analyze", str(robot.bag), str(robot.script), "--config", str(config)]
    assert main([*argv, "--evidence", str(tmp_path / "ev"), "--json", str(out), "--quiet"]) == 0
    report = json.loads(out.read_text())
    assert any("not read for evidence" in note for note in report["evidence_notes"])
    assert report["snapshots"] and all(not c["topics"] for c in report["snapshots"])


NO_COOLDOWN_RETAIN = "      recapture_cooldown_sec: 0.0\n      retain_on_clear: true\n"


@pytest.mark.parametrize(
    ("settings", "motor"),
    [
        # retain_on_clear keeps capture 1 through the clear at 22 s
        ("      retain_on_clear: true\n", [(1, True, False), (2, True, True)]),
        # (no --graph: the battery fault's entity-default capture takes no id)
        # no cooldown: the reconfirmation at 20.1 s captures too; the clear drops 1 and 2
        (
            "      recapture_cooldown_sec: 0.0\n",
            [(1, False, False), (2, False, False), (3, True, True)],
        ),
        # max_per_fault 4 with 3-topic captures: each new set evicts the older one whole
        (
            NO_COOLDOWN_RETAIN + "      max_per_fault: 4\n",
            [(1, False, False), (2, False, False), (3, True, True)],
        ),
        # max_per_fault 0: no limit
        (
            NO_COOLDOWN_RETAIN + "      max_per_fault: 0\n",
            [(1, True, False), (2, True, False), (3, True, True)],
        ),
    ],
)
def test_snapshot_storage_rules(
    tmp_path: Path, settings: str, motor: list[tuple[int, bool, bool]]
) -> None:
    robot = write_robot(tmp_path)
    config = write_config(tmp_path)
    config.write_text(config.read_text().replace("    snapshots:\n", "    snapshots:\n" + settings))
    out = tmp_path / "r.json"
    argv = ["analyze", str(robot.bag), str(robot.script), "--config", str(config)]
    assert main([*argv, "--json", str(out), "--quiet"]) == 0
    captures = json.loads(out.read_text())["snapshots"]
    got = [
        (c["capture_id"], c["retained"], c["freeze_frame"])
        for c in captures
        if c["fault_code"] == "MOTOR_OVERCURRENT"
    ]
    assert got == motor
