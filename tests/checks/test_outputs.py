"""The verdict outputs on hostile text: terminal, JUnit XML, workflow commands, step summary."""

from __future__ import annotations

import io
import xml.etree.ElementTree as ET
from typing import TYPE_CHECKING

from junitparser import JUnitXml

from medkit_replay.checks.budget_file import parse_budget
from medkit_replay.checks.evaluate import CheckRun, Verdict
from medkit_replay.checks.facts import Offender
from medkit_replay.checks.github import (
    escape_data,
    escape_property,
    markdown,
    step_summary,
    workflow_commands,
)
from medkit_replay.checks.junit import failure_message, junit_element, write_junit
from medkit_replay.checks.terminal import conclusion, print_conclusion, print_run
from medkit_replay.text import printable, xml_text
from tests.checks.support import budget_text
from tests.outputs.scripts import FakeTTY

if TYPE_CHECKING:
    from pathlib import Path

EVIL = "[bold red]X[/] \x1b[2J%0A 50% a,b: c\r\n::warning::y <script>|*z*</script> \u202e @all"


def hostile_run(offenders: int = 1) -> CheckRun:
    budget = parse_budget(
        budget_text("- name: 'rule [b]x[/b] <i>'\n  never_confirm: ['*']\n- allow_confirm: ['*']"),
        "budgets/ci.yaml",
    )
    failed = Verdict(
        budget.rules[0],
        False,
        f"message {EVIL}",
        tuple(Offender(f"CODE_{n}", 10 + n, 2_000_000_000 + n, EVIL) for n in range(offenders)),
    )
    held = Verdict(budget.rules[1], True, "all fine")
    return CheckRun(
        label=f"run {EVIL}",
        inputs=(f"run {EVIL}",),
        budget=budget,
        verdicts=(failed, held),
        warnings=(f"warning {EVIL}",),
    )


def test_printable_and_xml_text() -> None:
    assert printable("a\nb\tc\x1b[0m\u202ed\x00") == "a b c\\x1b[0m\\u202ed\\x00"
    assert xml_text("a\x1b\x00\ud800b\n\t<&>") == "a\\x1b\\x00\\ud800b\n\t<&>"


def test_plain_terminal_output_is_literal_and_unwrapped() -> None:
    stream = io.StringIO()
    print_run(hostile_run(), stream)
    out = stream.getvalue()
    assert "\x1b" not in out and "\u202e" not in out and "\r" not in out
    lines = out.splitlines()
    assert lines[0].startswith("check run [bold red]X[/] \\x1b[2J%0A 50% a,b: c  ::warning::y")
    assert lines[0].endswith("against ci.yaml: 1 of 2 rules failed")
    assert lines[1].startswith("FAIL rule [b]x[/b] <i>: message [bold red]X[/]")
    assert lines[2].startswith("     - CODE_0 at 2.000 s: [bold red]X[/] \\x1b[2J")
    assert lines[3] == "PASS only allowed codes confirm: *: all fine"
    assert lines[4].startswith("!    warning [bold red]X[/]")
    assert all(line == line.rstrip() for line in lines)


def test_terminal_output_in_colour_keeps_recorded_text_literal() -> None:
    stream = FakeTTY()
    print_run(hostile_run(offenders=12), stream)
    out = stream.getvalue()
    assert "\x1b[" in out  # colour
    assert "\x1b[2J" not in out and "\u202e" not in out
    assert "[bold red]X[/]" in out
    assert "... and 2 more" in out
    assert out.count("CODE_") == 10


def test_conclusion_lines() -> None:
    run = hostile_run()
    assert conclusion([run]).plain == "budget exceeded: 1 rule verdict failed in 1 of 1 run"
    passing = CheckRun(run.label, run.inputs, run.budget, run.verdicts[1:])
    assert conclusion([passing, passing]).plain == "budget holds: 1 rule passed on 2 runs"
    stream = io.StringIO()
    print_conclusion([passing], stream)
    assert stream.getvalue() == "budget holds: 1 rule passed on 1 run\n"


def test_workflow_command_escaping() -> None:
    assert escape_data("50%\r\nx:y,z") == "50%25%0D%0Ax:y,z"
    assert escape_property("50%\r\nx:y,z") == "50%25%0D%0Ax%3Ay%2Cz"
    commands = workflow_commands([hostile_run(offenders=25)])
    assert len(commands) == 2
    error, warning = commands
    assert all("\n" not in c and "\r" not in c for c in commands)
    assert error.startswith("::error file=budgets/ci.yaml,line=3,title=fault budget exceeded%3A ")
    head, message = error.split("::", 2)[1:]
    assert ":" not in head.split("title=", 1)[1]  # properties: ':' and ',' encoded
    # Recorded text: printable first (CR LF are spaces, ESC an escape), then %-encoded; a
    # recorded "::warning::" stays data, since a command only starts at a line's start.
    assert "\x1b" not in error and "\u202e" not in error
    assert "\\x1b[2J%250A 50%25 a,b: c  ::warning::y <script>" in message
    assert message.count("%0ACODE_") == 20
    assert message.endswith("%0A... and 5 more")
    assert warning.startswith("::warning title=medkit-replay warning (run [bold red]X[/] ")
    assert warning.endswith(
        "::warning [bold red]X[/] \\x1b[2J%250A 50%25 a,b: c  ::warning::y "
        "<script>|*z*</script> \\u202e @all"
    )


def test_markdown_escaping() -> None:
    text = markdown("a|b <script>&x</script> *e* _u_ [l](h) `c` #h :smile: @team \\ \n!")
    assert text == (
        "a\\|b &lt;script&gt;&amp;x&lt;\\/script&gt; \\*e\\* \\_u\\_ \\[l\\]\\(h\\) \\`c\\` "
        "\\#h \\:smile\\: \\@team \\\\  \\!"
    )


def test_step_summary_page() -> None:
    page = step_summary([hostile_run(offenders=25)])
    lines = page.splitlines()
    assert lines[0] == "## medkit-replay check: budget exceeded ❌"
    assert lines[2] == "Budget: ci\\.yaml (budgets\\/ci\\.yaml)"
    assert lines[4].startswith(
        "### ❌ run \\[bold red\\]X\\[\\/\\] \\\\x1b\\[2J\\%0A 50\\% a\\,b\\:"
    )
    assert lines[4].endswith(": 1 of 2 rules failed")
    rows = [line for line in lines if line.startswith("| ")]
    assert rows[0] == "| | rule | verdict |"
    assert rows[2].startswith("| ❌ **fail** | rule \\[b\\]x\\[\\/b\\] &lt;i&gt; | message ")
    assert rows[2].count("<br>• CODE\\_") == 20
    assert rows[2].endswith("<br>• \\.\\.\\. and 5 more |")
    assert rows[3] == "| ✅ pass | only allowed codes confirm\\: \\* | all fine |"
    assert all(row.count(" | ") + 2 == 4 for row in rows[2:])  # no cell split by a recorded '|'
    assert "<script>" not in page and "\r" not in page
    assert next(line for line in lines if line.startswith("- ")).startswith("- ⚠️ warning ")
    assert page.endswith("\n")


def test_junit_of_hostile_text(tmp_path: Path) -> None:
    run = hostile_run(offenders=25)
    assert failure_message(run.verdicts[0]).endswith("; and 5 more")
    path = tmp_path / "hostile.xml"
    write_junit([run], path)
    xml = JUnitXml.fromfile(str(path))
    (suite,) = list(xml)
    assert suite.name == xml_text(run.label)
    system_err = ET.parse(path).getroot().find("testsuite/system-err")
    assert system_err is not None
    assert system_err.text == xml_text(f"warning {EVIL}").replace("\r\n", "\n")
    cases = list(suite)
    assert cases[0].name == "rule [b]x[/b] <i>"
    (failure,) = cases[0].result
    assert failure.text is not None
    assert failure.text.count("\n- CODE_") == 25
    root = junit_element([run])
    assert root.tag == "testsuites"
    assert root.get("tests") == "2" and root.get("failures") == "1"
