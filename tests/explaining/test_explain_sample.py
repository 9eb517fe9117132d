"""``explain`` on the sample Nav2 mission: every fault's story, complete and consistent."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from medkit_replay.cli import main
from medkit_replay.explaining import build_story, render_story, story_record
from medkit_replay.pipeline import replay
from medkit_replay.trace import FaultTrace

if TYPE_CHECKING:
    from medkit_replay.model import ReportRecord, Transition

ROOT = Path(__file__).resolve().parents[2]
MISSION = ROOT / "sample_bags" / "nav2_mission_mcap"
CONFIGS = [ROOT / "rules" / "nav2" / "fault_manager.yaml", ROOT / "rules" / "nav2" / "bridges.yaml"]
FAULTS = (
    "ACTION_FOLLOW_PATH_ABORTED",
    "ACTION_NAVIGATE_TO_POSE_ABORTED",
    "CAMERA_FRAME_RATE",
    "IMU_DATA_RATE",
    "LIDAR_SCAN_RATE",
    "LOCALIZATION_POSE_CONFIDENCE",
    "LOG_BT_NAVIGATOR_4fc83613",
    "LOG_CONTROLLER_SERVER_e9897eb8",
    "LOG_MOTOR_DRIVER_4cf527a5",
    "LOG_MOTOR_DRIVER_e76c6116",
    "MOTOR_LEFT_COMM_LINK",
    "MOTOR_LEFT_OVERHEAT",
    "WHEEL_ODOMETRY_SLIP",
    "WIFI_SIGNAL_STRENGTH",
)
Record = dict[str, object]


def told(code: str) -> tuple[Record, str, list[ReportRecord], list[Transition]]:
    trace = FaultTrace(fault_code=code)
    result = replay([MISSION], CONFIGS, trace=trace)
    story = build_story(result, trace)
    record: Record = json.loads(json.dumps(story_record(story), allow_nan=False))
    reports = [r for r in result.reports if r.fault_code == code]
    transitions = [t for t in result.transitions if t.fault_code == code]
    return record, render_story(story), reports, transitions


def kind(record: Record, name: str) -> list[Record]:
    entries = record["entries"]
    assert isinstance(entries, list)
    return [e for e in entries if e["kind"] == name]


def test_the_sample_mission_has_these_faults() -> None:
    result = replay([MISSION], CONFIGS)
    assert tuple(f.fault_code for f in result.faults) == FAULTS


@pytest.mark.parametrize("code", FAULTS)
def test_every_fault_has_its_whole_story(code: str) -> None:
    record, text, reports, transitions = told(code)
    told_reports = len(kind(record, "report")) + sum(
        int(str(r["count"])) for r in kind(record, "repeat")
    )
    assert told_reports == len(reports)  # every report that reached the manager
    assert len(kind(record, "transition")) == len(transitions)
    final = replay([MISSION], CONFIGS).fault(code)
    assert final is not None
    assert record["state"]["status"] == final.status  # type: ignore[index]
    assert text.startswith(f"{code}: its story in bag time")
    for report in kind(record, "report"):
        message = report["message"]
        assert isinstance(message, dict) and message["topic"] == report["topic"]


def test_a_muted_symptom_names_root_rule_and_window() -> None:
    record, text, _, _ = told("MOTOR_LEFT_COMM_LINK")
    decision = kind(record, "correlation")[0]
    assert decision["root_cause_code"] == "MOTOR_LEFT_OVERHEAT" and decision["should_mute"]
    assert decision["rule"]["rule_id"] == "motor_overheat_cascade"  # type: ignore[index]
    assert decision["rule"]["window_ms"] == 5000  # type: ignore[index]
    assert kind(record, "event_withheld")
    assert "symptom of MOTOR_LEFT_OVERHEAT under rule motor_overheat_cascade" in text


def test_a_cluster_member_and_its_recorded_status() -> None:
    record, _, _, _ = told("CAMERA_FRAME_RATE")
    assert {d["cluster_id"] for d in kind(record, "correlation")} == {"sensor_storm_1"}
    failed = next(r for r in kind(record, "report") if r["event_type"] == "FAILED")
    message = failed["message"]
    assert isinstance(message, dict)
    assert message["type"] == "diagnostic_msgs/msg/DiagnosticStatus"
    assert message["fields"]["level"] == {"value": 2, "name": "ERROR"}
    assert message["items"] == [["rate_hz", "0.0"]]


def test_an_action_fault_with_per_entity_thresholds() -> None:
    record, _, _, _ = told("ACTION_NAVIGATE_TO_POSE_ABORTED")
    first, healing = kind(record, "report")
    assert first["entity_prefix"] == "/bt_navigator" and first["healing_threshold"] == 0
    assert first["message"]["type"] == "action_msgs/msg/GoalStatusArray"  # type: ignore[index]
    assert first["message"]["items"][0][1] == "ABORTED"  # type: ignore[index]
    assert healing["status"] == "HEALED"


def test_a_log_fault_shows_the_line() -> None:
    record, _, _, _ = told("LOG_MOTOR_DRIVER_4cf527a5")
    message = kind(record, "report")[0]["message"]
    assert isinstance(message, dict) and message["type"] == "rcl_interfaces/msg/Log"
    assert message["fields"]["level"] == {"value": 40, "name": "ERROR"}


def test_reporter_filtering_and_the_near_miss() -> None:
    record, text, _, _ = told("WIFI_SIGNAL_STRENGTH")
    held = kind(record, "held")
    assert held and all(h["stage"] == "local_filter" for h in held)
    assert "came within 1 of confirming at 135.750 s" in text
    assert record["summary"]["closest_near_miss"]["margin"] == 1  # type: ignore[index]


def test_the_command_on_the_sample(capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["explain", str(MISSION), "MOTOR_LEFT_OVERHEAT", "--quiet", "--at", "80"]
    for config in CONFIGS:
        argv += ["--config", str(config)]
    assert main(argv) == 0
    out, err = capsys.readouterr()
    assert err == "" and "state at 80.000 s: CONFIRMED" in out


def test_the_readme_shows_real_output(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("COLUMNS", raising=False)
    monkeypatch.chdir(ROOT)
    section = (ROOT / "docs" / "commands" / "explain.md").read_text(encoding="utf-8")
    example = section.split("```\nmedkit-replay explain sample_bags", 1)[1]
    command, shown = ("sample_bags" + example).split("```\n\n```\n", 1)
    shown = shown.split("\n```", 1)[0] + "\n"
    args = command.strip().split()
    assert main(["explain", *args, "--quiet"]) == 0
    out, _ = capsys.readouterr()
    assert out == shown
