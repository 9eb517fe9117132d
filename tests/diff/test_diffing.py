"""medkit_replay.diffing: every kind of difference, the alignment, the tolerance, the outputs."""

from __future__ import annotations

import copy
import json

import pytest

from medkit_replay.diffing import DIFF_SCHEMA, KINDS, diff_reports, render_diff, tolerance_ns
from medkit_replay.errors import InputError
from tests.diff.reports import SEC, START, base_report, cluster, event, fault, transition


def kinds(baseline: object, current: object, tolerance: int = 0) -> list[tuple[str, str]]:
    diff = diff_reports(baseline, current, time_tolerance_ns=tolerance)
    return [(d.kind, d.subject) for d in diff.differences]


def test_identical_reports_are_equal() -> None:
    diff = diff_reports(base_report(), base_report())
    assert diff.equal
    assert diff.counts() == dict.fromkeys(KINDS, 0)
    assert "reports are equal" in render_diff(diff)


def test_what_is_not_compared() -> None:
    current = base_report()
    current["tool_version"] = "9.9.9"
    current["inputs"][0]["path"] = "/elsewhere/run.jsonl"
    current["faults"][0]["description"] = "other words"
    current["faults"][0]["last_occurred_ns"] += SEC
    current["warnings"] = ["something"]
    current["reports"] = [{"t_ns": 1}]
    assert diff_reports(base_report(), current).equal


def test_fault_added_and_removed() -> None:
    current = base_report()
    current["faults"].append(fault("BATTERY_LOW"))
    current["transitions"].append(transition("BATTERY_LOW", 7.0, "CONFIRMED"))
    current["events"].append(event("BATTERY_LOW", 7.0, "fault_confirmed"))
    diff = diff_reports(base_report(), current)
    assert [(d.kind, d.subject) for d in diff.differences] == [("fault_added", "BATTERY_LOW")]
    assert diff.differences[0].to_json()["current"] == fault("BATTERY_LOW")
    reverse = diff_reports(current, base_report())
    assert [(d.kind, d.subject) for d in reverse.differences] == [("fault_removed", "BATTERY_LOW")]
    assert reverse.differences[0].to_json() == {
        "kind": "fault_removed",
        "fault_code": "BATTERY_LOW",
        "baseline": fault("BATTERY_LOW"),
    }


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("status", "HEALED"),
        ("severity", 3),
        ("occurrence_count", 2),
        ("reporting_sources", ["/node", "/other"]),
        ("muted", True),
        ("root_cause_code", "ESTOP"),
        ("cluster_ids", []),
    ],
)
def test_fault_changed(field: str, value: object) -> None:
    current = base_report()
    before = current["faults"][0][field]
    current["faults"][0][field] = value
    diff = diff_reports(base_report(), current)
    assert [d.to_json() for d in diff.differences] == [
        {
            "kind": "fault_changed",
            "fault_code": "LIDAR_SCAN_RATE",
            "field": field,
            "baseline": before,
            "current": value,
        }
    ]


def test_transition_and_event_shifted() -> None:
    current = base_report()
    current["transitions"][2]["t_ns"] += SEC // 2
    current["events"][3]["t_ns"] += SEC // 2
    diff = diff_reports(base_report(), current)
    assert [d.to_json() for d in diff.differences] == [
        {
            "kind": "transition_shifted",
            "fault_code": "MOTOR_OVERHEAT",
            "from_status": "CONFIRMED",
            "to_status": "HEALED",
            "cause": "report",
            "baseline_t_ns": START + 5 * SEC,
            "current_t_ns": START + 5 * SEC + SEC // 2,
            "shift_ns": SEC // 2,
        },
        {
            "kind": "event_shifted",
            "fault_code": "MOTOR_OVERHEAT",
            "event_type": "fault_cleared",
            "baseline_t_ns": START + 5 * SEC,
            "current_t_ns": START + 5 * SEC + SEC // 2,
            "shift_ns": SEC // 2,
        },
    ]
    lines = render_diff(diff).splitlines()
    assert [line.split() for line in lines[lines.index("MOTOR_OVERHEAT") + 1 :]] == [
        ["~", "CONFIRMED", "->", "HEALED", "5.000", "s", "5.500", "s", "(+0.500", "s)"],
        ["~", "event", "fault_cleared", "5.000", "s", "5.500", "s", "(+0.500", "s)"],
    ]


def test_tolerance() -> None:
    current = base_report()
    current["transitions"][1]["t_ns"] -= SEC // 4  # earlier: the absolute shift counts
    current["events"][1]["t_ns"] -= SEC // 4
    assert kinds(base_report(), current, SEC // 4) == []
    assert kinds(base_report(), current, SEC // 4 - 1) == [
        ("transition_shifted", "MOTOR_OVERHEAT"),
        ("event_shifted", "MOTOR_OVERHEAT"),
    ]
    assert tolerance_ns(0.25) == SEC // 4
    with pytest.raises(InputError, match="time tolerance"):
        tolerance_ns(-0.1)
    with pytest.raises(InputError, match="time tolerance"):
        tolerance_ns(float("nan"))


def test_missing_and_extra_are_aligned_like_a_text_diff() -> None:
    current = base_report()
    # MOTOR_OVERHEAT: the update at 3 s is gone; two more updates and a reconfirmation later.
    del current["events"][2]
    current["events"] += [
        event("MOTOR_OVERHEAT", 6.0, "fault_confirmed"),
        event("MOTOR_OVERHEAT", 7.0, "fault_updated"),
    ]
    current["transitions"].append(transition("MOTOR_OVERHEAT", 6.0, "CONFIRMED", "HEALED"))
    diff = diff_reports(base_report(), current)
    found = [
        (d.kind, d.detail.get("event_type") or d.detail.get("to_status"), d.detail["shift_ns"])
        for d in diff.differences
    ]
    assert found == [
        ("transition_extra", "CONFIRMED", None),
        ("event_missing", "fault_updated", None),
        ("event_extra", "fault_confirmed", None),
        ("event_extra", "fault_updated", None),
    ]
    missing = diff.differences[1].to_json()
    assert missing["baseline_t_ns"] == START + 3 * SEC and missing["current_t_ns"] is None


def test_items_at_the_same_time_are_aligned_first() -> None:
    """A fault_updated that vanished is missing; the later items are not shifted one along."""
    baseline = base_report()
    baseline["events"] += [
        event("MOTOR_OVERHEAT", 6.0, "fault_updated"),
        event("MOTOR_OVERHEAT", 7.0, "fault_updated"),
        event("MOTOR_OVERHEAT", 8.0, "fault_updated"),
    ]
    current = copy.deepcopy(baseline)
    del current["events"][5]  # the update at 7 s
    current["events"][-1]["t_ns"] += SEC // 10
    diff = diff_reports(baseline, current)
    assert [(d.kind, d.detail["baseline_t_ns"]) for d in diff.differences] == [
        ("event_missing", START + 7 * SEC),
        ("event_shifted", START + 8 * SEC),
    ]


def test_a_changed_cause_is_a_missing_and_an_extra_transition() -> None:
    current = base_report()
    current["transitions"][1]["cause"] = "auto_confirm"
    current["transitions"][1]["source_id"] = None
    assert kinds(base_report(), current) == [
        ("transition_missing", "MOTOR_OVERHEAT"),
        ("transition_extra", "MOTOR_OVERHEAT"),
    ]


def test_clusters_added_removed_changed() -> None:
    current = base_report()
    current["clusters"] = [cluster("storm_2", ["LIDAR_SCAN_RATE"])]
    assert kinds(base_report(), current) == [
        ("cluster_removed", "storm_1"),
        ("cluster_added", "storm_2"),
    ]
    current = base_report()
    current["clusters"][0]["fault_codes"] = ["LIDAR_SCAN_RATE", "IMU_DATA_RATE"]
    current["clusters"][0]["count"] = 2
    diff = diff_reports(base_report(), current)
    assert [(d.kind, d.subject, d.detail["field"]) for d in diff.differences] == [
        ("cluster_changed", "storm_1", "fault_codes"),
        ("cluster_changed", "storm_1", "count"),
    ]
    assert diff.differences[0].to_json()["cluster_id"] == "storm_1"
    assert "cluster storm_1" in render_diff(diff)


def test_json_output() -> None:
    current = base_report()
    current["faults"][1]["status"] = "CONFIRMED"
    diff = diff_reports(
        base_report(), current, time_tolerance_ns=5, baseline_name="a.json", current_name="b"
    )
    document = diff.to_json()
    assert json.loads(json.dumps(document)) == document
    assert document["schema"] == DIFF_SCHEMA
    assert document["baseline"] == "a.json" and document["current"] == "b"
    assert document["time_tolerance_ns"] == 5 and document["equal"] is False
    assert document["counts"] == {**dict.fromkeys(KINDS, 0), "fault_changed": 1}


def test_human_output_is_literal_and_safe() -> None:
    baseline = base_report()
    current = base_report()
    code = "[bold red]X\x1b[2J\u202e"
    current["faults"].append(fault(code))
    text = render_diff(diff_reports(baseline, current, baseline_name="[b]"), width=80)
    assert "[bold red]X\\x1b[2J\\u202e" in text
    assert "\x1b" not in text and "\u202e" not in text
    assert "baseline: [b]" in text
    assert "reports differ: 1 difference (fault added: 1; time tolerance 0.000 s)" in text


def test_many_differences_are_cut_in_the_human_output_only() -> None:
    current = base_report()
    current["faults"] += [fault(f"F{n:04d}") for n in range(600)]
    diff = diff_reports(base_report(), current)
    assert len(diff.differences) == 600
    assert "... and 100 more (the JSON output lists all)" in render_diff(diff)


@pytest.mark.parametrize(
    ("report", "message"),
    [
        ([], "not a JSON object"),
        ({"schema": "other/v1"}, "schema is 'other/v1'"),
        ({"schema": "medkit-replay/report/v1"}, "'faults' is not a list"),
        (
            {**base_report(), "transitions": [{"t_ns": 1}]},
            r"transitions\[0\] lacks one of t_ns, fault_code, to_status",
        ),
        (
            {**base_report(), "events": [{**event("A", 1, "fault_confirmed"), "t_ns": "1"}]},
            r"events\[0\].t_ns is not an integer",
        ),
        (
            {**base_report(), "events": [{**event("A", 1, "fault_confirmed"), "fault": {}}]},
            "an event without fault.fault_code",
        ),
        (
            {**base_report(), "events": [{**event("A", 1, "fault_confirmed"), "event_type": 1}]},
            r"events\[0\].event_type is not a string",
        ),
        (
            {**base_report(), "transitions": [{**transition("A", 1, "CONFIRMED"), "cause": []}]},
            r"transitions\[0\].cause is not a string",
        ),
        ({**base_report(), "faults": [fault("A"), 3]}, r"faults\[1\] lacks one of fault_code"),
    ],
)
def test_malformed_reports_are_input_errors(report: object, message: str) -> None:
    with pytest.raises(InputError, match=message) as caught:
        diff_reports(base_report(), report, current_name="cur.json")
    assert caught.value.path == "cur.json"
    assert caught.value.exit_code == 2


def test_large_gaps_are_aligned_by_runs_of_one_key() -> None:
    """Two recordings far apart in time: thousands of updates, none at the same instant."""
    baseline = base_report()
    baseline["events"] = [
        event("MOTOR_OVERHEAT", 10.0 + n / 100, "fault_updated") for n in range(3000)
    ]
    baseline["events"].insert(0, event("MOTOR_OVERHEAT", 9.0, "fault_confirmed"))
    baseline["events"].append(event("MOTOR_OVERHEAT", 50.0, "fault_cleared"))
    current = copy.deepcopy(baseline)
    del current["events"][1001]  # the update at 20.00 s
    for item in current["events"]:
        item["t_ns"] += 7
    diff = diff_reports(baseline, current, time_tolerance_ns=7)
    assert [(d.kind, d.detail["baseline_t_ns"]) for d in diff.differences] == [
        ("event_missing", START + 20 * SEC)
    ]
    counts = diff_reports(baseline, current).counts()
    assert (counts["event_shifted"], counts["event_missing"]) == (3001, 1)
