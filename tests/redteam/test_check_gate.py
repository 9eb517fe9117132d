"""Red team, check: an unreadable recording never passes the gate, hostile recorded text never
escapes its line in annotations, the step summary or JUnit, and outputs never land on inputs.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from typing import TYPE_CHECKING

import pytest

from medkit_replay.text import printable, xml_text
from tests.checks.support import NAV2, mission, write_budget
from tests.redteam.support import assert_one_line_error, run_limited, tree_listing

if TYPE_CHECKING:
    from pathlib import Path

PASSING = "- never_confirm: ['NOTHING_*']"
FAILING = "- name: no estop\n  never_confirm: ['ESTOP']"
HOSTILE = "\u061c\u2028\u2029\u202e\u2066\u200f\x1b[31m\x85"
"""Characters that reorder, recolour or break a line in a terminal, a CI log or a web page."""


def unreadable_inputs(tmp_path: Path) -> list[Path]:
    """Recordings that cannot be read at all, each in its own way."""
    garbage = tmp_path / "garbage.mcap"
    garbage.write_bytes(b"not an mcap file at all")
    bad_script = tmp_path / "bad.jsonl"
    bad_script.write_text('{"t_ns": 1, "op": "explode"}\n', encoding="utf-8")
    fifo = tmp_path / "pipe.mcap"
    os.mkfifo(fifo)
    empty_bag = tmp_path / "empty_bag"
    empty_bag.mkdir()
    (empty_bag / "metadata.yaml").write_text("rosbag2_bagfile_information: {}\n")
    far = tmp_path / "far.jsonl"
    far.write_text(
        f'{{"t_ns": {2**63 + 5}, "op": "report", "fault_code": "A", "event_type": "FAILED"}}\n',
        encoding="utf-8",
    )
    return [garbage, bad_script, fifo, empty_bag, far]


@pytest.mark.parametrize("index", range(5))
def test_an_unreadable_recording_fails_the_gate(tmp_path: Path, index: int) -> None:
    budget = write_budget(tmp_path, PASSING)
    good = mission(tmp_path)
    bad = unreadable_inputs(tmp_path)[index]
    junit = tmp_path / "out" / "check.xml"
    junit.parent.mkdir()
    outcome = run_limited(
        ["check", good, bad, "--budget", budget, "--config", NAV2, "--junit", junit, "--github"],
        env={"GITHUB_STEP_SUMMARY": str(tmp_path / "out" / "summary.md")},
        timeout=120,
    )
    assert "Traceback" not in outcome.stderr and "internal error" not in outcome.stderr
    if outcome.status == 0:  # only a recording the reader takes after all may pass
        pytest.fail(f"{bad.name} passed the gate: {outcome.stdout[-2000:]}")
    assert outcome.status == 1, outcome.stderr[-2000:]
    assert "could not be read" in outcome.stdout or "budget exceeded" in outcome.stdout
    root = ET.parse(junit).getroot()
    suites = list(root)
    assert [s.get("name") for s in suites] == [str(good), str(bad)]
    if root.get("errors") == "1":
        (error,) = suites[1].iter("error")
        assert (error.get("message") or "").startswith(str(bad))
        assert "::error title=recording cannot be read" in outcome.stdout
        summary = (tmp_path / "out" / "summary.md").read_text(encoding="utf-8")
        assert "cannot be read" in summary


def test_a_fifo_input_is_refused_not_waited_for(tmp_path: Path) -> None:
    budget = write_budget(tmp_path, PASSING)
    fifo = tmp_path / "pipe.jsonl"
    os.mkfifo(fifo)
    outcome = run_limited(["check", fifo, "--budget", budget], timeout=60)
    assert outcome.status == 1
    assert f"ERROR {fifo}: a FIFO, not a regular file" in outcome.stdout


def test_merged_inputs_fail_when_one_cannot_be_read(tmp_path: Path) -> None:
    budget = write_budget(tmp_path, PASSING)
    garbage = tmp_path / "garbage.mcap"
    garbage.write_bytes(b"x")
    outcome = run_limited(
        ["check", mission(tmp_path), garbage, "--merge", "--budget", budget, "--config", NAV2],
        timeout=120,
    )
    assert outcome.status == 1
    assert "check failed: 1 of 1 run could not be read" in outcome.stdout


def test_usage_budget_and_config_problems_stay_exit_2(tmp_path: Path) -> None:
    budget = write_budget(tmp_path, PASSING)
    script = mission(tmp_path)
    outcome = run_limited(["check", script, "--budget", budget, "--config", tmp_path / "no.yaml"])
    assert_one_line_error(outcome, "no.yaml", "not found")
    outcome = run_limited(["check", tmp_path / "absent.mcap", "--budget", budget])
    assert_one_line_error(outcome, "absent.mcap: input not found")


def test_outputs_never_land_on_inputs(tmp_path: Path) -> None:
    budget = write_budget(tmp_path, FAILING)
    script = mission(tmp_path)
    before = tree_listing(tmp_path)
    for option, target in (("--junit", script), ("--junit", budget), ("--junit", NAV2)):
        outcome = run_limited(
            ["check", script, "--budget", budget, "--config", NAV2, option, target]
        )
        assert_one_line_error(outcome, option, "refusing to write over")
    outcome = run_limited(
        ["check", script, "--budget", budget, "--config", NAV2, "--github"],
        env={"GITHUB_STEP_SUMMARY": str(script)},
    )
    assert_one_line_error(outcome, "GITHUB_STEP_SUMMARY", "refusing to write over")
    assert tree_listing(tmp_path) == before


def test_hostile_text_stays_on_its_line_everywhere(tmp_path: Path) -> None:
    """A recording named with bidi controls, U+061C, U+2028/9, ESC and NEL: never raw in the
    terminal output, the annotations, the step summary or the JUnit file."""
    budget = write_budget(tmp_path, FAILING)
    odd = tmp_path / f"run{HOSTILE}.jsonl"
    mission(tmp_path).rename(odd)
    junit = tmp_path / "check.xml"
    summary = tmp_path / "summary.md"
    outcome = run_limited(
        ["check", odd, "--budget", budget, "--config", NAV2, "--junit", junit, "--github"],
        env={"GITHUB_STEP_SUMMARY": str(summary)},
    )
    assert outcome.status == 1, outcome.stderr
    written = {
        "stdout": outcome.stdout,
        "summary": summary.read_text(encoding="utf-8"),
        "junit": junit.read_text(encoding="utf-8"),
    }
    for where, text in written.items():
        for char in HOSTILE.replace("[31m", ""):
            assert char not in text, (where, hex(ord(char)))
    annotations = [line for line in outcome.stdout.splitlines() if line.startswith("::")]
    assert annotations and all("\\u202e" in line for line in annotations)
    assert "\\u061c" in written["junit"] and "\\u2028" in written["summary"]


def test_text_helpers_escape_every_reordering_character() -> None:
    for char in ("\u061c", "\u2028", "\u2029", "\u200e", "\u200f", "\u202a", "\u2069", "\x85"):
        assert char not in printable(f"a{char}b")
        assert char not in xml_text(f"a{char}b")
    assert printable("a\ud800b") == "a\\ud800b"  # a lone surrogate cannot be printed
    assert xml_text("line 1\nline 2\té") == "line 1\nline 2\té"  # the rest is kept


def test_a_step_summary_that_cannot_be_appended_whole_is_not_appended(tmp_path: Path) -> None:
    """Past the file-size limit the append fails with one line and the file keeps its length."""
    budget = write_budget(tmp_path, FAILING)
    summary = tmp_path / "summary.md"
    summary.write_bytes(b"# earlier step\n" * 100)
    before = summary.read_bytes()
    outcome = run_limited(
        ["check", mission(tmp_path), "--budget", budget, "--config", NAV2, "--github"],
        env={"GITHUB_STEP_SUMMARY": str(summary)},
        file_size=len(before) + 64,  # room for a few bytes, not for the whole summary
    )
    assert_one_line_error(outcome, "cannot append the step summary")
    assert summary.read_bytes() == before
