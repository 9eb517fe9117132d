"""The bundled sample recordings and rules: rebuilt identically, and the verdicts they give.

sample_bags/README.md tells each recording's story; these tests pin it, config by config.
"""

from __future__ import annotations

import dataclasses
import json
import shlex
import subprocess
import sys
from collections import Counter
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pytest
from rosbags.rosbag2 import Reader

from medkit_replay import replay
from medkit_replay.cli import main
from medkit_replay.msgdefs import base_typestore
from medkit_replay.outputs.json_report import dumps

if TYPE_CHECKING:
    from collections.abc import Iterator

ROOT = Path(__file__).resolve().parent.parent
SAMPLES = ROOT / "sample_bags"
SCRIPT = SAMPLES / "make_sample_bags.py"
MCAP = "nav2_mission_mcap"
SQLITE3 = "nav2_mission_sqlite3"
SERVICES = "service_calls.mcap"
SAMPLE_NAMES = (MCAP, SQLITE3, SERVICES)
T0_NS = 1_773_480_413_000_000_000  # the script's bag time zero, 2026-03-14 09:26:53 UTC

NAV2 = ("rules/nav2/fault_manager.yaml",)
NAV2_BRIDGES = (*NAV2, "rules/nav2/bridges.yaml")
BRINGUP = ("rules/bringup/fault_manager.yaml",)
BRINGUP_BRIDGES = (*BRINGUP, "rules/nav2/bridges.yaml")
CONFIGS = {"nav2": NAV2, "nav2+bridges": NAV2_BRIDGES, "bringup": BRINGUP}
CONFIGS["bringup+bridges"] = BRINGUP_BRIDGES

Report = dict[str, Any]

# -- (a) the script rebuilds exactly the bundled recordings --------------------------------------


def normalised(value: object) -> object:
    """A decoded message as plain data: type name and fields, arrays as lists."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = {f.name: normalised(getattr(value, f.name)) for f in dataclasses.fields(value)}
        return {"__msgtype__": getattr(value, "__msgtype__", type(value).__name__), **fields}
    if isinstance(value, np.ndarray):
        return [normalised(v) for v in value.tolist()]
    if isinstance(value, list | tuple):
        return [normalised(v) for v in value]
    return value


def messages(path: Path) -> Iterator[tuple[str, str, int, object]]:
    """Every message of a recording in storage order: topic, type, log time, normalised form."""
    store = base_typestore()
    with Reader(path) as reader:
        for connection, t_ns, raw in reader.messages():
            msg = store.deserialize_cdr(raw, connection.msgtype)
            yield connection.topic, connection.msgtype, t_ns, normalised(msg)


@pytest.fixture(scope="module")
def rebuilt(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("rebuilt")
    done = subprocess.run(
        [sys.executable, str(SCRIPT), "--out", str(out)],
        capture_output=True,
        text=True,
        check=False,
        cwd=ROOT,
    )
    assert done.returncode == 0, done.stderr
    written = (*SAMPLE_NAMES, "nav2_mission_ros1.bag")  # the ROS 1 bag: tests/test_sample_ros1.py
    assert done.stdout.splitlines() == [f"wrote {out / name}" for name in written]
    return out


@pytest.mark.parametrize("name", SAMPLE_NAMES)
def test_script_rebuilds_the_bundled_messages(rebuilt: Path, name: str) -> None:
    bundled = list(messages(SAMPLES / name))
    assert bundled, name
    assert list(messages(rebuilt / name)) == bundled


def test_mcap_and_sqlite3_missions_hold_the_same_messages() -> None:
    assert list(messages(SAMPLES / MCAP)) == list(messages(SAMPLES / SQLITE3))


def test_samples_are_small_and_the_mission_lasts_minutes() -> None:
    for name in SAMPLE_NAMES:
        path = SAMPLES / name
        files = list(path.iterdir()) if path.is_dir() else [path]
        assert sum(p.stat().st_size for p in files) < 1_000_000, name
    times = [t for _, _, t, _ in messages(SAMPLES / MCAP)]
    assert times == sorted(times)
    assert 120 < (times[-1] - times[0]) / 1e9 < 180
    assert times[0] - T0_NS < 100_000_000
    topics = Counter(topic for topic, _, _, _ in messages(SAMPLES / MCAP))
    assert topics == {
        "/diagnostics": 604,
        "/navigate_to_pose/_action/status": 9,
        "/follow_path/_action/status": 13,
        "/rosout": 25,
    }


# -- helpers for (b) to (d) ----------------------------------------------------------------------


@cache
def report_text(sample: str, configs: tuple[str, ...]) -> str:
    """The JSON report of one sample under one layering of rules (from the repository root)."""
    return dumps(replay([SAMPLES / sample], [ROOT / c for c in configs]))


def report(sample: str, configs: tuple[str, ...]) -> Report:
    loaded: Report = json.loads(report_text(sample, configs))
    return loaded


def sec(t_ns: int) -> float:
    """Bag time as seconds after the samples' T0, to the 10 ms."""
    return round((t_ns - T0_NS) / 1e9, 2)


def statuses(rep: Report) -> dict[str, str]:
    return {f["fault_code"]: f["status"] for f in rep["faults"]}


def fault(rep: Report, code: str) -> Report:
    found: Report = next(f for f in rep["faults"] if f["fault_code"] == code)
    return found


def muted(rep: Report) -> dict[str, tuple[str, str, int]]:
    return {
        m["fault_code"]: (m["root_cause_code"], m["rule_id"], m["delay_ms"])
        for m in rep["muted_faults"]
    }


def transitions(rep: Report, code: str) -> list[tuple[float, str | None, str]]:
    return [
        (sec(t["t_ns"]), t["from_status"], t["to_status"])
        for t in rep["transitions"]
        if t["fault_code"] == code
    ]


def events_of(rep: Report, code: str) -> list[str]:
    return [e["event_type"] for e in rep["events"] if e["fault"]["fault_code"] == code]


def failed_reports(rep: Report, code: str) -> list[float]:
    return [
        sec(r["t_ns"])
        for r in rep["reports"]
        if r["fault_code"] == code and r["event_type"] == "FAILED"
    ]


# -- (b) the Nav2 mission under each rules config ------------------------------------------------

DIAGNOSTIC_VERDICTS = {
    "CAMERA_FRAME_RATE": "HEALED",
    "IMU_DATA_RATE": "HEALED",
    "LIDAR_SCAN_RATE": "HEALED",
    "LOCALIZATION_POSE_CONFIDENCE": "HEALED",
    "MOTOR_LEFT_COMM_LINK": "HEALED",
    "MOTOR_LEFT_OVERHEAT": "HEALED",
    "WHEEL_ODOMETRY_SLIP": "HEALED",
    "WIFI_SIGNAL_STRENGTH": "CONFIRMED",
}
LOG_VERDICTS = {
    "LOG_BT_NAVIGATOR_4fc83613": "CONFIRMED",  # "Goal failed"
    "LOG_CONTROLLER_SERVER_e9897eb8": "CONFIRMED",  # "Failed to make progress"
    "LOG_MOTOR_DRIVER_4cf527a5": "CONFIRMED",  # "Lost CAN heartbeat ..."
    "LOG_MOTOR_DRIVER_e76c6116": "CONFIRMED",  # FATAL "... thermal shutdown ..."
}
SYMPTOMS = {
    "ACTION_NAVIGATE_TO_POSE_ABORTED": ("MOTOR_LEFT_OVERHEAT", "motor_overheat_cascade", 4157),
    "MOTOR_LEFT_COMM_LINK": ("MOTOR_LEFT_OVERHEAT", "motor_overheat_cascade", 3999),
    "WHEEL_ODOMETRY_SLIP": ("MOTOR_LEFT_OVERHEAT", "motor_overheat_cascade", 3496),
}


def test_nav2_rules_without_bridges_file() -> None:
    rep = report(MCAP, NAV2)
    assert statuses(rep) == {
        **DIAGNOSTIC_VERDICTS,
        # No action_sources: the source is the action name, which no entity threshold names,
        # so the one PASSED of a recovery leaves the counter at 0 and the fault CONFIRMED.
        "ACTION_FOLLOW_PATH_ABORTED": "CONFIRMED",
        "ACTION_NAVIGATE_TO_POSE_ABORTED": "CONFIRMED",
    }
    assert fault(rep, "ACTION_NAVIGATE_TO_POSE_ABORTED")["reporting_sources"] == [
        "/navigate_to_pose"
    ]
    assert fault(rep, "ACTION_FOLLOW_PATH_ABORTED")["reporting_sources"] == ["/follow_path"]
    assert sec(fault(rep, "ACTION_NAVIGATE_TO_POSE_ABORTED")["last_passed_ns"]) == 146.5
    assert muted(rep) == SYMPTOMS
    assert rep["summary"]["messages_read"] == 626  # /rosout is not read: no log bridge
    assert rep["warnings"] == []
    assert rep["parity"] is None


def test_nav2_rules_with_bridges_file() -> None:
    rep = report(MCAP, NAV2_BRIDGES)
    assert statuses(rep) == {
        **DIAGNOSTIC_VERDICTS,
        **LOG_VERDICTS,
        # Reported as the action servers, whose entity thresholds heal on the one PASSED.
        "ACTION_FOLLOW_PATH_ABORTED": "HEALED",
        "ACTION_NAVIGATE_TO_POSE_ABORTED": "HEALED",
    }
    assert rep["summary"]["faults_by_status"] == {
        "PREFAILED": 0,
        "PREPASSED": 0,
        "CONFIRMED": 5,
        "HEALED": 9,
        "CLEARED": 0,
    }
    sources = {f["fault_code"]: f["reporting_sources"] for f in rep["faults"]}
    assert sources["ACTION_NAVIGATE_TO_POSE_ABORTED"] == ["/bt_navigator"]
    assert sources["ACTION_FOLLOW_PATH_ABORTED"] == ["/controller_server"]
    assert sources["LOG_BT_NAVIGATOR_4fc83613"] == ["/bt_navigator"]
    assert sources["LOG_CONTROLLER_SERVER_e9897eb8"] == ["/controller_server"]
    assert sources["LOG_MOTOR_DRIVER_e76c6116"] == ["/motor_driver"]
    assert sources["MOTOR_LEFT_OVERHEAT"] == ["/diagnostic_bridge"]
    assert fault(rep, "LOG_MOTOR_DRIVER_e76c6116")["severity"] == 3  # FATAL is CRITICAL
    assert transitions(rep, "ACTION_FOLLOW_PATH_ABORTED") == [
        (26.4, None, "CONFIRMED"),
        (52.45, "CONFIRMED", "HEALED"),
    ]
    assert transitions(rep, "ACTION_NAVIGATE_TO_POSE_ABORTED") == [
        (81.21, None, "CONFIRMED"),
        (146.5, "CONFIRMED", "HEALED"),
    ]
    # Muted when it confirmed; its heal is a PASSED, which correlation never sees: published.
    assert events_of(rep, "ACTION_NAVIGATE_TO_POSE_ABORTED") == ["fault_cleared"]
    assert muted(rep) == SYMPTOMS
    # The log bridge's cooldown: the second "Failed to make progress" (2.5 s later) is dropped;
    # WARN lines are under the severity floor of 40 (no LOG_AMCL_* fault).
    assert failed_reports(rep, "LOG_CONTROLLER_SERVER_e9897eb8") == [26.39]
    assert not [code for code in statuses(rep) if code.startswith("LOG_AMCL")]
    assert rep["warnings"] == []


@pytest.mark.parametrize("configs", [NAV2, NAV2_BRIDGES], ids=["nav2", "nav2+bridges"])
def test_nav2_correlation_mutes_the_overheat_symptoms_and_clusters_the_sensors(
    configs: tuple[str, ...],
) -> None:
    rep = report(MCAP, configs)
    assert transitions(rep, "MOTOR_LEFT_OVERHEAT") == [
        (77.05, None, "CONFIRMED"),
        (101.05, "CONFIRMED", "HEALED"),
    ]
    assert events_of(rep, "MOTOR_LEFT_OVERHEAT")[:1] == ["fault_confirmed"]
    for symptom in SYMPTOMS:
        # Confirmed, but its confirmation (and every FAILED update) withheld.
        assert "fault_confirmed" not in events_of(rep, symptom)
        assert fault(rep, symptom)["muted"] is True
        assert fault(rep, symptom)["root_cause_code"] == "MOTOR_LEFT_OVERHEAT"
    assert transitions(rep, "MOTOR_LEFT_COMM_LINK")[0] == (79.05, None, "CONFIRMED")
    assert rep["clusters"] == [
        {
            "cluster_id": "sensor_storm_1",
            "rule_id": "sensor_storm",
            "rule_name": "Sensor storm",
            "label": "Sensor storm",
            "representative_code": "LIDAR_SCAN_RATE",
            "representative_severity": "ERROR",
            "fault_codes": ["LIDAR_SCAN_RATE", "CAMERA_FRAME_RATE", "IMU_DATA_RATE"],
            "count": 3,
            "first_at_ns": rep["clusters"][0]["first_at_ns"],
            "last_at_ns": rep["clusters"][0]["first_at_ns"],
        }
    ]
    assert sec(rep["clusters"][0]["first_at_ns"]) == 114.3
    for code in ("LIDAR_SCAN_RATE", "CAMERA_FRAME_RATE", "IMU_DATA_RATE"):
        assert fault(rep, code)["cluster_ids"] == ["sensor_storm_1"]
    # Only the representative's confirmation is published.
    assert events_of(rep, "LIDAR_SCAN_RATE")[0] == "fault_confirmed"
    assert "fault_confirmed" not in events_of(rep, "CAMERA_FRAME_RATE")
    assert "fault_confirmed" not in events_of(rep, "IMU_DATA_RATE")


@pytest.mark.parametrize("configs", list(CONFIGS.values()), ids=list(CONFIGS))
def test_diagnostics_local_filter_debounce_and_healing(configs: tuple[str, ...]) -> None:
    rep = report(MCAP, configs)
    # The WiFi WARNs before 60 s never come three within 10 s: the local filter holds them all.
    wifi = failed_reports(rep, "WIFI_SIGNAL_STRENGTH")
    assert wifi[:6] == [65.8, 66.8, 108.8, 110.8, 112.8, 114.8]
    assert wifi[6] == 133.8
    assert transitions(rep, "WIFI_SIGNAL_STRENGTH") == [
        (65.8, None, "CONFIRMED"),
        (70.8, "CONFIRMED", "HEALED"),
        (136.8, "HEALED", "CONFIRMED"),
    ]
    # Flapping after it healed moves the counter 3 -> 2 -> 3 ...: the HEALED latch holds, and
    # the near misses show how close each FAILED got (the dead zone needs four to reconfirm).
    near = [
        (sec(n["t_ns"]), n["debounce_counter"], n["resulting_status"])
        for n in rep["near_misses"]
        if n["fault_code"] == "WIFI_SIGNAL_STRENGTH"
    ]
    assert near == [
        (108.8, 2, "HEALED"),
        (110.8, 2, "HEALED"),
        (112.8, 2, "HEALED"),
        (114.8, 2, "HEALED"),
        (133.8, 2, "HEALED"),
        (134.8, 1, "HEALED"),
        (135.8, 0, "HEALED"),
    ]
    assert events_of(rep, "WIFI_SIGNAL_STRENGTH").count("fault_confirmed") == 2
    # The localization ERROR bypasses the filter, then four OKs heal it (threshold 3).
    assert transitions(rep, "LOCALIZATION_POSE_CONFIDENCE") == [
        (23.55, None, "CONFIRMED"),
        (32.55, "CONFIRMED", "HEALED"),
    ]
    assert events_of(rep, "LOCALIZATION_POSE_CONFIDENCE")[-1] == "fault_cleared"
    assert fault(rep, "LOCALIZATION_POSE_CONFIDENCE")["description"] == (
        "pose covariance 2.41 m^2 above 0.50 m^2, diverged"
    )
    # The motor's WARNs before the ERROR stay under the filter; the ERROR gets through.
    assert failed_reports(rep, "MOTOR_LEFT_OVERHEAT")[0] == 77.05
    assert fault(rep, "MOTOR_LEFT_OVERHEAT")["severity"] == 2
    # The canceled FollowPath goal is no fault (canceled_is_fault false everywhere).
    assert "ACTION_FOLLOW_PATH_CANCELED" not in statuses(rep)


def test_bringup_rules() -> None:
    rep = report(MCAP, BRINGUP)
    # Same verdicts as the Nav2 rules, but nothing correlated: every confirmation is published.
    assert statuses(rep) == {
        **DIAGNOSTIC_VERDICTS,
        "ACTION_FOLLOW_PATH_ABORTED": "CONFIRMED",
        "ACTION_NAVIGATE_TO_POSE_ABORTED": "CONFIRMED",
    }
    assert rep["muted_faults"] == []
    assert rep["clusters"] == []
    for code in (*SYMPTOMS, "CAMERA_FRAME_RATE", "IMU_DATA_RATE"):
        assert events_of(rep, code)[0] == "fault_confirmed"
    assert rep["summary"]["events"] == {
        "fault_confirmed": 11,
        "fault_updated": 69,
        "fault_cleared": 8,
    }
    assert report(MCAP, NAV2)["summary"]["events"] == {
        "fault_confirmed": 6,
        "fault_updated": 62,
        "fault_cleared": 8,
    }


def test_bringup_settings_do_not_heal_a_recovered_action() -> None:
    """Upstream's bringup says an action SUCCEEDED heals its fault; threshold 3 prevents it."""
    rep = report(MCAP, BRINGUP_BRIDGES)
    assert statuses(rep) == {
        **DIAGNOSTIC_VERDICTS,
        **LOG_VERDICTS,
        "ACTION_FOLLOW_PATH_ABORTED": "CONFIRMED",
        "ACTION_NAVIGATE_TO_POSE_ABORTED": "CONFIRMED",
    }
    navigate = fault(rep, "ACTION_NAVIGATE_TO_POSE_ABORTED")
    assert navigate["reporting_sources"] == ["/bt_navigator"]
    assert sec(navigate["last_passed_ns"]) == 146.5
    assert events_of(rep, "ACTION_NAVIGATE_TO_POSE_ABORTED") == [
        "fault_confirmed",
        "fault_updated",  # the PASSED of the recovery, counter -1 -> 0, still CONFIRMED
    ]


def test_default_log_floor_and_canceled_goals_as_faults(tmp_path: Path) -> None:
    """Two variations layered on the ready rules: WARN logs in, CANCELED goals as faults."""
    floor = tmp_path / "floor.yaml"
    floor.write_text("log_bridge:\n  ros__parameters:\n    severity_floor: 30\n")
    cancel = tmp_path / "cancel.yaml"
    cancel.write_text("action_status_bridge:\n  ros__parameters:\n    canceled_is_fault: true\n")
    configs = [ROOT / c for c in NAV2_BRIDGES]
    rep: Report = json.loads(dumps(replay([SAMPLES / MCAP], [*configs, floor, cancel])))
    # Four AMCL WARNs within 10 s: the third gets through the local filter.
    amcl = fault(rep, "LOG_AMCL_7bb55b53")
    assert (amcl["status"], amcl["severity"], amcl["reporting_sources"]) == (
        "CONFIRMED",
        1,
        ["/amcl"],
    )
    assert failed_reports(rep, "LOG_AMCL_7bb55b53") == [25.61, 26.61]
    # Single WARN lines stay under the filter.
    assert not [c for c in statuses(rep) if c.startswith(("LOG_SENSOR_MONITOR", "LOG_BEHAVIOR"))]
    # The FollowPath goal the navigator canceled is now a symptom of the overheat.
    assert muted(rep)["ACTION_FOLLOW_PATH_CANCELED"] == (
        "MOTOR_LEFT_OVERHEAT",
        "motor_overheat_cascade",
        4127,
    )
    assert transitions(rep, "ACTION_FOLLOW_PATH_CANCELED") == [
        (81.18, None, "CONFIRMED"),
        (146.35, "CONFIRMED", "HEALED"),
    ]


@pytest.mark.parametrize("configs", list(CONFIGS.values()), ids=list(CONFIGS))
def test_mcap_and_sqlite3_reports_are_identical_but_for_inputs(configs: tuple[str, ...]) -> None:
    mcap, sqlite3 = report(MCAP, configs), report(SQLITE3, configs)
    assert mcap["warnings"] == []  # every ready config loads cleanly

    def rest(rep: Report) -> str:
        return json.dumps({k: v for k, v in rep.items() if k != "inputs"}, indent=2)

    assert rest(mcap) == rest(sqlite3)
    assert [i["storage"] for i in mcap["inputs"]] == ["mcap"]
    assert [i["storage"] for i in sqlite3["inputs"]] == ["sqlite3"]
    for a, b in zip(mcap["inputs"], sqlite3["inputs"], strict=True):
        assert {**a, "path": "", "storage": ""} == {**b, "path": "", "storage": ""}
    assert report_text(MCAP, configs) == report_text(MCAP, configs)  # cached, but also:
    assert dumps(replay([SAMPLES / MCAP], [ROOT / c for c in configs])) == report_text(
        MCAP, configs
    )


# -- (c) recorded service calls: parity with the recorded FaultEvents ----------------------------


def test_service_calls_match_the_recorded_manager() -> None:
    rep = report(SERVICES, NAV2)
    parity = rep["parity"]
    assert parity["verdict"] == "match"
    assert (parity["recorded_events"], parity["replayed_events"], parity["matched"]) == (9, 9, 9)
    assert parity["differences"] == parity["missing"] == parity["extra"] == []
    assert parity["max_abs_time_offset_ns"] == 420_000  # applied at REQUEST_SENT, recorded later
    # Three recorded copies of each call, applied once.
    assert len(rep["reports"]) == 12 and len(rep["clears"]) == 2
    rejected = [r for r in rep["reports"] if not r["accepted"]]
    assert [(r["fault_code"], r["origin"]) for r in rejected] == [("motor temp", "report_fault")]
    assert [
        (c["fault_code"], c["success"], c["message"], c["auto_cleared_codes"])
        for c in rep["clears"]
    ] == [
        (
            "MOTOR_OVERHEAT",
            True,
            "Fault cleared: MOTOR_OVERHEAT (auto-cleared 2 symptoms)",
            ["MOTOR_LEFT_COMM_TIMEOUT", "WHEEL_SLIP_DETECTED"],
        ),
        ("LIDAR_TIMEOUT", False, "Fault not found: LIDAR_TIMEOUT", []),
    ]
    assert statuses(rep) == {
        "BATTERY_LOW": "HEALED",
        "MOTOR_LEFT_COMM_TIMEOUT": "CONFIRMED",
        "MOTOR_OVERHEAT": "CONFIRMED",
        "WHEEL_SLIP_DETECTED": "CLEARED",
    }
    assert fault(rep, "MOTOR_OVERHEAT")["occurrence_count"] == 2
    assert fault(rep, "MOTOR_LEFT_COMM_TIMEOUT")["occurrence_count"] == 2
    assert muted(rep) == {
        "MOTOR_LEFT_COMM_TIMEOUT": ("MOTOR_OVERHEAT", "motor_overheat_cascade", 600),
    }
    assert report(SERVICES, NAV2_BRIDGES)["parity"]["verdict"] == "match"


def test_service_calls_differ_under_other_settings() -> None:
    """Parity notices a replay configured unlike the recorded manager."""
    parity = report(SERVICES, BRINGUP)["parity"]
    assert parity["verdict"] == "differ"
    assert [(e["fault_code"], e["event_type"]) for e in parity["extra"]] == [
        ("MOTOR_LEFT_COMM_TIMEOUT", "fault_confirmed"),
        ("MOTOR_LEFT_COMM_TIMEOUT", "fault_updated"),
        ("WHEEL_SLIP_DETECTED", "fault_confirmed"),
    ]
    assert [d["differences"] for d in parity["differences"]] == [
        {
            "auto_cleared_codes": {
                "recorded": ["MOTOR_LEFT_COMM_TIMEOUT", "WHEEL_SLIP_DETECTED"],
                "replayed": [],
            }
        }
    ]
    assert parity["missing"] == []


# -- (d) the README's first command ---------------------------------------------------------------


def readme_first_command() -> list[str]:
    """The arguments of the first ``medkit-replay analyze`` in README.md (after ``&&``)."""
    for line in (ROOT / "README.md").read_text(encoding="utf-8").splitlines():
        if "medkit-replay analyze" in line:
            words = shlex.split(line[line.index("medkit-replay analyze") :])
            return words[1:]
    raise AssertionError("README.md has no medkit-replay analyze command")


def test_readme_first_command_tells_the_mission_story(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    argv = readme_first_command()
    assert argv == [
        "analyze",
        "sample_bags/nav2_mission_mcap",
        "--config",
        "rules/nav2/fault_manager.yaml",
        "--config",
        "rules/nav2/bridges.yaml",
    ]
    monkeypatch.chdir(ROOT)
    status = main(argv)
    out, err = capsys.readouterr()
    assert (status, err) == (0, "")
    # Only what any layout of the summary shows.
    flat = " ".join(out.split())
    assert "CONFIRMED 5, HEALED 9" in flat
    assert len(out.splitlines()) <= 60 and "--all prints everything" in flat
    assert main([*argv, "--all"]) == 0
    whole, _ = capsys.readouterr()
    assert " ".join(whole.split()).count("muted by MOTOR_LEFT_OVERHEAT") == len(SYMPTOMS)
    for shown in (
        "MOTOR_LEFT_OVERHEAT",
        "WIFI_SIGNAL_STRENGTH",
        "LOG_MOTOR_DRIVER_e76c6116",
        "LIDAR_SCAN_RATE",
        "CAMERA_FRAME_RATE",
        "sensor_storm_1",
    ):
        assert shown in whole
    assert "WARNING" not in out


def test_readme_keeps_the_example_script() -> None:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert text.index("sample_bags/nav2_mission_mcap") < text.index("examples/nav2_mission.jsonl")
