"""Every file option makes its folder: check --junit, diff --json and suggest-rules --out write
into folders that do not exist yet, as analyze's outputs do (outputs/atomic.py makes them).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.cli import main
from sample_bags.make_tuning_fleet import FOLDER, write_fleet
from tests.checks.support import NAV2, mission, write_budget

if TYPE_CHECKING:
    import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "nav2_mission.jsonl"
BUDGET = """
- name: few criticals
  max_confirmed: {CRITICAL: 1}
"""


def test_check_junit_into_a_missing_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    junit = tmp_path / "x" / "a" / "j.xml"
    argv = ["check", str(mission(tmp_path)), "--budget", str(write_budget(tmp_path, BUDGET))]
    assert main([*argv, "--config", str(NAV2), "--junit", str(junit)]) == 0, capsys.readouterr()
    assert junit.read_text().startswith("<?xml")


def test_diff_json_into_a_missing_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    report = tmp_path / "r.json"
    assert main(["analyze", str(EXAMPLE), "--config", str(NAV2), "--json", str(report)]) == 0
    target = tmp_path / "x" / "c" / "d.json"
    assert main(["diff", str(report), str(report), "--json", str(target), "--quiet"]) == 0
    assert target.read_text().startswith("{")
    assert "Traceback" not in "".join(capsys.readouterr())


def test_suggest_rules_out_into_a_missing_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    write_fleet(tmp_path)
    fleet = tmp_path / FOLDER
    out = tmp_path / "x" / "rules" / "rules.yaml"
    argv = ["suggest-rules", str(fleet), "--config", str(fleet / "params.yaml"), "--jobs", "1"]
    assert main([*argv, "--out", str(out)]) == 0, capsys.readouterr()
    assert "rules:" in out.read_text()
