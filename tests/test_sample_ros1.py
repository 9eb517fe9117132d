"""The ROS 1 sample (the Nav2 mission as a ROS 1 bag): rebuilt identically, and the same
conclusions as the ROS 2 mission through analyze, check, diff, fleet and the pytest plugin."""

from __future__ import annotations

import csv
import dataclasses
import hashlib
import json
import shutil
import subprocess
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pytest
from rosbags.rosbag1 import Reader

from medkit_replay import replay
from medkit_replay.cli import main
from medkit_replay.inputs.ros1.messages import ros1_typestore
from medkit_replay.outputs.json_report import dumps
from medkit_replay.pytest_plugin import RecordingReplayer, assert_confirmed, assert_status

if TYPE_CHECKING:
    from collections.abc import Iterator

ROOT = Path(__file__).resolve().parent.parent
SAMPLES = ROOT / "sample_bags"
ROS1 = SAMPLES / "nav2_mission_ros1.bag"
MCAP = SAMPLES / "nav2_mission_mcap"
NAV2 = [ROOT / "rules/nav2/fault_manager.yaml", ROOT / "rules/nav2/bridges.yaml"]
CONFIGS = {
    "defaults": [],
    "nav2": NAV2,
    "bringup": [ROOT / "rules/bringup/fault_manager.yaml", ROOT / "rules/nav2/bridges.yaml"],
}


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    status = main(argv)
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return status, out, err


def normalised(value: object) -> object:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: normalised(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, list):
        return [normalised(v) for v in value]
    return value


def messages(path: Path) -> Iterator[tuple[str, str, int, object]]:
    """Every message of a ROS 1 bag as rosbags reads it: topic, type, log time, fields."""
    store = ros1_typestore()
    with Reader(path) as reader:
        for connection, t_ns, raw in reader.messages():
            msg = store.deserialize_ros1(raw, connection.msgtype)
            yield connection.topic, connection.msgtype, t_ns, normalised(msg)


def test_the_script_rebuilds_the_bundled_ros1_bag(tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, str(SAMPLES / "make_sample_bags.py"), "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        check=False,
        cwd=ROOT,
    )
    assert done.returncode == 0, done.stderr
    assert list(messages(tmp_path / ROS1.name)) == list(messages(ROS1))
    # rosbags' writer is deterministic: the same bytes.
    assert (tmp_path / ROS1.name).read_bytes() == ROS1.read_bytes()


def test_the_ros1_bag_holds_the_mission_in_ros1_types() -> None:
    counts: dict[tuple[str, str], int] = {}
    for topic, msgtype, _, _ in messages(ROS1):
        counts[(topic, msgtype)] = counts.get((topic, msgtype), 0) + 1
    assert counts == {
        ("/diagnostics", "diagnostic_msgs/msg/DiagnosticArray"): 604,
        ("/navigate_to_pose/status", "actionlib_msgs/msg/GoalStatusArray"): 9,
        ("/follow_path/status", "actionlib_msgs/msg/GoalStatusArray"): 13,
        ("/rosout", "rosgraph_msgs/msg/Log"): 25,
        ("/rosout_agg", "rosgraph_msgs/msg/Log"): 25,
    }
    with Reader(ROS1) as reader:
        assert len(reader.chunk_infos) > 5  # several LZ4 chunks
    assert ROS1.stat().st_size < 200_000


@pytest.mark.parametrize("configs", list(CONFIGS), ids=list(CONFIGS))
def test_the_ros1_mission_concludes_what_the_ros2_mission_does(configs: str) -> None:
    one = json.loads(dumps(replay([ROS1], CONFIGS[configs])))
    two = json.loads(dumps(replay([MCAP], CONFIGS[configs])))
    assert one.pop("inputs") != two.pop("inputs")
    if one["recordings"]:
        # Black-box recordings are planned alike, but a ROS 1 bag holds no ROS 2 messages to
        # copy into them: the report says so instead of listing them full.
        plan = ("recording_id", "fault_codes", "end_ns")
        assert [[r[k] for k in plan] for r in one.pop("recordings")] == [
            [r[k] for k in plan] for r in two.pop("recordings")
        ]
        notes = one.pop("evidence_notes")
        assert [n for n in notes if "ROS 1 bag holds no ROS 2 messages" in n]
        assert [n for n in notes if "ROS 1 bag" not in n] == two.pop("evidence_notes")
    assert one == two
    assert one["warnings"] == []


def test_analyze_summarises_the_ros1_bag(capsys: pytest.CaptureFixture[str]) -> None:
    flags = [part for config in NAV2 for part in ("--config", str(config))]
    status, out, _ = run(["analyze", str(ROS1), *flags, "--json", "-", "--quiet"], capsys)
    assert status == 0
    report = json.loads(out)
    (summary,) = report["inputs"]
    assert summary["storage"] == "rosbag1"
    topics = {t["topic"]: (t["type"], t["role"], t["messages"]) for t in summary["topics"]}
    assert topics == {
        "/diagnostics": ("diagnostic_msgs/msg/DiagnosticArray", "diagnostics", 604),
        "/follow_path/status": ("actionlib_msgs/msg/GoalStatusArray", "action_status", 13),
        "/navigate_to_pose/status": ("actionlib_msgs/msg/GoalStatusArray", "action_status", 9),
        "/rosout": ("rosgraph_msgs/msg/Log", "rosout", 25),
        "/rosout_agg": ("rosgraph_msgs/msg/Log", None, 25),  # not the log bridge's topic
    }
    statuses = {f["fault_code"]: f["status"] for f in report["faults"]}
    assert statuses["MOTOR_LEFT_OVERHEAT"] == "HEALED"
    assert statuses["ACTION_NAVIGATE_TO_POSE_ABORTED"] == "HEALED"
    assert statuses["LOG_MOTOR_DRIVER_e76c6116"] == "CONFIRMED"


def test_analyze_leaves_the_bag_untouched(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "in"
    folder.mkdir()
    bag = Path(shutil.copy(ROS1, folder))
    before = hashlib.sha256(bag.read_bytes()).hexdigest()
    status, _, _ = run(["analyze", str(bag), "--json", str(tmp_path / "r.json"), "--quiet"], capsys)
    assert status == 0
    assert [p.name for p in folder.iterdir()] == [ROS1.name]
    assert hashlib.sha256(bag.read_bytes()).hexdigest() == before


@pytest.mark.parametrize(
    ("budget", "expected"), [("nav2_mission_pass.yaml", 0), ("nav2_mission_fail.yaml", 1)]
)
def test_check_holds_the_ros1_bag_to_a_budget(
    budget: str, expected: int, capsys: pytest.CaptureFixture[str]
) -> None:
    flags = [part for config in NAV2 for part in ("--config", str(config))]
    budget_path = str(ROOT / "rules" / "budgets" / budget)
    status, _, _ = run(["check", str(ROS1), *flags, "--budget", budget_path], capsys)
    mcap_status, _, _ = run(["check", str(MCAP), *flags, "--budget", budget_path], capsys)
    assert status == mcap_status == expected


def test_diff_finds_no_difference_between_the_ros1_and_ros2_missions(
    capsys: pytest.CaptureFixture[str],
) -> None:
    flags = [part for config in NAV2 for part in ("--config", str(config))]
    status, out, _ = run(["diff", str(MCAP), str(ROS1), *flags, "--quiet"], capsys)
    assert status == 0, out


def test_fleet_finds_and_replays_a_ros1_bag(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "missions"
    (folder / "robot1").mkdir(parents=True)
    shutil.copy(ROS1, folder / "robot1")
    shutil.copytree(MCAP, folder / "robot2" / MCAP.name)
    flags = [part for config in NAV2 for part in ("--config", str(config))]
    status, _, _ = run(
        ["fleet", str(folder), *flags, "--jobs", "1", "--out", str(tmp_path / "r"), "--quiet"],
        capsys,
    )
    assert status == 0
    with (tmp_path / "r" / "runs.csv").open(newline="") as rows:
        runs = list(csv.DictReader(rows))
    assert [Path(r["path"]).relative_to(folder).as_posix() for r in runs] == [
        "robot1/nav2_mission_ros1.bag",
        "robot2/nav2_mission_mcap",
    ]
    # The same mission: the same row but for the path and the kind of recording.
    assert runs[0]["kind"] == "rosbag1"
    assert runs[0]["error"] == ""
    differ = {k for k in runs[0] if runs[0][k] != runs[1][k]}
    assert differ == {"path", "kind"}


def test_the_pytest_plugin_replays_a_ros1_bag() -> None:
    replayer = RecordingReplayer()
    result = replayer(ROS1, NAV2)
    assert_confirmed(result, "MOTOR_LEFT_OVERHEAT", within=(70, 80))
    assert_status(result, "WIFI_SIGNAL_STRENGTH", "CONFIRMED")
    assert_status(result, "ACTION_FOLLOW_PATH_ABORTED", "HEALED")
