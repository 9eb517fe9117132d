"""One table of exit statuses (docs/exit-statuses.md): every command's --help says what it
exits with in its terms, none contradicts the table, and the commands do what they say.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from medkit_replay.cli import cli, main
from tests.checks.support import BUDGETS, NAV2

ROOT = Path(__file__).resolve().parents[1]
GATES = {"check", "fleet", "sweep"}
"""Where a recording that cannot be read is a failed check (1), never a pass."""
FAILED_CHECKS = GATES | {"diff", "validate"}
"""The commands that exit 1 at all (diff: the reports differ; validate: warnings)."""
UNREADABLE = re.compile(r"cannot be read|unreadable")


def statuses(help_text: str) -> dict[str, str]:
    """The help's "Exit status: 0 ...; 1 ...; 2 ..." sentence, by status."""
    flat = " ".join(help_text.split())
    match = re.search(r"Exit status: ([^.]*)\.", flat)
    assert match is not None, flat
    parts = match[1].split("; ")
    assert all(re.match(r"[012] ", part) for part in parts), parts
    return {part[0]: part[2:] for part in parts}


def help_of(*command: str) -> str:
    done = CliRunner().invoke(cli, [*command, "--help"], terminal_width=100)
    assert done.exit_code == 0, done.output
    return done.output


def test_the_group_help_states_the_table() -> None:
    said = statuses(help_of())
    assert said == {
        "0": "pass",
        "1": "a check failed",
        "2": "usage or input error -- except that in check, fleet --budget, sweep --budget and "
        "the pytest plugin a recording that cannot be read, or is empty, is a failed check (1)",
    }


@pytest.mark.parametrize("name", sorted(cli.commands))
def test_each_help_follows_the_table(name: str) -> None:
    said = statuses(help_of(name))
    assert "0" in said and "2" in said and "usage" in said["2"], said
    assert ("1" in said) == (name in FAILED_CHECKS), said
    if name in GATES:
        assert UNREADABLE.search(said["1"]) and not UNREADABLE.search(said["2"]), said
        assert "--budget" in said["1"] or name == "check", said
    elif "1" in said:
        assert not UNREADABLE.search(said["1"]), said
    if name not in GATES and name != "suggest-rules":
        assert UNREADABLE.search(said["2"]) or "cannot be followed" in said["2"], said


def test_every_command_is_checked() -> None:
    assert set(cli.commands) == {
        "analyze",
        "check",
        "diff",
        "explain",
        "fleet",
        "follow",
        "serve",
        "suggest-rules",
        "sweep",
        "validate",
    }


def test_one_table_in_the_docs() -> None:
    page = (ROOT / "docs" / "exit-statuses.md").read_text(encoding="utf-8")
    section = page.split("# Exit statuses\n", 1)[1].split("\n## ", 1)[0]
    rows = [line for line in section.splitlines() if re.match(r"\| `[012]` \|", line)]
    assert [row[3] for row in rows] == ["0", "1", "2"]
    assert "`check`, `fleet --budget`, `sweep --budget` and the pytest plugin" in section
    assert "warnings in the files checked (`validate`" in rows[1]
    budgets = (ROOT / "docs" / "budgets.md").read_text(encoding="utf-8")
    assert "(exit-statuses.md)" in budgets
    assert not re.search(r"^\| `[012]` \|", budgets, re.MULTILINE)  # linked, not repeated
    assert "an unreadable input" not in budgets


@pytest.fixture
def unreadable(tmp_path: Path) -> Path:
    """A folder holding one file named like an MCAP recording that is not one."""
    folder = tmp_path / "runs"
    folder.mkdir()
    (folder / "run.mcap").write_bytes(b"\x89MCAP0\r\n" + bytes(range(256)) * 4)
    return folder


def command(name: str, runs: Path, tmp_path: Path, *, budget: bool) -> list[str]:
    recording, config = str(runs / "run.mcap"), ["--config", str(NAV2)]
    gate = ["--budget", str(BUDGETS / "nav2_mission_pass.yaml")] if budget else []
    out = ["--out", str(tmp_path / "out")]
    vary = ["--vary", "fault_manager.confirmation_threshold=-1,-2"]
    return {
        "analyze": ["analyze", recording, *config, "--quiet"],
        "explain": ["explain", recording, "ESTOP", *config, "--quiet"],
        "diff": ["diff", recording, recording, *config, "--quiet"],
        "check": ["check", recording, *gate, *config],
        "fleet": ["fleet", str(runs), *config, *gate, "--quiet", "--jobs", "1", *out],
        "sweep": ["sweep", recording, *config, *vary, *gate, "--quiet", "--jobs", "1", *out],
    }[name]


@pytest.mark.parametrize(
    ("name", "budget", "expected"),
    [
        ("analyze", False, 2),
        ("explain", False, 2),
        ("diff", False, 2),
        ("check", True, 1),
        ("fleet", True, 1),
        ("sweep", True, 1),
        ("fleet", False, 0),
        ("sweep", False, 0),
    ],
)
def test_an_unreadable_recording_exits_as_the_table_says(
    name: str,
    budget: bool,
    expected: int,
    unreadable: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(command(name, unreadable, tmp_path, budget=budget)) == expected
    err = capsys.readouterr().err
    assert "Traceback" not in err and "internal error" not in err, err
