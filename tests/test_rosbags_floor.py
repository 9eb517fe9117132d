"""The oldest rosbags that pyproject.toml allows still gives the sample report byte for byte.

That release goes into a throwaway virtual environment (from the package index) that shares
everything else with this one; the sample analysis runs there and here, from the same folder.
"""

from __future__ import annotations

import re
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = [
    "-m",
    "medkit_replay.cli",
    "analyze",
    "sample_bags/nav2_mission_mcap",
    "--config",
    "rules/nav2/fault_manager.yaml",
    "--config",
    "rules/nav2/bridges.yaml",
    "--quiet",
    "--json",
]


def rosbags_floor() -> str:
    """The lower bound of the rosbags range in pyproject.toml."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    (spec,) = [d for d in project["dependencies"] if d.startswith("rosbags")]
    match = re.search(r">=\s*([0-9.]+)", spec)
    assert match is not None, spec
    return match[1]


def run(python: Path | str, *argv: str) -> str:
    return subprocess.run(
        [str(python), *argv], check=True, capture_output=True, text=True, cwd=ROOT
    ).stdout


def test_the_floor_release_gives_the_same_report(tmp_path: Path) -> None:
    floor = rosbags_floor()
    venv = tmp_path / "venv"
    run(sys.executable, "-m", "venv", "--system-site-packages", str(venv))
    python = venv / "bin" / "python"
    run(python, "-m", "pip", "install", "-q", "--no-deps", f"rosbags=={floor}")
    version = "import importlib.metadata as m; print(m.version('rosbags'))"
    assert run(python, "-c", version).strip() == floor
    run(python, *SAMPLE, str(tmp_path / "floor.json"))
    run(sys.executable, *SAMPLE, str(tmp_path / "here.json"))
    assert (tmp_path / "floor.json").read_bytes() == (tmp_path / "here.json").read_bytes()
