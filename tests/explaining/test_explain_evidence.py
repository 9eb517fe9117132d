"""``explain`` tells the evidence of a fault: its freeze frames and black-box recordings."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from medkit_replay.evidence import EvidenceOptions, load_graph
from medkit_replay.explaining import build_story, render_story, story_record
from medkit_replay.pipeline import replay
from medkit_replay.trace import FaultTrace

if TYPE_CHECKING:
    from medkit_replay.result import Result

ROOT = Path(__file__).resolve().parents[2]
MISSION = ROOT / "sample_bags" / "nav2_mission_mcap"
CONFIGS = [
    ROOT / "rules" / "nav2" / "fault_manager.yaml",
    ROOT / "rules" / "nav2" / "bridges.yaml",
    ROOT / "examples" / "evidence" / "capture.yaml",
]
GRAPH = ROOT / "examples" / "evidence" / "nav2_graph.txt"
CODE = "MOTOR_LEFT_OVERHEAT"


def _story(at_ns: int | None = None) -> tuple[dict[str, Any], str, Result]:
    trace = FaultTrace(fault_code=CODE, at_offset_ns=at_ns)
    result = replay(
        [MISSION], CONFIGS, trace=trace, evidence=EvidenceOptions(graph=load_graph(GRAPH))
    )
    story = build_story(result, trace)
    record: dict[str, Any] = json.loads(json.dumps(story_record(story), allow_nan=False))
    return record, render_story(story), result


def test_each_capture_and_recording_of_the_fault_is_told_after_its_confirmation() -> None:
    record, text, result = _story()
    entries = record["entries"]
    assert isinstance(entries, list)
    captures = [e for e in entries if e["kind"] == "capture"]
    recordings = [e for e in entries if e["kind"] == "recording"]
    expected = [c for c in result.snapshots if c.fault_code == CODE]
    assert expected, "the capture config captures this fault"
    assert [(e["capture_id"], e["t_ns"]) for e in captures] == [
        (c.capture_id, c.t_ns) for c in expected
    ]
    for entry, capture in zip(captures, expected, strict=True):
        assert [t["topic"] for t in entry["topics"]] == [t.topic for t in capture.topics]
        assert [t["data"] for t in entry["topics"]] == [
            json.loads(json.dumps(t.data)) for t in capture.topics
        ]
    owned = [r for r in result.recordings if CODE in r.fault_codes]
    assert [e["recording_id"] for e in recordings] == [r.recording_id for r in owned]
    # Told right after the step that confirmed the fault (the event it published).
    at = entries.index(captures[0])
    confirmed = [
        e for e in entries[:at] if e["kind"] == "transition" and e["to_status"] == "CONFIRMED"
    ]
    assert confirmed and confirmed[-1]["t_ns"] == captures[0]["t_ns"]
    assert f"capture freeze frame {captures[0]['capture_id']}" in text
    assert f"recording {recordings[0]['recording_id']}" in " ".join(text.split())


def test_a_story_stopped_before_the_confirmation_tells_no_capture() -> None:
    record, _, result = _story()
    first = min(c.t_ns for c in result.snapshots if c.fault_code == CODE)
    origin = record["recording"]["start_ns"]
    stopped, _, _ = _story(at_ns=first - origin - 1)
    assert not [e for e in stopped["entries"] if e["kind"] in ("capture", "recording")]
