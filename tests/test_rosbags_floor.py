"""The oldest release of every dependency pyproject.toml declares still gives the sample reports
byte for byte: they go, from the package index, into a clean virtual environment (nothing shared).

Each dependency is installed at its lower bound (``name==floor``, with its environment markers),
the rest of what they need as pip resolves it; the samples run there, from this source tree, and
here. Nothing is skipped: without the package index the test fails and says so.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.version import Version

ROOT = Path(__file__).resolve().parents[1]
RULES = ["--config", "rules/nav2/fault_manager.yaml", "--config", "rules/nav2/bridges.yaml"]
SAMPLES = ["nav2_mission_mcap", "nav2_mission_sqlite3", "nav2_mission_ros1.bag"]
"""README's first command's recording, then the same mission as rosbag2 sqlite3 and ROS 1."""


def declared() -> list[Requirement]:
    """The package's dependencies (not its extras), as pyproject.toml declares them."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    return [Requirement(text) for text in project["dependencies"]]


def lower_bound(requirement: Requirement) -> str:
    """The version of the requirement's ``>=``."""
    bounds = [spec.version for spec in requirement.specifier if spec.operator == ">="]
    assert len(bounds) == 1, f"{requirement} needs one lower bound"
    return bounds[0]


def floors(requirements: list[Requirement]) -> list[str]:
    """``name==floor`` (with the markers) for each requirement."""
    pinned = []
    for requirement in requirements:
        marker = f"; {requirement.marker}" if requirement.marker is not None else ""
        pinned.append(f"{requirement.name}=={lower_bound(requirement)}{marker}")
    return pinned


def run(python: Path | str, *argv: str, env: dict[str, str] | None = None) -> str:
    done = subprocess.run(
        [str(python), *argv], capture_output=True, text=True, cwd=ROOT, env=env, check=False
    )
    assert done.returncode == 0, f"{argv}: {done.stderr[-3000:]}"
    return done.stdout


def test_every_dependency_declared_is_bounded_below_and_above() -> None:
    for requirement in declared():
        operators = {spec.operator for spec in requirement.specifier}
        assert ">=" in operators and "<" in operators, requirement


def test_the_floors_give_the_same_reports(tmp_path: Path) -> None:
    venv = tmp_path / "venv"
    run(sys.executable, "-m", "venv", str(venv))  # its own site-packages only
    python = venv / "bin" / "python"
    # Nothing of this environment's Python settings; pip's (index, cache) stay.
    clean = {k: v for k, v in os.environ.items() if not k.startswith("PYTHON")}
    clean["PYTHONNOUSERSITE"] = "1"
    pinned = floors(declared())
    install = subprocess.run(
        [str(python), "-m", "pip", "install", "-q", "--only-binary=:all:", *pinned],
        capture_output=True,
        text=True,
        check=False,
        env=clean,
    )
    if install.returncode != 0:
        pytest.fail(
            "pip could not install the declared floors from the package index (this test needs "
            f"it): {' '.join(pinned)}\n{install.stderr[-3000:]}",
            pytrace=False,
        )
    versions = "import importlib.metadata as m, sys; print(m.version(sys.argv[1]))"
    for requirement in declared():
        if requirement.marker is None or requirement.marker.evaluate():
            installed = run(python, "-c", versions, requirement.name, env=clean).strip()
            assert Version(installed) == Version(lower_bound(requirement)), requirement
    source = clean | {"PYTHONPATH": str(ROOT)}  # this source tree beside the floors
    for sample in SAMPLES:
        command = ["-m", "medkit_replay.cli", "analyze", f"sample_bags/{sample}", *RULES, "--quiet"]
        oldest, here = tmp_path / f"{sample}.floor.json", tmp_path / f"{sample}.here.json"
        run(python, *command, "--json", str(oldest), env=source)
        run(sys.executable, *command, "--json", str(here))
        assert oldest.read_bytes() == here.read_bytes(), sample
