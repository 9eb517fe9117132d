"""``explain`` on bags built in code: requests held before the manager, and why."""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.explaining import build_story, story_record
from medkit_replay.pipeline import replay
from medkit_replay.trace import FaultTrace
from tests.inputs.builders import log
from tests.pipeline_support import (
    MS,
    SEC,
    WARN,
    bag,
    config,
    diagnostics,
    report_call,
    status,
)

if TYPE_CHECKING:
    from pathlib import Path

Record = dict[str, object]


def story(inputs: list[Path], code: str, configs: list[Path] | None = None) -> Record:
    trace = FaultTrace(fault_code=code)
    result = replay(inputs, configs or [], trace=trace)
    record: Record = story_record(build_story(result, trace))  # type: ignore[assignment]
    return record


def kind(record: Record, name: str) -> list[Record]:
    entries = record["entries"]
    assert isinstance(entries, list)
    return [e for e in entries if e["kind"] == name]


def test_recorded_calls_win_and_the_bridge_requests_are_held(tmp_path: Path) -> None:
    recs = [
        diagnostics(t * SEC, status("motor", WARN, "warm", values=[("temp_c", "71")]))
        for t in (1, 2, 3, 4)
    ]
    recs += report_call(
        [5 * SEC + i * MS for i in range(1, 5)],
        "MOTOR",
        sequence=1,
        severity=1,
        description="warm",
        source_id="/diagnostic_bridge",
    )
    record = story([bag(tmp_path, "bag", recs, "mcap")], "MOTOR")
    held = kind(record, "held")
    assert [(h["t_ns"], h["stage"]) for h in held] == [
        (1 * SEC, "local_filter"),
        (2 * SEC, "local_filter"),
        (3 * SEC, "double_counting"),
        (4 * SEC, "double_counting"),
    ]
    assert "1 of 3 FAILED report(s) within 10 s" in str(held[0]["reason"])
    assert "recorded ReportFault traffic" in str(held[2]["reason"])
    message = held[2]["message"]
    assert isinstance(message, dict)
    assert message["fields"] == {
        "level": {"value": 1, "name": "WARN"},
        "name": "motor",
        "message": "warm",
        "hardware_id": "",
    }
    assert message["items"] == [["temp_c", "71"]]
    (report,) = kind(record, "report")
    assert (report["origin"], report["t_ns"]) == ("report_fault", 5 * SEC + MS)
    recorded = report["message"]
    assert isinstance(recorded, dict)
    assert recorded["type"] == "ros2_medkit_msgs/srv/ReportFault_Event"
    fields = recorded["fields"]
    assert isinstance(fields, dict) and fields["sequence_number"] == 1
    assert fields["event_type"] == {"value": 0, "name": "REQUEST_SENT"}


def test_the_log_bridge_cooldown_is_told(tmp_path: Path) -> None:
    params = config(
        tmp_path,
        "log_bridge:\n  ros__parameters:\n    report_cooldown_sec: 5.0\n",
    )
    recs = [log(t * SEC, level=40, text="boom", name="driver") for t in (1, 2, 7)]
    inputs = [bag(tmp_path, "bag", recs, "mcap")]
    codes = {f.fault_code for f in replay(inputs, [params]).faults}
    (code,) = codes
    record = story(inputs, code, [params])
    assert [r["t_ns"] for r in kind(record, "report")] == [1 * SEC, 7 * SEC]
    (held,) = kind(record, "held")
    assert (held["t_ns"], held["stage"]) == (2 * SEC, "cooldown")
    assert "forwarded 1.000 s before (report_cooldown_sec 5)" in str(held["reason"])
    message = kind(record, "report")[0]["message"]
    assert isinstance(message, dict) and message["type"] == "rcl_interfaces/msg/Log"
    assert message["fields"]["msg"] == "boom"
