"""The command line end to end: outputs, exit statuses, one-line errors, determinism."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from medkit_replay.cli import main

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "nav2_mission.jsonl"
NAV2 = ROOT / "rules" / "nav2" / "fault_manager.yaml"


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    status = main(argv)
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return status, out, err


def test_example_summary_on_stdout(capsys: pytest.CaptureFixture[str]) -> None:
    status, out, err = run(["analyze", str(EXAMPLE), "--config", str(NAV2)], capsys)
    assert status == 0 and err == ""
    assert "ESTOP_PRESSED" in out and "muted by ESTOP_PRESSED" in out
    assert "cluster sensor_storm_1" in out


def test_json_to_stdout_keeps_stdout_pure(capsys: pytest.CaptureFixture[str]) -> None:
    status, out, err = run(["analyze", str(EXAMPLE), "--config", str(NAV2), "--json", "-"], capsys)
    assert status == 0
    report = json.loads(out)
    assert report["schema"] == "medkit-replay/report/v1"
    assert list(report) == [
        "schema",
        "tool_version",
        "upstream_release",
        "inputs",
        "faults",
        "events",
        "transitions",
        "reports",
        "clears",
        "muted_faults",
        "clusters",
        "near_misses",
        "retroactive_cluster_mutes",
        "snapshots",
        "recordings",
        "evidence_notes",
        "parity",
        "warnings",
        "summary",
    ]
    assert "faults:" in err  # the human summary moved to standard error
    rejected = [r for r in report["reports"] if not r["accepted"]]
    assert rejected == [
        {
            "t_ns": 26000000000,
            "origin": "script",
            "topic": None,
            "fault_code": "bad code!",
            "event_type": "FAILED",
            "severity": 2,
            "description": "",
            "source_id": "/misconfigured_node",
            "accepted": False,
            "reject_reason": "fault_code contains invalid character ' '. Only alphanumeric, "
            "underscore, hyphen, and dot are allowed",
            "status": None,
            "debounce_counter": None,
            "confirmation_threshold": None,
            "healing_threshold": None,
            "withheld_event": None,
        }
    ]
    assert report["muted_faults"] == [
        {
            "fault_code": "ACTION_FOLLOW_PATH_ABORTED",
            "root_cause_code": "ESTOP_PRESSED",
            "rule_id": "estop_cascade",
            "delay_ms": 100,
        }
    ]
    clear = report["clears"][0]
    assert clear["message"] == "Fault cleared: MOTOR_OVERHEAT (auto-cleared 2 symptoms)"
    assert clear["auto_cleared_codes"] == [
        "MOTOR_LEFT_COMM_TIMEOUT",
        "ACTION_NAVIGATE_TO_POSE_ABORTED",
    ]


def test_same_inputs_give_byte_identical_json(tmp_path: Path) -> None:
    outputs = []
    for name in ("a.json", "b.json"):
        assert (
            main(
                [
                    "analyze",
                    str(EXAMPLE),
                    "--config",
                    str(NAV2),
                    "--json",
                    str(tmp_path / name),
                    "--quiet",
                ]
            )
            == 0
        )
        outputs.append((tmp_path / name).read_bytes())
    assert outputs[0] == outputs[1]


def test_csv_tables(tmp_path: Path) -> None:
    assert main(["analyze", str(EXAMPLE), "--csv", str(tmp_path / "t"), "--quiet"]) == 0
    names = sorted(p.name for p in (tmp_path / "t").iterdir())
    assert names == sorted(
        f"{n}.csv"
        for n in (
            "faults",
            "events",
            "transitions",
            "reports",
            "clears",
            "muted_faults",
            "clusters",
            "near_misses",
            "snapshots",
            "recordings",
        )
    )
    header = (tmp_path / "t" / "faults.csv").read_text().splitlines()[0]
    assert header.startswith("fault_code,severity,severity_name,description")


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("make_args", "expected"),
    [
        (lambda t: ["analyze", str(t / "missing.jsonl")], "missing.jsonl: input not found"),
        (
            lambda t: ["analyze", str(write(t, "s.jsonl", '{"t_ns": 1}\n'))],
            "s.jsonl:1: missing 'fault_code'",
        ),
        (
            lambda t: ["analyze", str(EXAMPLE), "--config", str(t / "none.yaml")],
            "none.yaml: config file not found",
        ),
        (
            lambda t: [
                "analyze",
                str(EXAMPLE),
                "--config",
                str(write(t, "bad.yaml", "fault_manager:\n  ros__parameters: [\n")),
            ],
            "bad.yaml:3: invalid YAML",
        ),
        (lambda t: ["analyze", str(write(t, "x.bin", "x"))], "x.bin: unsupported input"),
        (lambda t: ["analyze"], "Missing argument"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], make_args: object, expected: str
) -> None:
    assert callable(make_args)
    status, out, err = run(make_args(tmp_path), capsys)
    assert status == 2
    assert out == ""
    assert err.count("\n") == 1 and expected in err


def test_invalid_correlation_disables_it_loudly(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    write(
        tmp_path,
        "corr.yaml",
        "correlation:\n  enabled: true\n  rules:\n    - {id: r, mode: hierarchical}\n",
    )
    params = write(
        tmp_path,
        "p.yaml",
        "fault_manager:\n  ros__parameters:\n    correlation: {config_file: corr.yaml}\n",
    )
    status, out, _ = run(
        ["analyze", str(EXAMPLE), "--config", str(params), "--json", "-", "--quiet"], capsys
    )
    assert status == 0
    report = json.loads(out)
    text = "\n".join(report["warnings"])
    assert "Hierarchical rule 'r' has no root_cause codes" in text
    assert report["muted_faults"] == [] and report["clusters"] == []


def test_console_script_runs_without_traceback(tmp_path: Path) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "medkit_replay.cli", "analyze", str(tmp_path / "nope.jsonl")],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 2
    assert proc.stderr.startswith("medkit-replay: error: ")
    assert "Traceback" not in proc.stderr


def test_console_script_writes_everything_before_it_leaves(tmp_path: Path) -> None:
    """The console script leaves without freeing the replay's objects: what it printed and
    wrote is whole, its status is the command's, and a reader that stops early is no error."""
    command = [sys.executable, "-m", "medkit_replay.cli", "analyze", str(EXAMPLE), "--json", "-"]
    whole = subprocess.run([*command, "--config", str(NAV2)], capture_output=True, check=False)
    assert whole.returncode == 0
    assert json.loads(whole.stdout)["summary"]["faults"] > 0
    assert b"faults:" in whole.stderr  # the summary, after the report
    head = subprocess.run(
        f"{' '.join(map(str, command))} | head -c 10",
        shell=True,
        capture_output=True,
        check=False,
        executable="/bin/bash",
    )
    assert head.stdout == whole.stdout[:10]
    assert b"Traceback" not in head.stderr and b"Exception ignored" not in head.stderr
    failed = subprocess.run(
        [
            *command[:3],
            "check",
            str(EXAMPLE),
            "--budget",
            str(ROOT / "rules" / "budgets" / "nav2_mission_fail.yaml"),
            "--config",
            str(NAV2),
        ],
        capture_output=True,
        check=False,
    )
    assert failed.returncode == 1  # a check's own status comes through


def test_python_api_tables() -> None:
    import medkit_replay  # noqa: PLC0415
    from medkit_replay import replay  # noqa: PLC0415

    result = replay([EXAMPLE], [NAV2])
    tables = medkit_replay.tables(result)
    assert set(tables) == {
        "faults",
        "events",
        "transitions",
        "reports",
        "clears",
        "muted_faults",
        "clusters",
        "near_misses",
        "snapshots",
        "recordings",
    }
    faults = tables["faults"]
    assert list(faults["fault_code"]) == [f.fault_code for f in result.faults]
    assert faults.set_index("fault_code").loc["ESTOP_PRESSED", "status"] == "CONFIRMED"
    fault = result.fault("LIDAR_SCAN_DROPOUT")
    assert fault is not None and fault.status == "HEALED"


def test_html_report_option(tmp_path: Path) -> None:
    out = tmp_path / "report.html"
    assert (
        main(["analyze", str(EXAMPLE), "--config", str(NAV2), "--html", str(out), "--quiet"]) == 0
    )
    text = out.read_text()
    assert text.startswith("<!DOCTYPE html>") or text.lower().startswith("<!doctype html>")
    assert text.count('class="fault-row"') == 8


def test_unwritable_output_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # A missing folder is made (as --csv makes its own); a file in the way of it cannot be.
    (tmp_path / "a-file").write_text("")
    target = tmp_path / "a-file" / "sub" / "report.html"
    status, _, err = run(["analyze", str(EXAMPLE), "--html", str(target), "--quiet"], capsys)
    assert status == 2 and err.count("\n") == 1 and "cannot write HTML" in err
