"""Recordings through the whole pipeline: bags in tmp_path → inputs → bridges → manager → report.

Each test writes its own rosbag2 recording (MCAP and sqlite3 where storage could matter) and checks
concrete report contents (SEMANTICS.md §2 to §4, cli-and-report.md §3, bridges.md §1 to §3).
"""

from __future__ import annotations

import hashlib
import json
import stat
import subprocess
import sys
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from medkit_replay.cli import main
from tests.inputs.builders import as_wal, log, storage_file, string_msg, truncated, write_bag
from tests.pipeline_support import (
    ABORTED,
    CANCELED,
    ERROR,
    EXECUTING,
    MS,
    OK,
    REPORT_KEYS,
    REPORT_TOPIC,
    REQUEST_RECEIVED,
    RESPONSE_SENT,
    SCHEMA,
    SEC,
    STALE,
    SUCCEEDED,
    TRANSITION_KEYS,
    WARN,
    bag,
    config,
    contract,
    diagnostics,
    events,
    fault,
    fault_event,
    goals,
    report_call,
    reports,
    run,
    run_cli,
    status,
    warnings_with,
)

if TYPE_CHECKING:
    from collections.abc import Iterator

    from tests.inputs.builders import Rec, Storage

FIXTURES = Path(__file__).parent / "fixtures" / "rosbag2"
EMPTY = "no topic the replay reads was found"


@pytest.fixture(params=["mcap", "sqlite3"])
def storage(request: pytest.FixtureRequest) -> Storage:
    """Both storage plugins rosbag2 writes."""
    value: Storage = request.param
    return value


# --- diagnostics → diagnostic bridge → manager --------------------------------------------------


def test_warn_needs_three_reports_within_ten_seconds(tmp_path: Path, storage: Storage) -> None:
    times = [1, 2, 12.5, 13, 14, 15]  # 1 and 2 have left the 10 s window by 12.5
    recs = [diagnostics(int(t * SEC), status("motor temp", WARN, "warm")) for t in times]
    report = run([bag(tmp_path, "bag", recs, storage)])
    assert reports(report, "t_ns", "origin", "topic", "fault_code", "event_type", "severity") == [
        (14 * SEC, "diagnostic_bridge", "/diagnostics", "MOTOR_TEMP", "FAILED", 1),
        (15 * SEC, "diagnostic_bridge", "/diagnostics", "MOTOR_TEMP", "FAILED", 1),
    ]
    assert {r["source_id"] for r in report["reports"]} == {"/diagnostic_bridge"}
    assert {r["description"] for r in report["reports"]} == {"warm"}
    assert events(report) == [
        (14 * SEC, "fault_confirmed", "MOTOR_TEMP", "CONFIRMED"),
        (15 * SEC, "fault_updated", "MOTOR_TEMP", "CONFIRMED"),
    ]
    motor = fault(report, "MOTOR_TEMP")
    assert (motor["severity"], motor["first_occurred_ns"], motor["last_occurred_ns"]) == (
        1,
        14 * SEC,
        15 * SEC,
    )
    assert report["summary"]["messages_read"] == 6
    assert report["summary"]["reports"] == 2


def test_warn_window_edge_is_inclusive(tmp_path: Path, storage: Storage) -> None:
    # Exactly 10 s old still counts: 0, 5 and 10 s are three reports within the window.
    recs = [diagnostics(t * SEC, status("fan", WARN, "slow")) for t in (0, 5, 10)]
    report = run([bag(tmp_path, "bag", recs, storage)])
    assert reports(report, "t_ns", "fault_code", "severity") == [(10 * SEC, "FAN", 1)]


def test_error_bypasses_the_local_filter(tmp_path: Path, storage: Storage) -> None:
    recs = [diagnostics(2 * SEC, status("/robot/sensor", ERROR, "no data"))]
    report = run([bag(tmp_path, "bag", recs, storage)])
    assert [contract(r, REPORT_KEYS) for r in report["reports"]] == [
        {
            "t_ns": 2 * SEC,
            "origin": "diagnostic_bridge",
            "topic": "/diagnostics",
            "fault_code": "ROBOT_SENSOR",
            "event_type": "FAILED",
            "severity": 2,
            "description": "no data",
            "source_id": "/diagnostic_bridge",
            "accepted": True,
            "reject_reason": None,
        }
    ]
    assert events(report) == [(2 * SEC, "fault_confirmed", "ROBOT_SENSOR", "CONFIRMED")]
    assert [contract(t, TRANSITION_KEYS) for t in report["transitions"]] == [
        {
            "t_ns": 2 * SEC,
            "fault_code": "ROBOT_SENSOR",
            "from_status": None,
            "to_status": "CONFIRMED",
            "cause": "report",
            "source_id": "/diagnostic_bridge",
        }
    ]


def test_ok_sends_passed_after_three_in_the_window(tmp_path: Path, storage: Storage) -> None:
    recs = [diagnostics(1 * SEC, status("battery", ERROR, "low"))]
    recs += [diagnostics(t * SEC, status("battery", OK, "fine")) for t in (2, 3, 4)]
    report = run([bag(tmp_path, "bag", recs, storage)])
    assert reports(report, "t_ns", "fault_code", "event_type", "severity", "description") == [
        (1 * SEC, "BATTERY", "FAILED", 2, "low"),
        (4 * SEC, "BATTERY", "PASSED", 0, ""),
    ]
    battery = fault(report, "BATTERY")
    # healing is off by default: a CONFIRMED fault stays latched; the PASSED is still recorded
    assert (battery["status"], battery["last_passed_ns"]) == ("CONFIRMED", 4 * SEC)
    assert events(report) == [
        (1 * SEC, "fault_confirmed", "BATTERY", "CONFIRMED"),
        (4 * SEC, "fault_updated", "BATTERY", "CONFIRMED"),
    ]


def test_ok_heals_with_healing_enabled(tmp_path: Path, storage: Storage) -> None:
    recs = [diagnostics(1 * SEC, status("battery", ERROR, "low"))]
    recs += [diagnostics(t * SEC, status("battery", OK, "")) for t in (2, 3, 4, 5)]
    params = config(
        tmp_path,
        "fault_manager:\n  ros__parameters: {healing_enabled: true, healing_threshold: 1}\n",
    )
    report = run([bag(tmp_path, "bag", recs, storage)], [params])
    assert reports(report, "t_ns", "event_type") == [
        (1 * SEC, "FAILED"),
        (4 * SEC, "PASSED"),
        (5 * SEC, "PASSED"),
    ]
    assert events(report)[-1] == (5 * SEC, "fault_cleared", "BATTERY", "HEALED")
    assert [(t["t_ns"], t["from_status"], t["to_status"]) for t in report["transitions"]] == [
        (1 * SEC, None, "CONFIRMED"),
        (5 * SEC, "CONFIRMED", "HEALED"),
    ]


def test_stale_is_critical_and_confirms_at_once(tmp_path: Path, storage: Storage) -> None:
    params = config(tmp_path, "fault_manager:\n  ros__parameters: {confirmation_threshold: -3}\n")
    recs = [diagnostics(SEC, status("lidar", STALE, "no update"), status("imu", ERROR, "drift"))]
    report = run([bag(tmp_path, "bag", recs, storage)], [params])
    assert reports(report, "t_ns", "fault_code", "severity") == [
        (SEC, "LIDAR", 3),  # STALE → CRITICAL (code wins over upstream's docs)
        (SEC, "IMU", 2),
    ]
    assert fault(report, "LIDAR")["status"] == "CONFIRMED"
    assert fault(report, "IMU")["status"] == "PREFAILED"  # -1 of -3
    assert events(report) == [(SEC, "fault_confirmed", "LIDAR", "CONFIRMED")]


def test_statuses_of_one_array_are_reported_in_order(tmp_path: Path, storage: Storage) -> None:
    recs = [
        diagnostics(
            SEC,
            status("motor: Status", ERROR, "a"),
            status("ok thing", OK, ""),
            status("Zeta", ERROR, "b"),
            status("alpha", ERROR, "c"),
        )
    ]
    report = run([bag(tmp_path, "bag", recs, storage)])
    assert reports(report, "fault_code") == [("MOTOR_STATUS",), ("ZETA",), ("ALPHA",)]
    assert [f["fault_code"] for f in report["faults"]] == ["ALPHA", "MOTOR_STATUS", "ZETA"]


def test_custom_diagnostics_topic(tmp_path: Path, storage: Storage) -> None:
    recs = [
        diagnostics(1 * SEC, status("motor", ERROR, "hot"), topic="/robot/diagnostics"),
        diagnostics(2 * SEC, status("battery", ERROR, "low")),  # the default topic
    ]
    recording = bag(tmp_path, "bag", recs, storage)
    params = config(
        tmp_path,
        "diagnostic_bridge:\n  ros__parameters: {diagnostics_topic: /robot/diagnostics}\n",
    )
    custom = run([recording], [params])
    assert reports(custom, "t_ns", "origin", "topic", "fault_code") == [
        (1 * SEC, "diagnostic_bridge", "/robot/diagnostics", "MOTOR")
    ]
    roles = {t["topic"]: t["role"] for t in custom["inputs"][0]["topics"]}
    assert roles == {"/robot/diagnostics": "diagnostics", "/diagnostics": None}
    assert custom["summary"]["messages_read"] == 1

    default = run([recording])
    assert reports(default, "t_ns", "topic", "fault_code") == [(2 * SEC, "/diagnostics", "BATTERY")]


def test_timers_tick_on_bag_time_from_the_first_message_read(
    tmp_path: Path, storage: Storage
) -> None:
    recs = [
        string_msg(0, "/chatter"),  # not read: the replay's clock starts at 0.5 s, not 0
        diagnostics(SEC // 2, status("fan", OK, "")),
        diagnostics(1 * SEC, status("motor", ERROR, "hot")),
        diagnostics(4 * SEC, status("fan", OK, "")),
    ]
    params = config(
        tmp_path,
        "fault_manager:\n  ros__parameters:\n"
        "    {confirmation_threshold: -3, auto_confirm_after_sec: 2.0}\n",
    )
    report = run([bag(tmp_path, "bag", recs, storage)], [params])
    # ticks at 1.5, 2.5, 3.5 s: the first at which the 1 s report is at least 2 s old is 3.5 s
    assert [
        (t["t_ns"], t["fault_code"], t["from_status"], t["to_status"], t["cause"], t["source_id"])
        for t in report["transitions"]
    ] == [
        (1 * SEC, "MOTOR", None, "PREFAILED", "report", "/diagnostic_bridge"),
        (3 * SEC + SEC // 2, "MOTOR", "PREFAILED", "CONFIRMED", "auto_confirm", None),
    ]
    assert report["events"] == []  # upstream publishes nothing for a time-based confirmation
    assert report["summary"]["start_ns"] == SEC // 2


# --- action status → action bridge --------------------------------------------------------------

NAV = "/navigate_to_pose"
NAV_ABORTED = "ACTION_NAVIGATE_TO_POSE_ABORTED"


def test_action_aborted_raises_and_succeeded_heals(tmp_path: Path, storage: Storage) -> None:
    recs = [
        goals(1 * SEC, NAV, SUCCEEDED),  # never reported counts as healthy: heals nothing
        goals(2 * SEC, NAV, EXECUTING, ABORTED),
        goals(3 * SEC, NAV, ABORTED),  # still failed: no second report
        goals(4 * SEC, NAV, SUCCEEDED),
        goals(5 * SEC, NAV, EXECUTING),  # no verdict
        goals(6 * SEC, NAV, ABORTED),
    ]
    report = run([bag(tmp_path, "bag", recs, storage)])
    rows = reports(report, "t_ns", "origin", "topic", "fault_code", "event_type", "source_id")
    topic = f"{NAV}/_action/status"
    assert rows == [
        (2 * SEC, "action_status_bridge", topic, NAV_ABORTED, "FAILED", NAV),
        (4 * SEC, "action_status_bridge", topic, NAV_ABORTED, "PASSED", NAV),
        (6 * SEC, "action_status_bridge", topic, NAV_ABORTED, "FAILED", NAV),
    ]
    first = report["reports"][0]
    assert (first["severity"], first["description"]) == (2, "Action /navigate_to_pose aborted")
    nav = fault(report, NAV_ABORTED)
    assert (nav["status"], nav["reporting_sources"], nav["last_passed_ns"]) == (
        "CONFIRMED",
        [NAV],
        4 * SEC,
    )


def test_canceled_goals(tmp_path: Path, storage: Storage) -> None:
    recs = [
        goals(1 * SEC, NAV, ABORTED),
        goals(2 * SEC, NAV, CANCELED),  # a cancel is a terminal, healthy outcome by default
        goals(3 * SEC, NAV, CANCELED),
        goals(4 * SEC, NAV, CANCELED, ABORTED),
    ]
    recording = bag(tmp_path, "bag", recs, storage)
    default = run([recording])
    assert reports(default, "t_ns", "fault_code", "event_type") == [
        (1 * SEC, NAV_ABORTED, "FAILED"),
        (2 * SEC, NAV_ABORTED, "PASSED"),
        (4 * SEC, NAV_ABORTED, "FAILED"),
    ]
    params = config(
        tmp_path, "action_status_bridge:\n  ros__parameters: {canceled_is_fault: true}\n"
    )
    as_fault = run([recording], [params])
    canceled = "ACTION_NAVIGATE_TO_POSE_CANCELED"
    # 1 s fails; a purely canceled array stays failed (no transition); ABORTED dominates a mix
    assert reports(as_fault, "t_ns", "fault_code", "event_type") == [
        (1 * SEC, NAV_ABORTED, "FAILED")
    ]
    recs = [goals(1 * SEC, NAV, SUCCEEDED), goals(2 * SEC, NAV, CANCELED)]
    recs += [goals(3 * SEC, NAV, SUCCEEDED)]
    cancel_only = run([bag(tmp_path, "bag2", recs, storage)], [params])
    assert reports(cancel_only, "t_ns", "fault_code", "event_type", "description") == [
        (2 * SEC, canceled, "FAILED", "Action /navigate_to_pose canceled"),
        (3 * SEC, NAV_ABORTED, "PASSED", ""),  # a heal sends PASSED for both codes
        (3 * SEC, canceled, "PASSED", ""),
    ]


def test_action_sources_set_the_source_id(tmp_path: Path, storage: Storage) -> None:
    recs = [goals(1 * SEC, NAV, ABORTED), goals(2 * SEC, "/follow_path", ABORTED)]
    params = config(
        tmp_path,
        "medkit_replay:\n  ros__parameters:\n"
        "    action_sources: {/navigate_to_pose: /bt_navigator}\n",
    )
    report = run([bag(tmp_path, "bag", recs, storage)], [params])
    assert reports(report, "fault_code", "source_id") == [
        (NAV_ABORTED, "/bt_navigator"),
        ("ACTION_FOLLOW_PATH_ABORTED", "/follow_path"),  # unmapped: the action name
    ]
    assert fault(report, NAV_ABORTED)["reporting_sources"] == ["/bt_navigator"]


# --- /rosout → log bridge -----------------------------------------------------------------------


def rosout_recording(tmp_path: Path, storage: Storage) -> Path:
    recs = [
        log(1 * SEC, 40, "Goal failed", "bt_navigator"),
        log(2 * SEC, 40, "Goal failed", "bt_navigator"),  # ERROR cooldown (5 s): suppressed
        log(3 * SEC, 20, "just info", "bt_navigator"),  # INFO never passes
        log(4 * SEC, 50, "oops 42", "ctrl"),
    ]
    return bag(tmp_path, "bag", recs, storage)


def test_rosout_is_ignored_without_the_log_bridge(tmp_path: Path, storage: Storage) -> None:
    report = run([rosout_recording(tmp_path, storage)])
    assert report["reports"] == []
    assert report["summary"]["messages_read"] == 0
    assert [t["role"] for t in report["inputs"][0]["topics"]] == [None]
    assert len(warnings_with(report, EMPTY)) == 1


@pytest.mark.parametrize(
    "params",
    [
        "log_bridge:\n  ros__parameters: {}\n",
        "log_bridge:\n  ros__parameters:\n    severity_floor: 30\n",
        "medkit_replay:\n  ros__parameters: {enable_log_bridge: true}\n",
    ],
    ids=["empty-section", "section", "option"],
)
def test_rosout_through_the_log_bridge(tmp_path: Path, storage: Storage, params: str) -> None:
    report = run([rosout_recording(tmp_path, storage)], [config(tmp_path, params)])
    rows = reports(report, "t_ns", "origin", "topic", "fault_code", "severity", "source_id")
    assert rows == [
        (1 * SEC, "log_bridge", "/rosout", "LOG_BT_NAVIGATOR_4fc83613", 2, "/bt_navigator"),
        (4 * SEC, "log_bridge", "/rosout", "LOG_CTRL_0bf0b26e", 3, "/ctrl"),
    ]
    assert report["reports"][1]["description"] == "oops 42"
    assert report["summary"]["messages_read"] == 4
    assert warnings_with(report, EMPTY) == []


def test_custom_rosout_topic(tmp_path: Path, storage: Storage) -> None:
    recs = [
        replace(log(1 * SEC, 40, "Goal failed", "bt_navigator"), topic="/robot/rosout"),
        log(2 * SEC, 40, "oops 42", "ctrl"),  # the default topic: nobody subscribes to it
    ]
    params = config(tmp_path, "log_bridge:\n  ros__parameters: {rosout_topic: /robot/rosout}\n")
    report = run([bag(tmp_path, "bag", recs, storage)], [params])
    assert reports(report, "t_ns", "origin", "topic", "fault_code") == [
        (1 * SEC, "log_bridge", "/robot/rosout", "LOG_BT_NAVIGATOR_4fc83613")
    ]
    # As for a custom diagnostics topic: the subscribed topic is read in its role, the default
    # one is not read at all.
    roles = {t["topic"]: t["role"] for t in report["inputs"][0]["topics"]}
    assert roles == {"/robot/rosout": "rosout", "/rosout": None}
    assert report["summary"]["messages_read"] == 1


def test_log_bridge_can_be_turned_off_explicitly(tmp_path: Path, storage: Storage) -> None:
    params = config(tmp_path, "medkit_replay:\n  ros__parameters: {enable_log_bridge: false}\n")
    report = run([rosout_recording(tmp_path, storage)], [params])
    assert report["reports"] == []


# --- several inputs: one recording --------------------------------------------------------------


def named_errors(t_ns: int, *names: str) -> Rec:
    return diagnostics(t_ns, *(status(n, ERROR, n) for n in names))


def test_two_bags_merge_by_time_then_input_then_position(tmp_path: Path, storage: Storage) -> None:
    first = bag(
        tmp_path,
        "first",
        [named_errors(1 * SEC, "a1"), named_errors(1 * SEC, "a2"), named_errors(3 * SEC, "a3")],
        storage,
    )
    second = bag(
        tmp_path,
        "second",
        [named_errors(1 * SEC, "b1"), named_errors(2 * SEC, "b2"), named_errors(3 * SEC, "b3")],
        "mcap" if storage == "sqlite3" else "sqlite3",  # mixed storages in one recording
    )
    forward = run([first, second])
    assert reports(forward, "t_ns", "fault_code") == [
        (1 * SEC, "A1"),
        (1 * SEC, "A2"),
        (1 * SEC, "B1"),
        (2 * SEC, "B2"),
        (3 * SEC, "A3"),
        (3 * SEC, "B3"),
    ]
    backward = run([second, first])
    assert reports(backward, "t_ns", "fault_code") == [
        (1 * SEC, "B1"),
        (1 * SEC, "A1"),
        (1 * SEC, "A2"),
        (2 * SEC, "B2"),
        (3 * SEC, "B3"),
        (3 * SEC, "A3"),
    ]
    assert [i["path"] for i in forward["inputs"]] == [str(first), str(second)]
    assert [i["message_count"] for i in forward["inputs"]] == [3, 3]
    assert forward["summary"]["start_ns"] == 1 * SEC
    assert forward["summary"]["end_ns"] == 3 * SEC


def test_bag_and_script_merge(tmp_path: Path, storage: Storage) -> None:
    recording = bag(
        tmp_path, "bag", [named_errors(1 * SEC, "disk"), named_errors(3 * SEC, "net")], storage
    )
    script = tmp_path / "ops.jsonl"
    lines = [
        {"t_ns": 1 * SEC, "op": "report", "fault_code": "SCRIPTED", "event_type": "FAILED",
         "severity": 1, "source_id": "/tester"},
        {"t_ns": 2 * SEC, "op": "clear", "fault_code": "DISK"},
        {"t_ns": 3 * SEC, "op": "report", "fault_code": "NET", "event_type": "PASSED",
         "source_id": "/tester"},
    ]  # fmt: skip
    script.write_text("# a comment\n" + "\n".join(json.dumps(line) for line in lines) + "\n")
    report = run([recording, script])
    assert reports(report, "t_ns", "origin", "topic", "fault_code", "event_type") == [
        (1 * SEC, "diagnostic_bridge", "/diagnostics", "DISK", "FAILED"),
        (1 * SEC, "script", None, "SCRIPTED", "FAILED"),
        (3 * SEC, "diagnostic_bridge", "/diagnostics", "NET", "FAILED"),
        (3 * SEC, "script", None, "NET", "PASSED"),
    ]
    assert [(c["t_ns"], c["fault_code"], c["success"]) for c in report["clears"]] == [
        (2 * SEC, "DISK", True)
    ]
    assert fault(report, "DISK")["status"] == "CLEARED"
    assert fault(report, "NET")["last_passed_ns"] == 3 * SEC
    assert [i["storage"] for i in report["inputs"]] == [storage, "jsonl"]
    swapped = run([script, recording])
    assert reports(swapped, "t_ns", "fault_code", "event_type")[:2] == [
        (1 * SEC, "SCRIPTED", "FAILED"),
        (1 * SEC, "DISK", "FAILED"),
    ]


# --- the CLI: determinism, read-only inputs, fixtures, damage ----------------------------------


def everything(tmp_path: Path, storage: Storage) -> Path:
    """A recording with every role the replay reads."""
    recs = [
        diagnostics(1 * SEC, status("motor", WARN, "warm"), status("fan", ERROR, "stuck")),
        goals(1 * SEC + 1, NAV, ABORTED),
        diagnostics(2 * SEC, status("motor", WARN, "warm")),
        fault_event(2 * SEC + 5 * MS, "fault_confirmed", "FAN", sources=["/diagnostic_bridge"]),
        diagnostics(3 * SEC, status("motor", WARN, "warm")),
        *report_call(
            [4 * SEC, 4 * SEC + MS], "PUMP", kinds=(REQUEST_RECEIVED, RESPONSE_SENT), severity=1
        ),
        goals(5 * SEC, NAV, SUCCEEDED),
        log(6 * SEC, 40, "Goal failed", "bt_navigator"),
    ]
    return bag(tmp_path, "bag", recs, storage)


def test_json_report_is_byte_identical_across_runs(
    tmp_path: Path, storage: Storage, capsys: pytest.CaptureFixture[str]
) -> None:
    recording = everything(tmp_path, storage)
    params = config(tmp_path, "log_bridge:\n  ros__parameters: {}\n")
    outputs = []
    for name in ("one.json", "two.json"):
        code, report, err = run_cli(
            [str(recording), "--config", str(params)], tmp_path / name, capsys
        )
        assert (code, err) == (0, "")
        assert report is not None
        outputs.append((tmp_path / name).read_bytes())
    assert outputs[0] == outputs[1]
    assert report is not None
    assert report["schema"] == SCHEMA
    assert {r["origin"] for r in report["reports"]} == {
        "diagnostic_bridge",
        "action_status_bridge",
        "report_fault",
        "log_bridge",
    }
    assert report["parity"] is not None


def test_human_summary_on_the_terminal(
    tmp_path: Path, storage: Storage, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["analyze", str(everything(tmp_path, storage))]) == 0
    out, err = capsys.readouterr()
    assert err == "" and "Traceback" not in out
    assert "FAN" in out and "PUMP" in out


def snapshot(root: Path) -> dict[str, tuple[int, str]]:
    """Every file under root with its mode and content hash."""
    return {
        str(p.relative_to(root)): (p.stat().st_mode, hashlib.sha256(p.read_bytes()).hexdigest())
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


@contextmanager
def read_only(root: Path) -> Iterator[None]:
    """Make root and everything under it read-only for the duration."""
    for path in [*root.rglob("*"), root]:
        mode = stat.S_IRUSR | stat.S_IRGRP | stat.S_IROTH
        if path.is_dir():
            mode |= stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH
        path.chmod(mode)
    try:
        yield
    finally:
        for path in [root, *root.rglob("*")]:
            path.chmod(path.stat().st_mode | stat.S_IWUSR)


def test_cli_leaves_a_wal_mode_sqlite_bag_untouched(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    recs = [
        named_errors(1 * SEC, "motor"),
        fault_event(1 * SEC + MS, "fault_confirmed", "MOTOR", sources=["/diagnostic_bridge"]),
        *report_call([2 * SEC, 2 * SEC + MS], "PUMP", kinds=(REQUEST_RECEIVED, RESPONSE_SENT)),
        fault_event(2 * SEC + 2 * MS, "fault_confirmed", "PUMP"),
    ]
    folder = tmp_path / "ro"
    folder.mkdir()
    recording = write_bag(folder / "bag", recs, storage="sqlite3")
    db = storage_file(recording)
    as_wal(db)
    assert db.read_bytes()[18:20] == b"\x02\x02"  # WAL mode in the header
    before = snapshot(folder)
    listing = sorted(p.name for p in recording.iterdir())
    with read_only(folder):
        for target in (recording, db):  # the directory and the bare file
            code, report, err = run_cli([str(target)], tmp_path / "out.json", capsys)
            assert (code, err) == (0, "")
            assert report is not None
            assert reports(report, "t_ns", "fault_code") == [(1 * SEC, "MOTOR"), (2 * SEC, "PUMP")]
            assert report["parity"]["verdict"] == "match"
    assert snapshot(folder) == before
    assert sorted(p.name for p in recording.iterdir()) == listing == [db.name, "metadata.yaml"]
    assert not [p for p in folder.rglob("*") if p.name.endswith(("-wal", "-shm", "-journal"))]


KILL_WRITER = """
import os, sqlite3, sys
db = sqlite3.connect(sys.argv[1])
db.execute("PRAGMA wal_autocheckpoint=0")
row = db.execute("SELECT topic_id, data FROM messages ORDER BY id DESC LIMIT 1").fetchone()
db.execute("INSERT INTO messages (topic_id, timestamp, data) VALUES (?, 3000000000, ?)", row)
db.commit()
os._exit(0)  # the recorder dies: the -wal keeps the committed row, nothing checkpoints it
"""


def test_cli_reads_an_uncheckpointed_wal_without_touching_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "ro"
    folder.mkdir()
    recs = [named_errors(1 * SEC, "motor"), named_errors(2 * SEC, "fan")]
    recording = write_bag(folder / "bag", recs, storage="sqlite3")
    db = storage_file(recording)
    as_wal(db)
    subprocess.run([sys.executable, "-c", KILL_WRITER, str(db)], check=True)
    listing = sorted(p.name for p in recording.iterdir())
    assert listing == [db.name, f"{db.name}-shm", f"{db.name}-wal", "metadata.yaml"]
    before = snapshot(folder)
    with read_only(folder):
        code, report, err = run_cli([str(recording)], tmp_path / "out.json", capsys)
    assert (code, err) == (0, "")
    assert report is not None
    assert reports(report, "t_ns", "fault_code") == [
        (1 * SEC, "MOTOR"),
        (2 * SEC, "FAN"),
        (3 * SEC, "FAN"),  # the row only the -wal holds
    ]
    assert len(warnings_with(report, "not yet checkpointed")) == 1
    assert snapshot(folder) == before
    assert sorted(p.name for p in recording.iterdir()) == listing


FIXTURE_INPUTS = sorted(p for p in FIXTURES.iterdir() if p.is_dir()) + sorted(
    (FIXTURES / "bare_files").iterdir()
)
LOG_BRIDGE_READS = {"talker_mcap", "talker_sqlite3"}  # the only fixtures with /rosout messages


@pytest.mark.parametrize("with_log_bridge", [False, True], ids=["default", "log-bridge"])
@pytest.mark.parametrize("path", FIXTURE_INPUTS, ids=lambda p: p.name)
def test_every_fixture_through_the_cli(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], path: Path, with_log_bridge: bool
) -> None:
    args = [str(path)]
    if with_log_bridge:
        params = config(tmp_path, "medkit_replay:\n  ros__parameters: {enable_log_bridge: true}\n")
        args += ["--config", str(params)]
    code, report, err = run_cli(args, tmp_path / "out.json", capsys)
    if code == 2:  # only a truly unreadable input may end like this: one line naming it
        assert err.count("\n") == 1 and str(path) in err
        pytest.fail(f"fixture {path.name} is a real recording and must be readable: {err}")
    assert code == 0
    assert report is not None
    assert report["schema"] == SCHEMA
    assert [i["path"] for i in report["inputs"]] == [str(path)]
    # No fixture holds a topic a bridge turns into a fault (talker's /rosout is INFO only).
    assert report["reports"] == [] and report["faults"] == [] and report["parity"] is None
    read_something = with_log_bridge and path.name in LOG_BRIDGE_READS
    assert report["summary"]["messages_read"] == (10 if read_something else 0)
    empty = warnings_with(report, EMPTY)
    assert len(empty) == (0 if read_something else 1)
    if empty:
        # With the log bridge off, a recorded /rosout is named as what the bridge would read.
        bridge_off = "which the log bridge would read" in empty[0]
        assert bridge_off == (not with_log_bridge and path.name in LOG_BRIDGE_READS)
        assert ("/rosout" in empty[0]) == (with_log_bridge or bridge_off)


def damaged_mcap(tmp_path: Path) -> tuple[Path, int]:
    """A bare MCAP file cut inside its fourth chunk (40 ERROR statuses, 5 per chunk)."""
    recs = [named_errors((t + 1) * SEC, f"s{t}") for t in range(40)]
    source = storage_file(
        write_bag(tmp_path / "good", recs, storage="mcap", compression="chunk", chunk_every=5)
    )
    data = source.read_bytes()
    pos, starts = 8, []
    while pos + 9 <= len(data) and data[pos] != 0x0F:  # walk the records to find chunk starts
        if data[pos] == 0x06:
            starts.append(pos)
        pos += 9 + int.from_bytes(data[pos + 1 : pos + 9], "little")
    cut = starts[3] + 80
    return truncated(source, tmp_path / "cut.mcap", cut), cut


def test_truncated_mcap_through_the_cli(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path, _ = damaged_mcap(tmp_path)
    code, report, err = run_cli([str(path)], tmp_path / "out.json", capsys)
    assert (code, err) == (0, "")
    assert report is not None
    kept = [f"S{t}" for t in range(15)]  # the three complete chunks
    assert reports(report, "fault_code") == [(c,) for c in kept]
    assert sorted(f["fault_code"] for f in report["faults"]) == sorted(kept)
    assert report["summary"]["end_ns"] == 15 * SEC
    losses = [w for w in report["warnings"] if w.startswith(f"{path}: ")]
    assert any("is cut off" in w and "it is lost" in w for w in losses)
    assert any("truncated" in w for w in losses)
    assert len(losses) == len(set(losses))  # each loss said once, not once per pass over the file


def test_truncated_mcap_in_a_bag_directory(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cut, _ = damaged_mcap(tmp_path)
    recording = write_bag(tmp_path / "bag", [named_errors(SEC, "x")], storage="mcap")
    storage_file(recording).write_bytes(cut.read_bytes())
    code, report, err = run_cli([str(recording)], tmp_path / "out.json", capsys)
    assert (code, err) == (0, "")
    assert report is not None
    assert len(report["reports"]) == 15
    assert any("truncated" in w for w in report["warnings"])


def test_recorded_report_traffic_topic_is_in_the_inputs(tmp_path: Path, storage: Storage) -> None:
    report = run([everything(tmp_path, storage)])
    roles = {t["topic"]: (t["role"], t["messages"]) for t in report["inputs"][0]["topics"]}
    assert roles == {
        "/diagnostics": ("diagnostics", 3),
        f"{NAV}/_action/status": ("action_status", 2),
        "/fault_manager/events": ("fault_events", 1),
        REPORT_TOPIC: ("report_fault", 2),
        "/rosout": (None, 1),
    }
