"""The README's test command is the one .ci/run runs: the same steps in the same order."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def readme_steps() -> list[str]:
    """The steps of the README's command that starts with ``pip install -e``."""
    lines = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    commands = [line for line in lines if line.startswith("pip install -e ")]
    assert len(commands) == 1, "README.md: one test command expected"
    return commands[0].split(" && ")


def ci_steps() -> list[str]:
    """The commands .ci/run runs, as a user would type them (pip's -q and exits left out)."""
    steps = []
    for line in (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines():
        line = line.removesuffix(" || exit 1")
        if line.startswith(("python -m pip install", "ruff", "mypy", "mkdocs", "python -m pytest")):
            steps.append(line.replace("python -m pip install -q ", "pip install "))
    return steps


def test_the_readme_runs_what_ci_runs() -> None:
    assert readme_steps() == ci_steps()
    assert "mkdocs build --strict" in readme_steps()
    assert readme_steps()[0] == "pip install -e '.[test,docs]'"
