"""The evidence example of docs/evidence.md prints what the page shows."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.cli import main

if TYPE_CHECKING:
    import pytest

ROOT = Path(__file__).resolve().parents[2]


def test_the_readme_shows_the_real_summary(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(ROOT)
    monkeypatch.setenv("COLUMNS", "80")
    argv = [
        "analyze",
        "sample_bags/nav2_mission_mcap",
        "--config",
        "rules/nav2/fault_manager.yaml",
        "--config",
        "rules/nav2/bridges.yaml",
        "--config",
        "examples/evidence/capture.yaml",
        "--graph",
        "examples/evidence/nav2_graph.txt",
        "--evidence",
        str(tmp_path / "clips"),
        "--json",
        str(tmp_path / "report.json"),
    ]
    assert main(argv) == 0
    out = capsys.readouterr().out
    printed = out[out.index("Evidence:") :].rstrip("\n")
    readme = (ROOT / "docs" / "evidence.md").read_text(encoding="utf-8")
    shown = readme.split("The summary ends with:\n\n```\n", 1)[1].split("\n```", 1)[0]
    assert printed == shown
    assert len(list((tmp_path / "clips").iterdir())) == 8
