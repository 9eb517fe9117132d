"""``medkit-replay fleet`` end to end: a generated fleet of 54 recordings, determinism, --jobs,
budgets, the sample bags, and every exit status."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from medkit_replay.cli import main
from medkit_replay.fleet.report import FILES
from tests.fleet.fleet_support import (
    BRINGUP,
    NAV2,
    ROOT,
    SAMPLES,
    Fleet,
    build_fleet,
    episode,
    write_script,
)

if TYPE_CHECKING:
    from collections.abc import Iterator

BRIDGES = ROOT / "rules" / "nav2" / "bridges.yaml"
PASSING_BUDGET = ROOT / "rules" / "budgets" / "nav2_mission_pass.yaml"
FLEET_SECONDS = 30.0
"""The most the three runs over the generated fleet may take together."""


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    status = main(argv)
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return status, out, err


def read_rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="", encoding="utf-8") as stream:
        return list(csv.DictReader(stream))


def files(folder: Path) -> dict[str, bytes]:
    return {name: (folder / name).read_bytes() for name in FILES}


@pytest.fixture(scope="module")
def big_fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Fleet, Path, float]]:
    """54 recordings (44 scripts, 7 bags, 3 broken), replayed three times: --jobs 2 twice,
    --jobs 1 once, into out_a, out_b and out_c. Yields the fleet, the folder holding the
    outputs, and how long the three replays took together."""
    base = tmp_path_factory.mktemp("big")
    fleet = build_fleet(base / "fleet")
    args = ["fleet", str(fleet.root), "--config", str(BRINGUP), "--quiet"]
    start = time.perf_counter()
    statuses = [
        main([*args, "--jobs", "2", "--out", str(base / "out_a")]),
        main([*args, "--jobs", "2", "--out", str(base / "out_b")]),
        main([*args, "--jobs", "1", "--out", str(base / "out_c")]),
    ]
    elapsed = time.perf_counter() - start
    assert statuses == [0, 0, 0]
    yield fleet, base, elapsed


def test_big_fleet_every_recording_has_a_row(big_fleet: tuple[Fleet, Path, float]) -> None:
    fleet, base, elapsed = big_fleet
    assert len(fleet.recordings) >= 50
    assert elapsed < FLEET_SECONDS
    rows = read_rows(base / "out_a" / "runs.csv")
    assert sorted(r["path"] for r in rows) == sorted(str(p) for p in fleet.recordings)
    kinds = {r["kind"] for r in rows}
    assert kinds == {"script", "rosbag2", "mcap"}
    failed = {r["path"]: r["error"] for r in rows if r["error"]}
    assert sorted(failed) == sorted(str(p) for p in fleet.broken)
    assert all(error.startswith(path) for path, error in failed.items())
    replayed = [r for r in rows if not r["error"]]
    assert all(int(r["messages"]) > 0 for r in replayed if r["kind"] != "rosbag2")
    assert any(r["path"].endswith("nav2_mission_mcap") and r["messages"] == "626" for r in rows)


def test_big_fleet_statistics(big_fleet: tuple[Fleet, Path, float]) -> None:
    _, base, _ = big_fleet
    runs = json.loads((base / "out_a" / "runs.json").read_text(encoding="utf-8"))
    codes = json.loads((base / "out_a" / "codes.json").read_text(encoding="utf-8"))
    replayed = [r for r in runs if r["error"] is None]
    for code in codes:
        confirming = [r for r in replayed if code["fault_code"] in r["confirmed_codes"]]
        assert code["runs_confirmed"] == len(confirming)
        assert code["share_of_runs"] == pytest.approx(len(confirming) / len(replayed))
    by_code = {c["fault_code"]: c for c in codes}
    # Script heals take 2, 4 or 8 s (tests/fleet/fleet_support.py: mission).
    for code in ("MOTOR_OVERHEAT", "BATTERY_LOW", "WIFI_WEAK"):
        assert 2.0 <= by_code[code]["mean_time_to_heal_s"] <= 8.0
        assert by_code[code]["median_time_to_heal_s"] in (2.0, 3.0, 4.0, 6.0, 8.0)
    assert [c["runs_confirmed"] for c in codes] == sorted(
        (c["runs_confirmed"] for c in codes), reverse=True
    )


def test_big_fleet_output_is_the_same_bytes_twice(big_fleet: tuple[Fleet, Path, float]) -> None:
    _, base, _ = big_fleet
    assert files(base / "out_a") == files(base / "out_b")


def test_big_fleet_jobs_1_and_2_give_the_same_output(
    big_fleet: tuple[Fleet, Path, float],
) -> None:
    _, base, _ = big_fleet
    assert files(base / "out_a") == files(base / "out_c")


def test_summary_and_no_progress_off_a_terminal(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    write_script(tmp_path / "in" / "a.jsonl", [line for _, line in episode("A", 1.0, 4.0)])
    broken = tmp_path / "in" / "broken.mcap"
    broken.write_bytes(b"x")
    status, out, err = run(
        ["fleet", str(tmp_path / "in"), "--config", str(BRINGUP), "--out", str(tmp_path / "o")],
        capsys,
    )
    assert status == 0  # a broken recording is reported, not fatal
    assert err == ""  # no progress bar off a terminal
    flat = "".join(out.split())  # long paths are wrapped at 80 columns
    assert "fleet: 2 recordings, 1 replayed, 1 failed" in out
    assert "".join(f"{broken}: not an MCAP file".split()) in flat
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == sorted(FILES)


def test_quiet_prints_nothing(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    write_script(tmp_path / "in" / "a.jsonl", [line for _, line in episode("A", 1.0, 4.0)])
    out_dir = str(tmp_path / "o")
    status, out, err = run(["fleet", str(tmp_path / "in"), "--quiet", "--out", out_dir], capsys)
    assert (status, out, err) == (0, "", "")


def test_default_out_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    write_script(tmp_path / "in" / "a.jsonl", [line for _, line in episode("A", 1.0, 4.0)])
    monkeypatch.chdir(tmp_path)
    status, out, _ = run(["fleet", "in", "--jobs", "1"], capsys)
    assert status == 0
    assert sorted(p.name for p in (tmp_path / "fleet-report").iterdir()) == sorted(FILES)
    assert "report: fleet-report/" in out
    assert read_rows(tmp_path / "fleet-report" / "runs.csv")[0]["path"] == "in/a.jsonl"


def test_sample_bags_with_budget(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The example of the README and docs/commands/fleet.md: the mission passes the budget, the
    service-call recording (BATTERY_LOW confirms) does not: exit 1."""
    status, out, _ = run(
        [
            "fleet",
            str(SAMPLES),
            "--config",
            str(NAV2),
            "--config",
            str(BRIDGES),
            "--budget",
            str(PASSING_BUDGET),
            "--out",
            str(tmp_path / "r"),
        ],
        capsys,
    )
    assert status == 1
    rows = read_rows(tmp_path / "r" / "runs.csv")
    assert [(Path(r["path"]).name, r["budget"]) for r in rows] == [
        ("nav2_mission_mcap", "pass"),
        ("nav2_mission_ros1.bag", "pass"),
        ("nav2_mission_sqlite3", "pass"),
        ("service_calls.mcap", "fail"),
    ]
    assert "no e-stop, no battery fault" in rows[3]["budget_failures"]
    assert "budget: 1 fail, 3 pass" in out
    assert "over budget:" in out


def test_budget_that_holds_exits_0(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    write_script(tmp_path / "in" / "a.jsonl", [line for _, line in episode("A", 1.0, 4.0)])
    budget = tmp_path / "budget.yaml"
    budget.write_text("version: 1\nrules:\n  - never_confirm: ['MOTOR_*']\n")
    status, _, _ = run(
        ["fleet", str(tmp_path / "in"), "--budget", str(budget), "--out", str(tmp_path / "o")],
        capsys,
    )
    assert status == 0
    assert read_rows(tmp_path / "o" / "runs.csv")[0]["budget"] == "pass"


def test_console_script_exit_status(tmp_path: Path) -> None:
    write_script(tmp_path / "in" / "a.jsonl", [line for _, line in episode("MOTOR_HOT", 1.0, None)])
    budget = tmp_path / "budget.yaml"
    budget.write_text("version: 1\nrules:\n  - never_confirm: ['MOTOR_*']\n")
    done = subprocess.run(
        [sys.executable, "-m", "medkit_replay.cli", "fleet", "in", "--budget", "budget.yaml"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        check=False,
        timeout=120,
    )
    assert done.returncode == 1, done.stderr
    assert "over budget:" in done.stdout and done.stderr == ""


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["fleet", "{tmp}/nope"], "{tmp}/nope: input folder not found"),
        (["fleet", "{tmp}/empty"], "{tmp}/empty: no recording found"),
        (["fleet", "{tmp}/in", "--config", "{tmp}/missing.yaml"], "missing.yaml"),
        (["fleet", "{tmp}/in", "--budget", "{tmp}/missing.yaml"], "budget file not found"),
        (["fleet", "{tmp}/in", "--budget", "{tmp}/bad_budget.yaml"], "bad_budget.yaml:1: "),
        (["fleet", "{tmp}/in", "--jobs", "0"], "--jobs"),
        (["fleet", "{tmp}/in", "--jobs", "2", "--dask", "tcp://x:1"], "cannot be used together"),
        (["fleet", "{tmp}/in", "--out", "{tmp}/a_file"], "a_file"),
        (["fleet"], "Missing argument"),
    ],
)
def test_bad_usage_exits_2_with_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str], message: str
) -> None:
    (tmp_path / "empty").mkdir()
    write_script(tmp_path / "in" / "a.jsonl", [line for _, line in episode("A", 1.0, 4.0)])
    (tmp_path / "a_file").write_text("x")
    (tmp_path / "bad_budget.yaml").write_text("version: 7\nrules: []\n")
    tmp = str(tmp_path)
    status, out, err = run([a.replace("{tmp}", tmp) for a in argv], capsys)
    assert status == 2
    assert out == ""
    assert err.count("\n") == 1 and err.startswith("medkit-replay: error: ")
    assert message.replace("{tmp}", tmp) in err


def test_help_names_every_option(capsys: pytest.CaptureFixture[str]) -> None:
    status, out, _ = run(["fleet", "--help"], capsys)
    assert status == 0
    for option in ("--config", "--budget", "--jobs", "--dask", "--out", "--quiet"):
        assert option in out
