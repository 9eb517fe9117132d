"""Parity: the replayed FaultEvents against the live manager's recorded /fault_manager/events.

Recordings are written in tmp_path (MCAP and sqlite3) and replayed through the whole pipeline.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

from tests.pipeline_support import (
    ABORTED,
    ERROR,
    MS,
    SEC,
    SUCCEEDED,
    bag,
    config,
    diagnostics,
    fault_event,
    goals,
    on_topic,
    run,
    status,
    warnings_with,
)

if TYPE_CHECKING:
    from pathlib import Path

    from tests.inputs.builders import Rec, Storage

DIAG = "/diagnostic_bridge"
NAV = "/navigate_to_pose"
NAV_ABORTED = "ACTION_NAVIGATE_TO_POSE_ABORTED"
SUGGEST = "the live manager saw other reporting sources for action faults"


@pytest.fixture(params=["mcap", "sqlite3"])
def storage(request: pytest.FixtureRequest) -> Storage:
    """Both storage plugins rosbag2 writes."""
    value: Storage = request.param
    return value


def motor_run(recorded: list[Rec]) -> list[Rec]:
    """Two ERROR diagnostics for MOTOR (1 s, 2 s) with the recorded events interleaved."""
    return sorted(
        [
            diagnostics(1 * SEC, status("motor", ERROR, "hot")),
            diagnostics(2 * SEC, status("motor", ERROR, "hot")),
            *recorded,
        ],
        key=lambda rec: rec.t_ns,
    )


def test_no_recorded_events_no_parity(tmp_path: Path, storage: Storage) -> None:
    report = run([bag(tmp_path, "bag", motor_run([]), storage)])
    assert report["parity"] is None


def test_equal_events_match(tmp_path: Path, storage: Storage) -> None:
    recorded = [
        fault_event(1 * SEC + 4 * MS, "fault_confirmed", "MOTOR", sources=[DIAG]),
        fault_event(2 * SEC + 2 * MS, "fault_updated", "MOTOR", sources=[DIAG]),
    ]
    report = run([bag(tmp_path, "bag", motor_run(recorded), storage)])
    parity = report["parity"]
    assert parity["verdict"] == "match"
    assert {
        key: parity[key]
        for key in (
            "recorded_events",
            "replayed_events",
            "matched",
            "matched_with_differences",
            "missing_in_replay",
            "extra_in_replay",
            "max_abs_time_offset_ns",
        )
    } == {
        "recorded_events": 2,
        "replayed_events": 2,
        "matched": 2,
        "matched_with_differences": 0,
        "missing_in_replay": 0,
        "extra_in_replay": 0,
        "max_abs_time_offset_ns": 4 * MS,
    }
    assert parity["differences"] == parity["missing"] == parity["extra"] == []
    assert warnings_with(report, SUGGEST) == []


def test_namespaced_events_topic_is_compared(tmp_path: Path, storage: Storage) -> None:
    recorded = [
        on_topic(
            fault_event(1 * SEC + MS, "fault_confirmed", "MOTOR", sources=[DIAG]),
            "/robot1/fault_manager/events",
        ),
        on_topic(
            fault_event(2 * SEC + MS, "fault_updated", "MOTOR", sources=[DIAG]),
            "/robot1/fault_manager/events",
        ),
    ]
    report = run([bag(tmp_path, "bag", motor_run(recorded), storage)])
    assert report["parity"]["verdict"] == "match"
    assert report["parity"]["matched"] == 2


def test_differing_events_are_listed(tmp_path: Path, storage: Storage) -> None:
    recorded = [
        # the live manager saw CRITICAL where the replay has ERROR
        fault_event(1 * SEC + MS, "fault_confirmed", "MOTOR", severity=3, sources=[DIAG]),
        # the live manager published nothing for the 2 s report (missing one, extra one)
        fault_event(2 * SEC + MS, "fault_confirmed", "GHOST", sources=["/ghost"]),
    ]
    report = run([bag(tmp_path, "bag", motor_run(recorded), storage)])
    parity = report["parity"]
    assert parity["verdict"] == "differ"
    assert (
        parity["recorded_events"],
        parity["replayed_events"],
        parity["matched"],
        parity["matched_with_differences"],
        parity["missing_in_replay"],
        parity["extra_in_replay"],
    ) == (2, 2, 1, 1, 1, 1)
    [difference] = parity["differences"]
    assert difference["fault_code"] == "MOTOR"
    assert difference["event_type"] == "fault_confirmed"
    assert (difference["recorded_t_ns"], difference["replayed_t_ns"]) == (SEC + MS, SEC)
    assert difference["differences"] == {"severity": {"recorded": 3, "replayed": 2}}
    [missing] = parity["missing"]
    assert (missing["fault_code"], missing["event_type"], missing["recorded_t_ns"]) == (
        "GHOST",
        "fault_confirmed",
        2 * SEC + MS,
    )
    [extra] = parity["extra"]
    assert (extra["fault_code"], extra["event_type"], extra["replayed_t_ns"]) == (
        "MOTOR",
        "fault_updated",
        2 * SEC,
    )


def test_other_differing_fields(tmp_path: Path, storage: Storage) -> None:
    recorded = [
        fault_event(1 * SEC, "fault_confirmed", "MOTOR", occurrence_count=2, sources=[DIAG]),
        fault_event(2 * SEC, "fault_updated", "MOTOR", sources=[DIAG, "/other"]),
    ]
    report = run([bag(tmp_path, "bag", motor_run(recorded), storage)])
    parity = report["parity"]
    assert parity["verdict"] == "differ"
    assert [d["differences"] for d in parity["differences"]] == [
        {"occurrence_count": {"recorded": 2, "replayed": 1}},
        {"reporting_sources": {"recorded": [DIAG, "/other"], "replayed": [DIAG]}},
    ]
    assert parity["max_abs_time_offset_ns"] == 0


def action_run(tmp_path: Path, storage: Storage, live_source: str) -> Path:
    recs = [
        goals(1 * SEC, NAV, ABORTED),
        fault_event(1 * SEC + MS, "fault_confirmed", NAV_ABORTED, sources=[live_source]),
        goals(2 * SEC, NAV, SUCCEEDED),
        fault_event(2 * SEC + MS, "fault_updated", NAV_ABORTED, sources=[live_source]),
    ]
    return bag(tmp_path, "bag", recs, storage)


def test_action_server_node_is_suggested(tmp_path: Path, storage: Storage) -> None:
    report = run([action_run(tmp_path, storage, "/bt_navigator")])
    parity = report["parity"]
    assert parity["verdict"] == "differ"
    assert parity["suggested_action_sources"] == {NAV: "/bt_navigator"}
    assert [d["differences"] for d in parity["differences"]] == [
        {"reporting_sources": {"recorded": ["/bt_navigator"], "replayed": [NAV]}}
    ] * 2
    [said] = warnings_with(report, SUGGEST)
    assert "medkit_replay.action_sources" in said and f"{NAV}: /bt_navigator" in said


def test_following_the_suggestion_matches(tmp_path: Path, storage: Storage) -> None:
    params = config(
        tmp_path,
        "medkit_replay:\n  ros__parameters:\n    action_sources:\n"
        "      /navigate_to_pose: /bt_navigator\n",
    )
    report = run([action_run(tmp_path, storage, "/bt_navigator")], [params])
    parity = report["parity"]
    assert parity["verdict"] == "match"
    assert "suggested_action_sources" not in parity
    assert warnings_with(report, SUGGEST) == []


def test_action_name_as_source_needs_no_suggestion(tmp_path: Path, storage: Storage) -> None:
    report = run([action_run(tmp_path, storage, NAV)])
    assert report["parity"]["verdict"] == "match"
    assert "suggested_action_sources" not in report["parity"]
    assert warnings_with(report, SUGGEST) == []
