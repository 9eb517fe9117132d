"""``medkit-replay sweep`` on the command line: exit statuses, one-line errors, the summary,
byte-identical tables whatever the number of workers, budgets and failed inputs."""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

import pytest

from medkit_replay.cli import main
from tests.fleet.fleet_support import report, write_script

ROOT = Path(__file__).resolve().parents[2]
NAV2 = ROOT / "rules" / "nav2"
BRINGUP = ROOT / "rules" / "bringup" / "fault_manager.yaml"
BUDGETS = ROOT / "rules" / "budgets"


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    status = main(argv)
    out, err = capsys.readouterr()
    return status, out, err


def flapping(path: Path) -> Path:
    """A code that fails and passes in turns: the healing threshold decides the flaps."""
    lines = []
    for cycle in range(6):
        start = cycle * 10.0
        lines += [report(start + 0.1 * i, "WIFI_WEAK") for i in range(3)]
        lines += [report(start + 1 + 0.5 * i, "WIFI_WEAK", "PASSED") for i in range(2 + cycle % 3)]
    lines.append(report(70.0, "BATTERY_LOW"))
    return write_script(path, lines)


@pytest.mark.parametrize(
    ("vary", "message"),
    [
        ("nonsense", "--vary nonsense: expected NODE.PARAM=V1,V2,..."),
        ("robot.speed=1,2", "--vary robot.speed=1,2: unknown node 'robot'"),
        ("fault_manager.confirmaton_threshold=-1", "--vary fault_manager.confirmaton_threshold:"),
        (
            "fault_manager.confirmation_threshold=-1,abc",
            "--vary fault_manager.confirmation_threshold=abc: fault_manager parameter "
            "'confirmation_threshold' must be an integer, got string 'abc'",
        ),
        (
            "fault_manager.auto_confirm_after_sec=1",
            "--vary fault_manager.auto_confirm_after_sec=1: fault_manager parameter "
            "'auto_confirm_after_sec' must be a double, got integer 1 (write 1.0)",
        ),
        ("fault_manager.healing_threshold=1,1", "a value is listed twice"),
        ("log_bridge.severity_floor=[1, 2]", "log_bridge parameter 'severity_floor'"),
    ],
)
def test_a_bad_name_or_value_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], vary: str, message: str
) -> None:
    script = flapping(tmp_path / "wifi.jsonl")
    status, out, err = run(["sweep", str(script), "--vary", vary, "--quiet"], capsys)
    assert status == 2
    assert message in err
    assert err.count("\n") == 1
    assert "Traceback" not in err + out


def test_a_parameter_varied_twice_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    script = flapping(tmp_path / "wifi.jsonl")
    argv = ["sweep", str(script), "--vary", "fault_manager.healing_threshold=1"]
    status, _, err = run([*argv, "--vary", "fault_manager.healing_threshold=2"], capsys)
    assert status == 2
    assert "varied twice" in err


def test_the_summary_ranks_fewest_flaps_first_among_equal_detections(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    script = flapping(tmp_path / "wifi.jsonl")
    argv = ["sweep", str(script), "--config", str(BRINGUP), "--jobs", "1"]
    status, out, _ = run([*argv, "--vary", "fault_manager.healing_threshold=1,2,4"], capsys)
    assert status == 0
    assert "sweep: 3 variant(s) x 1 input(s)" in out
    lines = out.splitlines()
    ranked = [line.split()[1] for line in lines if line.strip()[:2] in ("1 ", "2 ", "3 ")]
    # Healing after 4 net PASSED never heals WIFI_WEAK here: no flaps, fewest events.
    assert ranked[0] == "v03"
    assert "Ranked by" in out.replace("\n", " ")


def test_a_base_config_warning_is_printed_once_and_a_variant_one_per_variant(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    script = flapping(tmp_path / "wifi.jsonl")
    base = tmp_path / "base.yaml"
    base.write_text("fault_manager:\n  ros__parameters:\n    healing_treshold: 2\n")
    argv = ["sweep", str(script), "--config", str(base), "--jobs", "1", "--quiet"]
    varies = ["--vary", "fault_manager.healing_threshold=1,2"]
    varies += ["--vary", "fault_manager.confirmation_threshold=-1,2"]
    status, _, err = run([*argv, *varies], capsys)
    assert status == 0
    typo = [line for line in err.splitlines() if "healing_treshold" in line]
    assert typo == [
        f"medkit-replay: warning: {base}:3: fault_manager has no parameter 'healing_treshold' "
        "at ros2_medkit 0.7.0 (did you mean 'healing_threshold'?); upstream ignores it"
    ]
    positive = [line for line in err.splitlines() if "is positive" in line]
    assert [line.split()[2] for line in positive] == ["v02:", "v04:"]


def test_tables_are_byte_identical_whatever_the_workers(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scripts = [flapping(tmp_path / f"in/run_{i}.jsonl") for i in range(3)]
    outs = []
    for jobs in ("1", "2", "3"):
        out = tmp_path / f"out{jobs}"
        argv = ["sweep", *map(str, scripts), "--config", str(BRINGUP), "--out", str(out)]
        argv += ["--vary", "fault_manager.healing_threshold=1,2,4", "--jobs", jobs, "--quiet"]
        argv += ["--vary", "fault_manager.auto_confirm_after_sec=0.0,0.5"]
        assert run(argv, capsys)[0] == 0
        outs.append(out)
    names = sorted(p.name for p in outs[0].iterdir() if p.is_file())
    assert names == sorted(
        f"{t}.{s}" for t in ("runs", "run_codes", "variants", "codes") for s in ("csv", "parquet")
    )
    for name in names:
        first = (outs[0] / name).read_bytes()
        assert all((o / name).read_bytes() == first for o in outs[1:]), name
    assert len((outs[0] / "runs.csv").read_text().splitlines()) == 1 + 6 * 3


def test_a_budget_gives_a_verdict_per_row_and_exit_1(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bag = ROOT / "sample_bags" / "nav2_mission_mcap"
    out = tmp_path / "out"
    argv = ["sweep", str(bag), "--config", str(NAV2 / "fault_manager.yaml"), "--out", str(out)]
    argv += ["--budget", str(BUDGETS / "nav2_mission_fail.yaml"), "--jobs", "1"]
    status, text, _ = run([*argv, "--vary", "fault_manager.confirmation_threshold=-1,-2"], capsys)
    assert status == 1
    assert " over" in text
    rows = (out / "runs.csv").read_text().splitlines()
    assert all(",fail,no critical fault;" in row or "fail" in row for row in rows[1:])


def test_an_unreadable_input_fails_its_rows_only(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    good = flapping(tmp_path / "good.jsonl")
    bad = write_script(tmp_path / "bad.jsonl", ["{not json"])
    out = tmp_path / "out"
    argv = ["sweep", str(good), str(bad), "--out", str(out), "--jobs", "1"]
    status, text, _ = run([*argv, "--vary", "fault_manager.healing_enabled=true,false"], capsys)
    assert status == 0
    assert "not replayed:" in text
    rows = (out / "runs.csv").read_text().splitlines()[1:]
    assert [r.split(",")[0] for r in rows] == ["v01", "v02", "v01", "v02"]
    assert all(str(bad) in r for r in rows[2:])
    assert all(r.endswith(",,,0,") for r in rows[:2])


def test_outputs_may_not_overwrite_an_input(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    script = flapping(tmp_path / "wifi.jsonl")
    argv = ["sweep", str(script), "--vary", "fault_manager.healing_threshold=1", "--html"]
    status, _, err = run([*argv, str(script)], capsys)
    assert status == 2
    assert "--html" in err
    assert script.read_text().startswith("{")


def test_an_unwritable_page_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    script = flapping(tmp_path / "wifi.jsonl")
    (tmp_path / "a-file").write_text("")  # a missing folder is made; a file in its way is not
    page = tmp_path / "a-file" / "sub" / "sweep.html"
    argv = ["sweep", str(script), "--vary", "fault_manager.healing_threshold=1", "--jobs", "1"]
    status, _, err = run([*argv, "--html", str(page), "--quiet"], capsys)
    assert status == 2
    assert err.startswith(f"medkit-replay: error: {page}: cannot write the page")
    assert err.count("\n") == 1


def test_a_damaged_input_is_swept_as_far_as_it_reads_and_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    whole = (ROOT / "sample_bags" / "nav2_mission_mcap" / "nav2_mission_mcap.mcap").read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(whole[: len(whole) // 2])
    out = tmp_path / "out"
    argv = ["sweep", str(cut), "--out", str(out), "--jobs", "1", "--quiet"]
    assert run([*argv, "--vary", "fault_manager.healing_enabled=true,false"], capsys)[0] == 0
    header, *rows = (out / "runs.csv").read_text().splitlines()
    warnings = header.split(",").index("input_warnings")
    assert len(rows) == 2
    assert all(int(row.split(",")[warnings]) >= 1 for row in rows)
    assert all(row.endswith(",") for row in rows)  # no error: the readable part was swept


def test_a_carriage_return_in_a_cell_cannot_break_a_row(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    script = flapping(tmp_path / "we\rird.jsonl")
    out = tmp_path / "out"
    argv = ["sweep", str(script), "--out", str(out), "--jobs", "1", "--quiet"]
    assert run([*argv, "--vary", "fault_manager.healing_threshold=1,2"], capsys)[0] == 0
    with (out / "runs.csv").open(newline="") as stream:
        rows = list(csv.reader(stream))
    assert len(rows) == 3
    assert all(row[2] == str(script) for row in rows[1:])


def test_the_command_line_starts_without_pandas_or_pyarrow() -> None:
    heavy = "('pandas', 'pyarrow')"
    code = f"import sys, medkit_replay.cli; print([m for m in {heavy} if m in sys.modules])"
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    assert out.stdout.strip() == "[]"
