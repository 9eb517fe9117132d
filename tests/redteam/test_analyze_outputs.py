"""Red team, analyze: an output never lands on a recording or a config, a report is whole or
absent, and standard output that closes or fills never changes a verdict or shows a traceback.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.checks.support import NAV2, mission, write_budget
from tests.redteam.support import assert_one_line_error, run_limited, tree_listing

ROOT = Path(__file__).resolve().parents[2]
SAMPLE = ROOT / "sample_bags" / "nav2_mission_mcap"
RULES = ROOT / "rules" / "nav2"


def hashes(root: Path) -> dict[str, str]:
    """Every file under ``root`` with its SHA-256: the bytes, not only sizes and times."""
    return {
        str(path.relative_to(root)): hashlib.sha256(path.read_bytes()).hexdigest()
        for path in sorted(root.rglob("*"))
        if path.is_file()
    }


@pytest.fixture
def workspace(tmp_path: Path) -> Path:
    """A bag folder, a script, and the Nav2 configs (which name a correlation and a thresholds
    file) copied into one folder, as a user's working directory looks."""
    shutil.copytree(SAMPLE, tmp_path / "bag")
    for name in ("fault_manager.yaml", "correlation.yaml", "entity_thresholds.yaml"):
        shutil.copy(RULES / name, tmp_path / name)
    mission(tmp_path, "run.jsonl")
    return tmp_path


BAG_FILE = "bag/nav2_mission_mcap.mcap"
CASES = [
    # (option, target relative to the workspace, input the message names)
    ("--json", BAG_FILE, "is inside the input bag"),
    ("--json", "run.jsonl", "is the input run.jsonl"),
    ("--html", "bag/metadata.yaml", "is inside the input bag"),
    ("--mcap", BAG_FILE, "is inside the input bag"),
    ("--csv", "bag", "is the input bag"),
    ("--csv", "bag/tables", "is inside the input bag"),
    ("--parquet", "bag", "is the input bag"),
    ("--json", "fault_manager.yaml", "is the input fault_manager.yaml"),
    ("--html", "correlation.yaml", "is the input correlation.yaml"),
    ("--mcap", "entity_thresholds.yaml", "is the input entity_thresholds.yaml"),
]


@pytest.mark.parametrize(("option", "target", "needle"), CASES)
def test_an_output_over_an_input_or_a_config_is_refused(
    workspace: Path, option: str, target: str, needle: str
) -> None:
    before = hashes(workspace)
    listing = tree_listing(workspace)
    outcome = run_limited(
        ["analyze", "bag", "run.jsonl", "--config", "fault_manager.yaml", option, target],
        cwd=workspace,
        timeout=120,
    )
    line = assert_one_line_error(outcome, option, needle, "nothing was written")
    assert line.startswith(f"medkit-replay: error: {target}: ")
    assert hashes(workspace) == before
    assert tree_listing(workspace) == listing


def test_links_to_an_input_are_seen_through(workspace: Path) -> None:
    (workspace / "soft.mcap").symlink_to(workspace / BAG_FILE)
    os.link(workspace / "run.jsonl", workspace / "hard.json")
    before = hashes(workspace)
    for option, target in (("--json", "soft.mcap"), ("--html", "hard.json")):
        outcome = run_limited(
            ["analyze", "bag", "run.jsonl", option, target], cwd=workspace, timeout=120
        )
        assert_one_line_error(outcome, option, "refusing to write over a recording")
    assert hashes(workspace) == before


def test_a_report_too_large_for_the_disk_leaves_the_old_report(workspace: Path) -> None:
    """Past the file-size limit the write fails with one line; the earlier report is kept
    byte for byte and no temporary file is left beside it."""
    out = workspace / "out"
    out.mkdir()
    (out / "report.json").write_text('{"old": true}\n', encoding="utf-8")
    outcome = run_limited(
        ["analyze", "bag", "--config", "fault_manager.yaml", "--json", out / "report.json"],
        file_size=4096,
        cwd=workspace,
        timeout=120,
    )
    assert_one_line_error(outcome, "report.json", "cannot write report")
    assert sorted(p.name for p in out.iterdir()) == ["report.json"]
    assert (out / "report.json").read_text(encoding="utf-8") == '{"old": true}\n'


def test_a_written_report_keeps_the_old_file_mode(workspace: Path) -> None:
    target = workspace / "report.json"
    target.write_text("{}", encoding="utf-8")
    target.chmod(0o644)
    outcome = run_limited(["analyze", "run.jsonl", "--json", target, "--quiet"], cwd=workspace)
    assert outcome.status == 0, outcome.stderr
    assert target.stat().st_mode & 0o777 == 0o644
    assert json.loads(target.read_text(encoding="utf-8"))["schema"] == "medkit-replay/report/v1"


def _into_a_closed_pipe(argv: list[str], cwd: Path) -> tuple[int, str]:
    """Run the CLI with its standard output a pipe whose reader is already gone (as after
    ``| head``): every write gets EPIPE. Returns the status and the standard error."""
    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        done = subprocess.run(
            [sys.executable, "-m", "medkit_replay.cli", *argv],
            stdout=write_end,
            stderr=subprocess.PIPE,
            cwd=cwd,
            timeout=120,
            check=False,
        )
    finally:
        os.close(write_end)
    return done.returncode, done.stderr.decode("utf-8", "replace")


@pytest.mark.parametrize("extra", [["--json", "-", "--quiet"], [], ["--json", "-"]])
def test_a_closed_pipe_ends_the_output_quietly(workspace: Path, extra: list[str]) -> None:
    status, stderr = _into_a_closed_pipe(
        ["analyze", "bag", "--config", "fault_manager.yaml", *extra], workspace
    )
    assert status == 0, stderr
    assert "Error" not in stderr and "error" not in stderr, stderr


def test_a_closed_pipe_still_writes_the_other_outputs(workspace: Path) -> None:
    status, stderr = _into_a_closed_pipe(
        ["analyze", "run.jsonl", "--json", "-", "--html", "r.html", "--quiet"], workspace
    )
    assert status == 0, stderr
    assert (workspace / "r.html").stat().st_size > 0


def test_a_closed_pipe_never_turns_a_failed_check_into_a_pass(workspace: Path) -> None:
    failing = write_budget(workspace, "- name: no estop\n  never_confirm: ['ESTOP']")
    status, stderr = _into_a_closed_pipe(
        ["check", "run.jsonl", "--budget", str(failing), "--config", str(NAV2), "--github"],
        workspace,
    )
    assert status == 1, stderr
    assert "Traceback" not in stderr and "error" not in stderr, stderr
    passing = write_budget(workspace, "- never_confirm: ['NOTHING_*']")
    status, stderr = _into_a_closed_pipe(
        ["check", "run.jsonl", "--budget", str(passing), "--config", str(NAV2)], workspace
    )
    assert status == 0, stderr


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
@pytest.mark.parametrize(
    ("extra", "what"), [(["--json", "-", "--quiet"], "the report"), ([], "the summary")]
)
def test_a_full_standard_output_is_one_line(workspace: Path, extra: list[str], what: str) -> None:
    with Path("/dev/full").open("wb") as full:
        done = subprocess.run(
            [sys.executable, "-m", "medkit_replay.cli", "analyze", "run.jsonl", *extra],
            stdout=full,
            stderr=subprocess.PIPE,
            cwd=workspace,
            timeout=120,
            check=False,
        )
    stderr = done.stderr.decode("utf-8", "replace")
    assert done.returncode == 2
    assert stderr.splitlines() == [
        f"medkit-replay: error: cannot write {what} to standard output: No space left on device"
    ]


CLI = [sys.executable, "-m", "medkit_replay.cli"]


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
def test_a_full_standard_output_still_leaves_the_report_written(workspace: Path) -> None:
    """The summary is drawn before the report is written and printed after: a standard output
    that cannot take it is still said after the report and the page are in place."""
    with Path("/dev/full").open("wb") as full:
        done = subprocess.run(
            [*CLI, "analyze", "run.jsonl", "--json", "r.json", "--html", "r.html"],
            stdout=full,
            stderr=subprocess.PIPE,
            cwd=workspace,
            timeout=120,
            check=False,
        )
    assert done.returncode == 2
    assert done.stderr.decode().splitlines() == [
        "medkit-replay: error: cannot write the summary to standard output: No space left on device"
    ]
    assert json.loads((workspace / "r.json").read_text())["faults"]
    assert (workspace / "r.html").stat().st_size > 0


def test_the_diff_is_never_written_over_a_side_or_a_config(workspace: Path) -> None:
    base = workspace / "base.json"
    made = run_limited(["analyze", "run.jsonl", "--json", base, "--quiet"], cwd=workspace)
    assert made.status == 0, made.stderr
    before = hashes(workspace)
    for target in ("base.json", "run.jsonl", "fault_manager.yaml", "correlation.yaml"):
        outcome = run_limited(
            ["diff", "base.json", "run.jsonl", "--config", "fault_manager.yaml", "--json", target],
            cwd=workspace,
        )
        assert_one_line_error(outcome, "--json", "refusing to write over")
    assert hashes(workspace) == before


def test_a_diff_too_large_for_the_disk_leaves_the_old_file(workspace: Path) -> None:
    made = run_limited(["analyze", "run.jsonl", "--json", "base.json", "--quiet"], cwd=workspace)
    assert made.status == 0, made.stderr
    (workspace / "d.json").write_text("old\n", encoding="utf-8")
    outcome = run_limited(
        ["diff", "base.json", "bag", "--json", "d.json", "--quiet"],
        cwd=workspace,
        file_size=512,
    )
    assert_one_line_error(outcome, "d.json", "cannot write diff")
    assert (workspace / "d.json").read_text(encoding="utf-8") == "old\n"
    assert sorted(p.name for p in workspace.iterdir() if p.name.startswith(".")) == []
