"""Reading the capture settings (snapshots.*, snapshots.rosbag.*, the snapshot config file)
and the node graph (--graph): upstream's defaults and sanitising, clear errors for bad files."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING

import pytest

from medkit_replay.cli import main
from medkit_replay.config.params import load_parameters
from medkit_replay.config.snapshots import snapshot_config
from medkit_replay.errors import ConfigError
from medkit_replay.evidence.graph import load_graph
from medkit_replay.evidence.rules import RosbagConfig, SnapshotConfig

if TYPE_CHECKING:
    from pathlib import Path


def read(tmp_path: Path, text: str) -> tuple[SnapshotConfig, list[str]]:
    path = tmp_path / "params.yaml"
    path.write_text(text)
    return snapshot_config(load_parameters([path]).node("fault_manager"))


def test_upstream_defaults(tmp_path: Path) -> None:
    config, warnings = read(tmp_path, "fault_manager:\n  ros__parameters: {}\n")
    assert config == SnapshotConfig()
    assert config.enabled and config.entity_default and not config.rosbag.enabled
    assert (config.timeout_sec, config.max_message_size, config.max_per_fault) == (1.0, 65536, 10)
    assert config.recapture_cooldown_sec == 60.0 and warnings == []


def test_the_snapshot_file_resolves_beside_its_yaml_and_patterns_sort(tmp_path: Path) -> None:
    (tmp_path / "snap.yaml").write_text(
        "fault_specific:\n  A: [/a]\n  QUIET: []\npatterns:\n  'Z.*': [/z]\n  'B.*': [/b]\n"
        "  '([': [/bad]\ndefault_topics: [/d]\n"
    )
    config, warnings = read(
        tmp_path,
        "fault_manager:\n  ros__parameters:\n    snapshots:\n      config_file: snap.yaml\n"
        "      default_topics: ['']\n",
    )
    assert config.fault_specific == {"A": ("/a",), "QUIET": ()}
    assert config.patterns == (("B.*", ("/b",)), ("Z.*", ("/z",)))
    assert config.default_topics == ("/d",)  # [''] is "none": the file's list applies
    assert len(warnings) == 1 and "'(['" in warnings[0]


def test_sanitising_follows_upstream(tmp_path: Path) -> None:
    config, warnings = read(
        tmp_path,
        "fault_manager:\n  ros__parameters:\n    snapshots:\n"
        "      recapture_cooldown_sec: -1.0\n      timeout_sec: 0.0\n      max_message_size: 0\n"
        "      max_per_fault: -3\n      rosbag:\n        enabled: true\n"
        "        duration_sec: -2.0\n        duration_after_sec: -1.0\n        format: zip\n"
        "        max_bags_per_fault: -1\n        max_bag_size_mb: 0\n",
    )
    assert config.recapture_cooldown_sec == 0.0 and config.timeout_sec == 1.0
    assert config.max_message_size == 65536 and config.max_per_fault == 0
    assert config.rosbag == RosbagConfig(
        enabled=True,
        duration_sec=5.0,
        duration_after_sec=0.0,
        format="sqlite3",
        max_bags_per_fault=0,
    )
    assert len(warnings) == 9


def test_a_missing_snapshot_file_is_warned_about(tmp_path: Path) -> None:
    config, warnings = read(
        tmp_path,
        "fault_manager:\n  ros__parameters:\n    snapshots.config_file: nowhere.yaml\n",
    )
    assert config.fault_specific == {} and "nowhere.yaml" in warnings[0]


def test_a_wrong_type_names_the_file_and_line(tmp_path: Path) -> None:
    with pytest.raises(ConfigError) as caught:
        read(tmp_path, "fault_manager:\n  ros__parameters:\n    snapshots.enabled: 3\n")
    assert "params.yaml:3" in str(caught.value)


NODE_INFO = """\
/robot1/driver
  Subscribers:
    /cmd_vel: geometry_msgs/msg/Twist
  Publishers:
    /odom: nav_msgs/msg/Odometry
    /rosout: rcl_interfaces/msg/Log
  Service Servers:
    /robot1/driver/get_parameters: rcl_interfaces/srv/GetParameters
  Action Servers:

/planner
  Publishers:
    /plan: nav_msgs/msg/Path
"""


def test_graph_from_ros2_node_info(tmp_path: Path) -> None:
    path = tmp_path / "graph.txt"
    path.write_text(NODE_INFO)
    graph = load_graph(path)
    assert graph.published("/robot1/driver") == {"/odom", "/rosout"}
    assert graph.subscribed("/robot1/driver") == {"/cmd_vel"}
    assert graph.published("/planner") == {"/plan"}
    assert graph.published("/unknown") == frozenset()


def test_graph_from_yaml(tmp_path: Path) -> None:
    path = tmp_path / "graph.yaml"
    path.write_text("driver:\n  publishers: [/odom]\n  subscribers: {/cmd_vel: x}\n")
    graph = load_graph(path)
    assert graph.published("/driver") == {"/odom"}
    assert graph.subscribed("/driver") == {"/cmd_vel"}


@pytest.mark.parametrize(
    "text",
    ["- a\n- b\n", "driver: 3\n", "driver:\n  talks: [/x]\n", "driver:\n  publishers: [1]\n"],
)
def test_a_bad_graph_is_one_clear_line(
    tmp_path: Path, text: str, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "graph.yaml"
    path.write_text(text)
    script = tmp_path / "s.jsonl"
    script.write_text("")
    assert main(["analyze", str(script), "--graph", str(path), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_evidence_all_needs_evidence(tmp_path: Path) -> None:
    script = tmp_path / "s.jsonl"
    script.write_text("")
    assert main(["analyze", str(script), "--evidence-all", "--quiet"]) == 2


def test_evidence_without_rosbag_capture_says_so(tmp_path: Path) -> None:
    script = tmp_path / "s.jsonl"
    script.write_text("")
    out = tmp_path / "r.json"
    assert (
        main(
            [
                "analyze",
                str(script),
                "--evidence",
                str(tmp_path / "ev"),
                "--json",
                str(out),
                "--quiet",
            ]
        )
        == 0
    )
    notes = json.loads(out.read_text())["evidence_notes"]
    assert notes == [
        "--evidence is given but snapshots.rosbag.enabled is false: no recording to write"
    ]
    assert not (tmp_path / "ev").exists()
