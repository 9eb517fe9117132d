"""``explain`` on small JSON-lines scripts: every element of a fault's story, terminal and JSON."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING

import pytest

from medkit_replay.cli import main
from medkit_replay.explaining import build_story, render_story
from medkit_replay.outputs.json_report import dumps
from medkit_replay.pipeline import replay
from medkit_replay.trace import FaultTrace
from tests.explaining.support import S, clear, failed, passed, write_config, write_script

if TYPE_CHECKING:
    from pathlib import Path

JSONDict = dict[str, object]


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    status = main(argv)
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return status, out, err


def story_json(
    tmp_path: Path,
    lines: list[JSONDict],
    code: str,
    capsys: pytest.CaptureFixture[str],
    *extra: str,
    conf: int = -3,
    auto: float = 0.0,
) -> JSONDict:
    config = write_config(tmp_path, conf=conf, auto=auto)
    script = write_script(tmp_path, lines)
    status, out, err = run(
        ["explain", str(script), code, "--config", str(config), "--json", *extra], capsys
    )
    assert status == 0, err
    story: JSONDict = json.loads(out)
    return story


def story_text(
    tmp_path: Path, lines: list[JSONDict], code: str, *, conf: int = -3, at: float | None = None
) -> str:
    config = write_config(tmp_path, conf=conf)
    script = write_script(tmp_path, lines)
    trace = FaultTrace(fault_code=code, at_offset_ns=None if at is None else round(at * S))
    result = replay([script], [config], trace=trace)
    return render_story(build_story(result, trace), width=200)


def entries(story: JSONDict, kind: str) -> list[JSONDict]:
    listed = story["entries"]
    assert isinstance(listed, list)
    return [e for e in listed if e["kind"] == kind]


def test_rejected_report_says_why(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    lines = [failed(1, "MOTOR_OVERHEAT"), failed(2, "MOTOR_OVERHEAT", severity=7)]
    story = story_json(tmp_path, lines, "MOTOR_OVERHEAT", capsys)
    rejected = [e for e in entries(story, "report") if not e["accepted"]]
    assert len(rejected) == 1
    assert rejected[0]["t_ns"] == 2 * S and "severity" in str(rejected[0]["reject_reason"])
    assert rejected[0]["debounce_counter"] is None
    assert story["summary"]["reports_rejected"] == 1  # type: ignore[index]
    text = story_text(tmp_path, lines, "MOTOR_OVERHEAT")
    assert "rejected (" in text


def test_counter_and_effective_thresholds_after_each_report(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lines = [
        failed(1, "MOTOR_OVERHEAT"),
        failed(2, "MOTOR_OVERHEAT"),
        failed(3, "MOTOR_OVERHEAT", source="/robot/arm/joint1"),
    ]
    story = story_json(tmp_path, lines, "MOTOR_OVERHEAT", capsys)
    reports = entries(story, "report")
    assert [(r["debounce_counter"], r["confirmation_threshold"]) for r in reports] == [
        (-1, -3),
        (-2, -3),
        (-1, -1),  # the arm's band: per-entity thresholds, clamped into [-1, 0]
    ]
    assert [r["entity_prefix"] for r in reports] == [None, None, "/robot/arm"]
    assert reports[2]["status"] == "CONFIRMED" and reports[2]["healing_threshold"] == 0
    text = story_text(tmp_path, lines, "MOTOR_OVERHEAT")
    assert "per-entity thresholds of /robot/arm" in text
    assert "confirm at -3, heal at 2" in text


def test_near_miss_is_marked(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    lines = [failed(1, "MOTOR_OVERHEAT"), failed(2, "MOTOR_OVERHEAT"), passed(3, "MOTOR_OVERHEAT")]
    story = story_json(tmp_path, lines, "MOTOR_OVERHEAT", capsys)
    assert [r["near_miss_margin"] for r in entries(story, "report")] == [2, 1, None]
    assert story["summary"]["closest_near_miss"] == {"t_ns": 2 * S, "margin": 1}  # type: ignore[index]
    text = story_text(tmp_path, lines, "MOTOR_OVERHEAT")
    assert "came within 1 of confirming at 1.000 s" in text


def test_auto_confirm_is_silent(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    lines = [failed(0, "MOTOR_OVERHEAT"), passed(5, "OTHER")]
    story = story_json(tmp_path, lines, "MOTOR_OVERHEAT", capsys, auto=2.0)
    transitions = entries(story, "transition")
    assert [(t["from_status"], t["to_status"], t["cause"]) for t in transitions] == [
        (None, "PREFAILED", "report"),
        ("PREFAILED", "CONFIRMED", "auto_confirm"),
    ]
    assert transitions[1]["t_ns"] == 2 * S  # the first 1 s tick at or after 2 s
    withheld = entries(story, "event_withheld")
    assert withheld == [
        {
            "t_ns": 2 * S,
            "offset_ns": 2 * S,
            "kind": "event_withheld",
            "text": withheld[0]["text"],
            "event_type": "fault_confirmed",
            "reason": "auto-confirm is silent",
        }
    ]
    assert entries(story, "event") == []


def test_healing_and_its_event(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    lines = [failed(1, "MOTOR_OVERHEAT", severity=3), passed(2, "MOTOR_OVERHEAT")]
    lines += [passed(3, "MOTOR_OVERHEAT"), passed(4, "MOTOR_OVERHEAT")]
    story = story_json(tmp_path, lines, "MOTOR_OVERHEAT", capsys)
    healed = [t for t in entries(story, "transition") if t["to_status"] == "HEALED"]
    assert len(healed) == 1 and healed[0]["cause"] == "report"
    assert "healed by this report" in str(healed[0]["text"])
    events = [(e["event_type"], e["t_ns"]) for e in entries(story, "event")]
    assert ("fault_confirmed", 1 * S) in events and events[-1][0] == "fault_cleared"
    assert story["state"]["status"] == "HEALED"  # type: ignore[index]


def test_muted_symptom_auto_cleared_with_its_root(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lines = [failed(1, "MOTOR_OVERHEAT"), failed(2.5, "WHEEL_SLIP"), failed(3, "WHEEL_SLIP")]
    lines += [failed(3.2, "WHEEL_SLIP"), clear(5, "MOTOR_OVERHEAT")]
    story = story_json(tmp_path, lines, "WHEEL_SLIP", capsys)
    decisions = entries(story, "correlation")
    assert decisions[0]["root_cause_code"] == "MOTOR_OVERHEAT"
    assert decisions[0]["should_mute"] is True and decisions[0]["delay_ms"] == 1500
    rule = decisions[0]["rule"]
    assert isinstance(rule, dict)
    assert (rule["rule_id"], rule["window_ms"], rule["mode"]) == ("overheat", 3000, "hierarchical")
    withheld = entries(story, "event_withheld")
    assert [w["event_type"] for w in withheld] == ["fault_confirmed"]
    assert entries(story, "clear")[0]["fault_code"] == "MOTOR_OVERHEAT"
    last = entries(story, "transition")[-1]
    assert (last["to_status"], last["cause"]) == ("CLEARED", "auto_clear")
    assert "auto-cleared with its root MOTOR_OVERHEAT" in str(last["text"])
    root_event = entries(story, "event")[-1]
    assert root_event["fault_code"] == "MOTOR_OVERHEAT"
    assert root_event["auto_cleared_codes"] == ["WHEEL_SLIP"]
    text = story_text(tmp_path, lines, "WHEEL_SLIP")
    assert "symptom of MOTOR_OVERHEAT under rule overheat (hierarchical, window 3000 ms)" in text
    # The root's own story names the symptom it muted and the clear cascade.
    root = story_json(tmp_path, lines, "MOTOR_OVERHEAT", capsys)
    named = [d for d in entries(root, "correlation") if d["fault_code"] == "WHEEL_SLIP"]
    assert named and named[0]["should_mute"] is True
    assert entries(root, "clear")[0]["auto_cleared_codes"] == ["WHEEL_SLIP"]


def test_cluster_joined(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    lines = [failed(1, "CAM_RATE"), failed(1.5, "LIDAR_RATE"), failed(1.7, "LIDAR_RATE")]
    story = story_json(tmp_path, lines, "LIDAR_RATE", capsys)
    decisions = entries(story, "correlation")
    assert {d["cluster_id"] for d in decisions} == {"storm_1"}
    assert decisions[0]["should_mute"] is True  # not the representative (first: CAM_RATE)
    rule = decisions[0]["rule"]
    assert isinstance(rule, dict) and rule["rule_id"] == "storm" and rule["min_count"] == 2
    assert story["state"]["clusters"] == ["storm_1"]  # type: ignore[index]
    text = story_text(tmp_path, lines, "LIDAR_RATE")
    assert "cluster storm_1 joined under rule storm (auto_cluster, window 2000 ms)" in text


def test_at_stops_the_story_and_gives_the_state_then(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lines = [failed(1, "MOTOR_OVERHEAT"), failed(2, "MOTOR_OVERHEAT"), failed(3, "MOTOR_OVERHEAT")]
    lines += [passed(4, "MOTOR_OVERHEAT")]
    story = story_json(tmp_path, lines, "MOTOR_OVERHEAT", capsys, "--at", "1.5")
    # Seconds from the start: the script starts at 1 s, so the story stops at 2.5 s.
    assert (story["at_offset_ns"], story["at_ns"]) == (3 * S // 2, 5 * S // 2)
    assert [e["t_ns"] for e in entries(story, "report")] == [1 * S, 2 * S]
    state = story["state"]
    assert isinstance(state, dict)
    assert (state["status"], state["debounce_counter"], state["t_ns"]) == (
        "PREFAILED",
        -2,
        5 * S // 2,
    )
    before = story_json(tmp_path, lines, "MOTOR_OVERHEAT", capsys, "--at", "-1")
    assert before["entries"] == [] and before["state"]["known"] is False  # type: ignore[index]
    text = story_text(tmp_path, lines, "MOTOR_OVERHEAT", at=2.0)
    assert "state at 2.000 s: CONFIRMED" in text and "PASSED" not in text


def test_unknown_code_names_the_nearest(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    config = write_config(tmp_path)
    script = write_script(tmp_path, [failed(1, "MOTOR_OVERHEAT"), failed(2, "WHEEL_SLIP")])
    status, out, err = run(
        ["explain", str(script), "MOTOR_OVERHAET", "--config", str(config)], capsys
    )
    assert status == 2 and out == ""
    assert err.count("\n") == 1
    assert "'MOTOR_OVERHAET' never appears" in err
    assert "nearest codes: MOTOR_OVERHEAT, WHEEL_SLIP" in err


HOSTILE = "85 C \u202eevil\u202c \x1b[31mred\x1b[0m [bold]markup[/bold] :smile:"


def test_recording_text_is_escaped(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    lines = [failed(1, "MOTOR_OVERHEAT", description=HOSTILE)]
    config = write_config(tmp_path)
    script = write_script(tmp_path, lines)
    status, out, _ = run(
        ["explain", str(script), "MOTOR_OVERHEAT", "--config", str(config)], capsys
    )
    assert status == 0
    assert "\u202e" not in out and "\x1b" not in out
    assert "\\u202e" in out and "\\x1b[31m" in out and "[bold]markup[/bold]" in out
    assert ":smile:" in out
    status, raw, _ = run(
        ["explain", str(script), "MOTOR_OVERHEAT", "--config", str(config), "--json"], capsys
    )
    assert raw.isascii()
    assert json.loads(raw)["entries"][0]["description"] == HOSTILE


def test_piped_output_is_plain_and_json_is_deterministic(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lines = [failed(1, "MOTOR_OVERHEAT"), failed(2, "MOTOR_OVERHEAT"), clear(3, "MOTOR_OVERHEAT")]
    config = write_config(tmp_path)
    script = write_script(tmp_path, lines)
    argv = ["explain", str(script), "MOTOR_OVERHEAT", "--config", str(config)]
    _, text, _ = run(argv, capsys)
    assert "\x1b[" not in text and "state at 2.000 s: CLEARED" in text
    _, first, _ = run([*argv, "--json"], capsys)
    _, second, _ = run([*argv, "--json"], capsys)
    assert first == second
    json.loads(first, parse_constant=lambda c: pytest.fail(f"not strict JSON: {c}"))


def test_terminal_output_has_colour(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import io  # noqa: PLC0415

    from medkit_replay.explaining import print_story  # noqa: PLC0415

    monkeypatch.setenv("FORCE_COLOR", "1")
    monkeypatch.delenv("NO_COLOR", raising=False)
    config = write_config(tmp_path)
    script = write_script(tmp_path, [failed(1, "MOTOR_OVERHEAT", severity=3)])
    trace = FaultTrace(fault_code="MOTOR_OVERHEAT")
    result = replay([script], [config], trace=trace)
    stream = io.StringIO()
    print_story(build_story(result, trace), stream)
    assert "\x1b[" in stream.getvalue()


def test_tracing_changes_no_report_byte(tmp_path: Path) -> None:
    lines = [failed(1, "MOTOR_OVERHEAT"), failed(2.5, "WHEEL_SLIP"), clear(5, "MOTOR_OVERHEAT")]
    config = write_config(tmp_path, auto=1.0)
    script = write_script(tmp_path, lines)
    plain = dumps(replay([script], [config]))
    traced = dumps(replay([script], [config], trace=FaultTrace(fault_code="WHEEL_SLIP")))
    assert plain == traced


@pytest.mark.parametrize("at", ["nan", "inf", "soon"])
def test_at_must_be_a_time(tmp_path: Path, capsys: pytest.CaptureFixture[str], at: str) -> None:
    script = write_script(tmp_path, [failed(1, "MOTOR_OVERHEAT")])
    status, out, err = run(["explain", str(script), "MOTOR_OVERHEAT", "--at", at], capsys)
    assert status == 2 and out == "" and err.count("\n") == 1 and "--at" in err


def test_a_clear_of_the_fault_itself(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    lines = [failed(1, "MOTOR_OVERHEAT", severity=3), clear(2, "MOTOR_OVERHEAT")]
    lines += [clear(3, "MOTOR_OVERHEAT"), failed(4, "MOTOR_OVERHEAT")]
    story = story_json(tmp_path, lines, "MOTOR_OVERHEAT", capsys)
    assert [(c["t_ns"], c["success"], c["message"]) for c in entries(story, "clear")] == [
        (2 * S, True, "Fault cleared: MOTOR_OVERHEAT"),
        (3 * S, True, "Fault cleared: MOTOR_OVERHEAT"),
    ]
    assert [
        (t["from_status"], t["to_status"], t["cause"]) for t in entries(story, "transition")
    ] == [
        (None, "CONFIRMED", "report"),
        ("CONFIRMED", "CLEARED", "clear"),
        ("CLEARED", "PREFAILED", "report"),  # reactivated: the counter starts again
    ]
    cleared = [e for e in entries(story, "event") if e["event_type"] == "fault_cleared"]
    assert [e["t_ns"] for e in cleared] == [2 * S, 3 * S]
    listed = story["entries"]
    assert isinstance(listed, list)
    kinds = [e["kind"] for e in listed if e["t_ns"] == 2 * S]
    assert kinds == ["clear", "transition", "event"]
