"""``medkit-replay diff``: exit statuses, reports and recordings, tolerance, --update, --json."""

from __future__ import annotations

import io
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from medkit_replay.cli import main
from tests.diff.reports import SEC, base_report, fault

if TYPE_CHECKING:
    import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "nav2_mission.jsonl"
NAV2 = ROOT / "rules" / "nav2" / "fault_manager.yaml"
BRINGUP = ROOT / "rules" / "bringup" / "fault_manager.yaml"


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    status = main(argv)
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return status, out, err


def write(path: Path, report: dict[str, Any]) -> Path:
    path.write_text(json.dumps(report), encoding="utf-8")
    return path


def analyze(tmp_path: Path, name: str, config: Path, capsys: pytest.CaptureFixture[str]) -> Path:
    out = tmp_path / name
    status, _, _ = run(
        ["analyze", str(EXAMPLE), "--config", str(config), "--json", str(out), "--quiet"], capsys
    )
    assert status == 0
    return out


def test_identical_reports_exit_0(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    a = write(tmp_path / "a.json", base_report())
    b = write(tmp_path / "b.json", base_report())
    status, out, err = run(["diff", str(a), str(b)], capsys)
    assert (status, err) == (0, "")
    assert out == f"baseline: {a}\ncurrent:  {b}\nreports are equal (time tolerance 0.000 s)\n"


def test_every_difference_kind_exits_1(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    current = base_report()
    current["faults"].append(fault("BATTERY_LOW"))  # added
    del current["faults"][0]  # LIDAR_SCAN_RATE removed
    current["faults"][0]["severity"] = 3  # MOTOR_OVERHEAT changed
    current["transitions"][2]["t_ns"] += SEC  # the healing shifted
    current["events"][3]["t_ns"] += SEC  # its fault_cleared shifted
    current["events"].insert(3, dict(current["events"][2]))  # an extra fault_updated
    current["clusters"] = []  # removed
    a = write(tmp_path / "a.json", base_report())
    b = write(tmp_path / "b.json", current)
    status, out, err = run(["diff", str(a), str(b), "--json", str(tmp_path / "d.json")], capsys)
    assert status == 1
    assert err.splitlines() == [f"wrote {tmp_path / 'd.json'}"]  # the file written
    status, out, err = run(
        ["diff", str(a), str(b), "--json", str(tmp_path / "d.json"), "--quiet"], capsys
    )
    assert (status, out, err) == (1, "", "")  # never under --quiet
    status, out, err = run(["diff", str(a), str(b), "--json", str(tmp_path / "d.json")], capsys)
    assert "\x1b" not in out  # plain text when not on a terminal
    document = json.loads((tmp_path / "d.json").read_text(encoding="utf-8"))
    counts = {kind: n for kind, n in document["counts"].items() if n}
    assert counts == {
        "fault_added": 1,
        "fault_removed": 1,
        "fault_changed": 1,
        "transition_shifted": 1,
        "event_shifted": 1,
        "event_extra": 1,
        "cluster_removed": 1,
    }
    assert "reports differ: 7 differences" in out
    lines = out.splitlines()
    assert lines[lines.index("BATTERY_LOW") + 1].split() == ["+", "fault", "absent", "CONFIRMED"]
    assert lines[lines.index("LIDAR_SCAN_RATE") + 1].split() == [
        "-",
        "fault",
        "CONFIRMED",
        "absent",
    ]
    motor = lines.index("MOTOR_OVERHEAT")
    assert [line.split()[:2] for line in lines[motor + 1 : motor + 5]] == [
        ["~", "severity"],
        ["~", "CONFIRMED"],  # transitions first, then events, each in time order
        ["+", "event"],
        ["~", "event"],
    ]
    assert "(+1.000 s)" in lines[motor + 2]
    cluster_row = lines[lines.index("cluster storm_1") + 1].split()
    assert cluster_row[:3] == ["-", "cluster", "present:"] and cluster_row[-1] == "absent"
    # and the other way round: the mirror image of each
    status, out, _ = run(["diff", str(b), str(a), "--json", "-", "--quiet"], capsys)
    assert status == 1
    mirror = {kind: n for kind, n in json.loads(out)["counts"].items() if n}
    assert mirror == {
        "fault_added": 1,
        "fault_removed": 1,
        "fault_changed": 1,
        "transition_shifted": 1,
        "event_shifted": 1,
        "event_missing": 1,
        "cluster_added": 1,
    }


def test_time_tolerance(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    current = base_report()
    current["transitions"][1]["t_ns"] += 300_000_000
    a = write(tmp_path / "a.json", base_report())
    b = write(tmp_path / "b.json", current)
    assert run(["diff", str(a), str(b)], capsys)[0] == 1
    assert run(["diff", str(a), str(b), "--time-tolerance", "0.2"], capsys)[0] == 1
    status, out, _ = run(["diff", str(a), str(b), "--time-tolerance", "0.3"], capsys)
    assert status == 0 and "reports are equal (time tolerance 0.300 s)" in out
    status, _, err = run(["diff", str(a), str(b), "--time-tolerance", "-1"], capsys)
    assert status == 2 and "--time-tolerance" in err and len(err.splitlines()) == 1


def test_report_against_a_recording(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    report = analyze(tmp_path, "nav2.json", NAV2, capsys)
    argv = ["diff", str(report), str(EXAMPLE), "--config", str(NAV2)]
    status, out, _ = run(argv, capsys)
    assert status == 0 and f"{EXAMPLE} (replayed now)" in out and "reports are equal" in out
    # the recording as the baseline works too
    assert run(["diff", str(EXAMPLE), str(report), "--config", str(NAV2)], capsys)[0] == 0
    # replayed with the bringup settings (no correlation): no muting, no clusters
    status, out, _ = run(
        ["diff", str(report), str(EXAMPLE), "--config", str(BRINGUP), "--json", "-"], capsys
    )
    assert status == 1
    document = json.loads(out)
    assert document["current"] == f"{EXAMPLE} (replayed now)"
    assert document["counts"]["cluster_removed"] >= 1
    assert {"kind": "fault_changed", "field": "muted"}.items() <= next(
        d for d in document["differences"] if d.get("field") == "muted"
    ).items()


def test_two_recordings(capsys: pytest.CaptureFixture[str]) -> None:
    assert run(["diff", str(EXAMPLE), str(EXAMPLE), "--quiet"], capsys) == (0, "", "")


def test_update_rewrites_the_baseline(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    baseline = analyze(tmp_path, "baseline.json", BRINGUP, capsys)
    expected = analyze(tmp_path, "expected.json", NAV2, capsys).read_bytes()
    argv = ["diff", str(baseline), str(EXAMPLE), "--config", str(NAV2)]
    assert run(argv, capsys)[0] == 1
    status, out, _ = run([*argv, "--update"], capsys)
    assert status == 0
    assert "reports differ" in out and f"baseline updated: {baseline}" in out
    assert baseline.read_bytes() == expected  # exactly what analyze --json writes
    assert run(argv, capsys)[0] == 0
    assert not list(tmp_path.glob(".*tmp"))  # no temporary file left behind


def test_update_from_a_report_copies_it(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    a = write(tmp_path / "a.json", base_report())
    current = base_report()
    current["faults"][0]["status"] = "HEALED"
    b = tmp_path / "b.json"
    b.write_text(json.dumps(current, indent=1), encoding="utf-8")
    status, out, _ = run(["diff", str(a), str(b), "--update", "--json", "-"], capsys)
    assert status == 0
    document = json.loads(out)
    assert document["equal"] is False and document["baseline_updated"] is True
    assert a.read_bytes() == b.read_bytes()


def test_update_creates_a_missing_baseline(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    baseline = tmp_path / "new.json"
    argv = ["diff", str(baseline), str(EXAMPLE), "--config", str(NAV2)]
    status, _, err = run(argv, capsys)
    assert status == 2 and err == f"medkit-replay: error: {baseline}: no such report\n"
    status, out, _ = run([*argv, "--update"], capsys)
    assert status == 0 and out == f"baseline created: {baseline}\n"
    assert run(argv, capsys)[0] == 0


def test_update_refuses_a_recording_as_baseline(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    report = analyze(tmp_path, "nav2.json", NAV2, capsys)
    before = EXAMPLE.read_bytes()
    status, out, err = run(
        ["diff", str(EXAMPLE), str(report), "--config", str(NAV2), "--update"], capsys
    )
    assert status == 2 and out == ""
    assert err == (
        f"medkit-replay: error: {EXAMPLE}: --update rewrites a baseline report: "
        "BASELINE must be a .json report\n"
    )
    assert EXAMPLE.read_bytes() == before


def test_json_output(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    current = base_report()
    current["faults"][1]["occurrence_count"] = 4
    a = write(tmp_path / "a.json", base_report())
    b = write(tmp_path / "b.json", current)
    status, out, err = run(["diff", str(a), str(b), "--json", "-"], capsys)
    assert status == 1
    document = json.loads(out)  # standard output holds the JSON alone
    assert document == {
        "schema": "medkit-replay/diff/v1",
        "baseline": str(a),
        "current": str(b),
        "time_tolerance_ns": 0,
        "equal": False,
        "counts": document["counts"],
        "differences": [
            {
                "kind": "fault_changed",
                "fault_code": "MOTOR_OVERHEAT",
                "field": "occurrence_count",
                "baseline": 1,
                "current": 4,
            }
        ],
    }
    assert "reports differ: 1 difference" in err  # the human output moved to standard error
    target = tmp_path / "diff.json"
    status, out, _ = run(["diff", str(a), str(b), "--json", str(target)], capsys)
    assert status == 1 and "reports differ" in out
    assert json.loads(target.read_text(encoding="utf-8")) == document
    blocker = tmp_path / "blocker"
    blocker.write_text("", encoding="utf-8")
    status, _, err = run(
        ["diff", str(a), str(b), "--json", str(blocker / "d.json")], capsys
    )  # a missing folder is made (tests/commands); one where a file is cannot be
    assert status == 2 and "cannot write diff" in err


def test_config_with_two_reports_is_noted(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    a = write(tmp_path / "a.json", base_report())
    status, out, _ = run(["diff", str(a), str(a), "--config", str(NAV2)], capsys)
    assert status == 0
    assert "note: --config is not used: both sides are reports, nothing is replayed" in out


def test_bad_input_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    good = write(tmp_path / "good.json", base_report())
    other = write(tmp_path / "other.json", {"schema": "something/else"})
    broken = tmp_path / "broken.json"
    broken.write_text('{"schema":\n  nope}\n', encoding="utf-8")
    cases = {
        str(other): f"{other}: not a medkit-replay report: schema is 'something/else'",
        str(broken): f"{broken}:2: not valid JSON",
        str(tmp_path / "missing.json"): "missing.json: no such report",
        str(tmp_path): "no metadata.yaml",  # a directory that is not a recording
        str(tmp_path / "nothing.mcap"): "nothing.mcap",
    }
    for current, message in cases.items():
        status, out, err = run(["diff", str(good), current, "--quiet"], capsys)
        assert status == 2, current
        assert out == "" and err.startswith("medkit-replay: error: ") and message in err, err
        assert len(err.splitlines()) == 1
    status, _, err = run(["diff", str(good)], capsys)
    assert status == 2 and "Missing argument 'CURRENT'" in err


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_human_output_on_a_terminal_is_coloured_and_literal(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    current = base_report()
    current["faults"].append(fault("[red]NOT_MARKUP[/red]"))
    a = write(tmp_path / "a.json", base_report())
    b = write(tmp_path / "b.json", current)
    terminal = _Terminal()
    monkeypatch.delenv("NO_COLOR", raising=False)
    monkeypatch.setattr(sys, "stdout", terminal)
    assert main(["diff", str(a), str(b), "--update"]) == 0
    text = terminal.getvalue()
    assert "\x1b[" in text  # colour
    assert "[red]NOT_MARKUP[/red]" in text  # recorded text printed as it is
    assert "baseline updated: " in text
