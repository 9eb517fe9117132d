"""Recorded ReportFault/ClearFault service traffic through the whole pipeline (SEMANTICS.md §2).

One call (client_gid, sequence_number) can be recorded four times; it is applied once, at its
earliest request-side event. Metadata-only introspection is said, not guessed. A bridge's input and
the traffic that bridge produced live are never both applied for one fault code.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

from tests.pipeline_support import (
    ABORTED,
    CLEAR_TOPIC,
    ERROR,
    MS,
    REPORT_KEYS,
    REPORT_TOPIC,
    REQUEST_RECEIVED,
    REQUEST_SENT,
    RESPONSE_RECEIVED,
    RESPONSE_SENT,
    SEC,
    WARN,
    bag,
    clear_event,
    contract,
    diagnostics,
    events,
    fault,
    goals,
    on_topic,
    report_call,
    report_event,
    reports,
    run,
    status,
    warnings_with,
)

if TYPE_CHECKING:
    from pathlib import Path

    from tests.inputs.builders import Rec, Storage

ALL_FOUR = (REQUEST_SENT, REQUEST_RECEIVED, RESPONSE_SENT, RESPONSE_RECEIVED)
DOUBLE = "double counting avoided"
METADATA = "metadata-only"


@pytest.fixture(params=["mcap", "sqlite3"])
def storage(request: pytest.FixtureRequest) -> Storage:
    """Both storage plugins rosbag2 writes."""
    value: Storage = request.param
    return value


def clear_call(t_ns: int, code: str, *, sequence: int = 1) -> list[Rec]:
    """All four copies of one ClearFault call, 1 ms apart."""
    return [
        clear_event(t_ns + i * MS, kind, code, sequence=sequence) for i, kind in enumerate(ALL_FOUR)
    ]


# --- one call, up to four copies ----------------------------------------------------------------


@pytest.mark.parametrize(
    ("kinds", "offsets_ms", "applied_at_ms"),
    [
        (ALL_FOUR, (0, 2, 3, 5), 0),
        # the server's recorder logged its copy before the client's (clocks differ)
        ((REQUEST_RECEIVED, REQUEST_SENT, RESPONSE_SENT, RESPONSE_RECEIVED), (0, 4, 5, 6), 0),
        ((REQUEST_SENT, RESPONSE_RECEIVED), (10, 12), 10),  # client-side introspection only
        ((REQUEST_RECEIVED, RESPONSE_SENT), (7, 8), 7),  # server-side introspection only
        ((RESPONSE_SENT, REQUEST_SENT, REQUEST_RECEIVED), (1, 3, 4), 3),  # response first
    ],
    ids=["all-four", "server-first", "client-only", "server-only", "response-first"],
)
def test_one_call_is_applied_once_at_its_earliest_request(
    tmp_path: Path,
    storage: Storage,
    kinds: tuple[int, ...],
    offsets_ms: tuple[int, ...],
    applied_at_ms: int,
) -> None:
    times = [SEC + offset * MS for offset in offsets_ms]
    recs = report_call(
        times, "MOTOR_HOT", kinds=kinds, severity=1, description="too hot", source_id="/motor"
    )
    report = run([bag(tmp_path, "bag", recs, storage)])
    assert [contract(r, REPORT_KEYS) for r in report["reports"]] == [
        {
            "t_ns": SEC + applied_at_ms * MS,
            "origin": "report_fault",
            "topic": REPORT_TOPIC,
            "fault_code": "MOTOR_HOT",
            "event_type": "FAILED",
            "severity": 1,
            "description": "too hot",
            "source_id": "/motor",
            "accepted": True,
            "reject_reason": None,
        }
    ]
    motor = fault(report, "MOTOR_HOT")
    assert (motor["occurrence_count"], motor["first_occurred_ns"], motor["status"]) == (
        1,
        SEC + applied_at_ms * MS,
        "CONFIRMED",
    )
    assert events(report) == [
        (SEC + applied_at_ms * MS, "fault_confirmed", "MOTOR_HOT", "CONFIRMED")
    ]
    assert report["summary"]["messages_read"] == len(kinds)
    assert warnings_with(report, METADATA) == []


def test_distinct_calls_are_each_applied(tmp_path: Path, storage: Storage) -> None:
    recs = [
        # one client, two sequence numbers
        *report_call([1 * SEC, 1 * SEC + MS], "A", kinds=ALL_FOUR[:2], sequence=1),
        *report_call([2 * SEC, 2 * SEC + MS], "A", kinds=ALL_FOUR[:2], sequence=2),
        # another client reusing sequence number 1
        *report_call([3 * SEC, 3 * SEC + MS], "B", kinds=ALL_FOUR[:2], sequence=1, gid=42),
        # the same call on another fault manager's topic
        *(
            on_topic(rec, "/robot2/fault_manager/report_fault/_service_event")
            for rec in report_call([4 * SEC], "C", kinds=(REQUEST_RECEIVED,), sequence=1)
        ),
    ]
    report = run([bag(tmp_path, "bag", recs, storage)])
    assert reports(report, "t_ns", "fault_code", "topic") == [
        (1 * SEC, "A", REPORT_TOPIC),
        (2 * SEC, "A", REPORT_TOPIC),
        (3 * SEC, "B", REPORT_TOPIC),
        (4 * SEC, "C", "/robot2/fault_manager/report_fault/_service_event"),
    ]
    assert events(report) == [
        (1 * SEC, "fault_confirmed", "A", "CONFIRMED"),
        (2 * SEC, "fault_updated", "A", "CONFIRMED"),
        (3 * SEC, "fault_confirmed", "B", "CONFIRMED"),
        (4 * SEC, "fault_confirmed", "C", "CONFIRMED"),
    ]


def test_calls_split_over_two_bags_are_applied_once(tmp_path: Path, storage: Storage) -> None:
    client = bag(
        tmp_path,
        "client",
        report_call([SEC + 3 * MS, SEC + 9 * MS], "X", kinds=(REQUEST_SENT, RESPONSE_RECEIVED)),
        storage,
    )
    server = bag(
        tmp_path,
        "server",
        report_call([SEC + 1 * MS, SEC + 2 * MS], "X", kinds=(REQUEST_RECEIVED, RESPONSE_SENT)),
        storage,
    )
    report = run([client, server])
    assert reports(report, "t_ns", "fault_code") == [(SEC + MS, "X")]


def test_passed_and_rejected_calls(tmp_path: Path, storage: Storage) -> None:
    recs = [
        *report_call([1 * SEC], "PUMP", kinds=(REQUEST_RECEIVED,), sequence=1),
        *report_call([2 * SEC], "PUMP", kinds=(REQUEST_RECEIVED,), sequence=2, event_type=1),
        *report_call([3 * SEC], "bad code", kinds=(REQUEST_RECEIVED,), sequence=3),
    ]
    report = run([bag(tmp_path, "bag", recs, storage)])
    assert reports(report, "t_ns", "fault_code", "event_type", "accepted") == [
        (1 * SEC, "PUMP", "FAILED", True),
        (2 * SEC, "PUMP", "PASSED", True),
        (3 * SEC, "bad code", "FAILED", False),
    ]
    assert report["reports"][2]["reject_reason"].startswith("fault_code contains invalid character")
    assert fault(report, "PUMP")["last_passed_ns"] == 2 * SEC
    assert [f["fault_code"] for f in report["faults"]] == ["PUMP"]


def test_a_recorded_clear_call_clears(tmp_path: Path, storage: Storage) -> None:
    recs = [
        *report_call([1 * SEC + i * MS for i in range(4)], "MOTOR_HOT"),
        *clear_call(3 * SEC, "MOTOR_HOT"),
        *clear_call(4 * SEC, "NEVER_REPORTED", sequence=2),
    ]
    report = run([bag(tmp_path, "bag", recs, storage)])
    assert [(c["t_ns"], c["fault_code"], c["success"]) for c in report["clears"]] == [
        (3 * SEC, "MOTOR_HOT", True),
        (4 * SEC, "NEVER_REPORTED", False),
    ]
    assert fault(report, "MOTOR_HOT")["status"] == "CLEARED"
    assert events(report) == [
        (1 * SEC, "fault_confirmed", "MOTOR_HOT", "CONFIRMED"),
        (3 * SEC, "fault_cleared", "MOTOR_HOT", "CLEARED"),
    ]
    assert [(t["t_ns"], t["to_status"], t["cause"]) for t in report["transitions"]] == [
        (1 * SEC, "CONFIRMED", "report"),
        (3 * SEC, "CLEARED", "clear"),
    ]
    assert report["summary"]["clears"] == 2
    roles = {t["topic"]: t["role"] for t in report["inputs"][0]["topics"]}
    assert roles == {REPORT_TOPIC: "report_fault", CLEAR_TOPIC: "clear_fault"}


# --- metadata-only introspection ----------------------------------------------------------------


def test_metadata_only_calls_are_said_not_guessed(tmp_path: Path, storage: Storage) -> None:
    recs = [
        *report_call([1 * SEC + i * MS for i in range(4)], "", contents=False, sequence=1),
        *report_call([2 * SEC + i * MS for i in range(4)], "", contents=False, sequence=2),
        *report_call([3 * SEC, 3 * SEC + MS], "", kinds=ALL_FOUR[:2], contents=False, gid=3),
        clear_event(4 * SEC, REQUEST_SENT, "", contents=False),
        clear_event(4 * SEC + MS, RESPONSE_RECEIVED, "", contents=False),
    ]
    report = run([bag(tmp_path, "bag", recs, storage)])
    assert report["reports"] == [] and report["clears"] == [] and report["faults"] == []
    assert report["events"] == [] and report["transitions"] == []
    report_warning = warnings_with(report, REPORT_TOPIC)
    assert len(report_warning) == 1
    assert f"{REPORT_TOPIC}: 3 call(s)" in report_warning[0]
    assert METADATA in report_warning[0]
    clear_warning = warnings_with(report, CLEAR_TOPIC)
    assert len(clear_warning) == 1
    assert f"{CLEAR_TOPIC}: 1 call(s)" in clear_warning[0]
    assert report["summary"]["messages_read"] == 12
    assert warnings_with(report, "no topic the replay reads was found") == []


def test_payload_on_another_copy_counts_the_call(tmp_path: Path, storage: Storage) -> None:
    # client introspection in metadata mode, server in contents mode: the call is replayable
    recs = [
        report_event(SEC, REQUEST_SENT, "", contents=False),
        report_event(SEC + MS, REQUEST_RECEIVED, "MOTOR_HOT"),
        report_event(SEC + 2 * MS, RESPONSE_SENT, "MOTOR_HOT"),
        report_event(SEC + 3 * MS, RESPONSE_RECEIVED, "", contents=False),
    ]
    report = run([bag(tmp_path, "bag", recs, storage)])
    assert reports(report, "fault_code") == [("MOTOR_HOT",)]
    assert warnings_with(report, METADATA) == []


# --- no double counting -------------------------------------------------------------------------


def live_traffic(t_ns: int, code: str, sequence: int, severity: int = 2) -> list[Rec]:
    """What the live diagnostic bridge's ReportFault call for ``code`` left in the recording."""
    return report_call(
        [t_ns + i * MS for i in range(1, 5)],
        code,
        sequence=sequence,
        severity=severity,
        description="hot",
        source_id="/diagnostic_bridge",
    )


def test_recorded_calls_win_over_the_simulated_bridge(tmp_path: Path, storage: Storage) -> None:
    recs = [
        diagnostics(1 * SEC, status("motor", ERROR, "hot"), status("battery", ERROR, "low")),
        *live_traffic(1 * SEC, "MOTOR", 1),  # the live bridge's call for MOTOR (not for BATTERY)
        diagnostics(2 * SEC, status("motor", ERROR, "hot")),
        *live_traffic(2 * SEC, "MOTOR", 2),
    ]
    report = run([bag(tmp_path, "bag", recs, storage)])
    assert reports(report, "t_ns", "origin", "fault_code", "source_id") == [
        (1 * SEC, "diagnostic_bridge", "BATTERY", "/diagnostic_bridge"),
        (1 * SEC + MS, "report_fault", "MOTOR", "/diagnostic_bridge"),
        (2 * SEC + MS, "report_fault", "MOTOR", "/diagnostic_bridge"),
    ]
    motor = fault(report, "MOTOR")
    assert (motor["first_occurred_ns"], motor["last_occurred_ns"]) == (SEC + MS, 2 * SEC + MS)
    assert events(report) == [
        (1 * SEC, "fault_confirmed", "BATTERY", "CONFIRMED"),
        (1 * SEC + MS, "fault_confirmed", "MOTOR", "CONFIRMED"),
        (2 * SEC + MS, "fault_updated", "MOTOR", "CONFIRMED"),
    ]
    said = warnings_with(report, DOUBLE)
    assert len(said) == 1
    assert "2 request(s)" in said[0] and "diagnostic_bridge" in said[0]
    assert "1 code(s)" in said[0]


def test_the_rule_is_per_code_for_the_whole_recording(tmp_path: Path, storage: Storage) -> None:
    # The live call appears late (the recorder subscribed to services later): the bridge's
    # earlier WARN reports for that code are withheld too, so the code is never applied twice.
    recs = [diagnostics(t * SEC, status("motor", WARN, "warm")) for t in (1, 2, 3, 4)]
    recs += live_traffic(5 * SEC, "MOTOR", 1, severity=1)
    report = run([bag(tmp_path, "bag", recs, storage)])
    assert reports(report, "t_ns", "origin", "fault_code") == [
        (5 * SEC + MS, "report_fault", "MOTOR")
    ]
    said = warnings_with(report, DOUBLE)
    assert len(said) == 1 and "2 request(s)" in said[0]  # 3 s and 4 s passed the local filter


def test_no_overlap_no_warning(tmp_path: Path, storage: Storage) -> None:
    recs = [diagnostics(SEC, status("battery", ERROR, "low")), *live_traffic(SEC, "PUMP", 1)]
    report = run([bag(tmp_path, "bag", recs, storage)])
    assert reports(report, "origin", "fault_code") == [
        ("diagnostic_bridge", "BATTERY"),
        ("report_fault", "PUMP"),
    ]
    assert warnings_with(report, DOUBLE) == []


def test_recorded_traffic_in_another_input_counts(tmp_path: Path, storage: Storage) -> None:
    robot = bag(tmp_path, "robot", [diagnostics(SEC, status("motor", ERROR, "hot"))], storage)
    services = bag(tmp_path, "services", live_traffic(SEC, "MOTOR", 1), storage)
    report = run([robot, services])
    assert reports(report, "origin", "fault_code") == [("report_fault", "MOTOR")]
    assert len(warnings_with(report, DOUBLE)) == 1


def test_metadata_only_traffic_does_not_withhold_the_bridge(
    tmp_path: Path, storage: Storage
) -> None:
    recs = [
        diagnostics(SEC, status("motor", ERROR, "hot")),
        *report_call([SEC + i * MS for i in range(1, 5)], "", contents=False),
    ]
    report = run([bag(tmp_path, "bag", recs, storage)])
    assert reports(report, "origin", "fault_code") == [("diagnostic_bridge", "MOTOR")]
    assert warnings_with(report, DOUBLE) == []
    assert len(warnings_with(report, METADATA)) == 1


def test_each_bridge_is_named_in_its_own_warning(tmp_path: Path, storage: Storage) -> None:
    nav_aborted = "ACTION_NAVIGATE_TO_POSE_ABORTED"
    recs = [
        diagnostics(1 * SEC, status("motor", ERROR, "hot")),
        *live_traffic(1 * SEC, "MOTOR", 1),
        goals(2 * SEC, "/navigate_to_pose", ABORTED),
        *report_call(
            [2 * SEC + MS, 2 * SEC + 2 * MS],
            nav_aborted,
            kinds=(REQUEST_RECEIVED, RESPONSE_SENT),
            sequence=7,
            source_id="/bt_navigator",
        ),
        goals(3 * SEC, "/follow_path", ABORTED),  # no recorded call for this one
    ]
    report = run([bag(tmp_path, "bag", recs, storage)])
    assert reports(report, "t_ns", "origin", "fault_code", "source_id") == [
        (1 * SEC + MS, "report_fault", "MOTOR", "/diagnostic_bridge"),
        (2 * SEC + MS, "report_fault", nav_aborted, "/bt_navigator"),
        (3 * SEC, "action_status_bridge", "ACTION_FOLLOW_PATH_ABORTED", "/follow_path"),
    ]
    said = warnings_with(report, DOUBLE)
    assert len(said) == 2
    assert "action_status_bridge" in said[0] and "1 request(s)" in said[0]
    assert "diagnostic_bridge" in said[1] and "1 request(s)" in said[1]


@pytest.mark.parametrize("definitions", [True, False], ids=["stored", "bundled"])
def test_service_traffic_without_stored_definitions(
    tmp_path: Path, storage: Storage, definitions: bool
) -> None:
    recs = [
        *report_call([1 * SEC + i * MS for i in range(4)], "MOTOR_HOT"),
        *clear_call(2 * SEC, "MOTOR_HOT"),
    ]
    recording = bag(tmp_path, "bag", recs, storage, definitions=definitions)
    report = run([recording])
    assert reports(report, "t_ns", "fault_code") == [(1 * SEC, "MOTOR_HOT")]
    assert [(c["t_ns"], c["success"]) for c in report["clears"]] == [(2 * SEC, True)]
    assert report["summary"]["messages_read"] == 8
