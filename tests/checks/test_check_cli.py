"""``medkit-replay check`` end to end: exit statuses, runs, JUnit XML, GitHub annotations."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from typing import TYPE_CHECKING

import pytest
from junitparser import Failure, JUnitXml, TestCase, TestSuite

from medkit_replay.cli import main
from tests.checks.support import BRIDGES, BUDGETS, NAV2, ROOT, SAMPLE, mission, write_budget
from tests.outputs.scripts import SEC, T0, report, write_script

if TYPE_CHECKING:
    from pathlib import Path

PASSING = """
- name: few criticals
  max_confirmed: {CRITICAL: 1}
- expect_cluster: {rule: sensor_storm}
"""
FAILING = """
- name: few criticals
  max_confirmed: {CRITICAL: 1}
- name: no e-stop
  never_confirm: [ESTOP]
- name: all resolved
  resolved_by_end: ['*']
"""


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    status = main(argv)
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return status, out, err


def check(
    tmp_path: Path, rules: str, capsys: pytest.CaptureFixture[str], *extra: str
) -> tuple[int, str, str]:
    budget = write_budget(tmp_path, rules)
    script = mission(tmp_path)
    return run(
        ["check", str(script), "--budget", str(budget), "--config", str(NAV2), *extra], capsys
    )


def test_exit_0_when_the_budget_holds(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    status, out, err = check(tmp_path, PASSING, capsys)
    assert status == 0
    assert err == ""
    release, *lines = out.splitlines()
    assert release == "ros2_medkit 0.7.0 modelled (medkit_replay.upstream_release: 0.6.0, 0.7.0)"
    assert lines[0] == f"check {tmp_path / 'mission.jsonl'} against budget.yaml: all 2 rules passed"
    assert lines[1] == "PASS few criticals: confirmed: CRITICAL 1 of at most 1"
    assert lines[2].startswith("PASS cluster of rule sensor_storm formed: sensor_storm_1 formed")
    assert lines[-1] == "budget holds: 2 rules passed on 1 run"
    assert "\x1b" not in out  # plain text when not a terminal


def test_exit_1_when_the_budget_is_exceeded(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    status, out, err = check(tmp_path, FAILING, capsys)
    assert status == 1
    assert err == ""
    assert "2 of 3 rules failed" in out
    assert "PASS few criticals" in out
    assert "FAIL no e-stop: 1 fault confirmed that must never confirm" in out
    assert "- ESTOP at 25.000 s: confirmed 2 times (ESTOP must never confirm)" in out
    assert "FAIL all resolved: 4 faults not healed or cleared by the end" in out
    assert "- BATTERY_LOW at 10.000 s: confirmed, still CONFIRMED at the end" in out
    assert out.splitlines()[-1] == "budget exceeded: 2 rule verdicts failed in 1 of 1 run"


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--budget", "{tmp}/absent.yaml"], "{tmp}/absent.yaml: budget file not found"),
        (["--budget", "{tmp}/bad.yaml"], "{tmp}/bad.yaml:3: rule 1: max_confirmed: unknown key"),
        (["--budget", "{tmp}/budget.yaml", "--config", "{tmp}/absent_params.yaml"], "not found"),
        ([], "Missing option '--budget'"),
    ],
)
def test_exit_2_on_bad_budget_config_or_usage(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str], message: str
) -> None:
    write_budget(tmp_path, PASSING)
    write_budget(tmp_path, "- max_confirmed: {FATAL: 0}", name="bad.yaml")
    script = mission(tmp_path)
    args = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    status, out, err = run(["check", str(script), *args], capsys)
    assert status == 2
    assert out == ""
    assert message.replace("{tmp}", str(tmp_path)) in err
    assert len(err.strip().splitlines()) <= 3  # one line (click adds its usage lines)


def test_an_unreadable_input_fails_the_check(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A recording that cannot be read never passes: exit 1, the reason in the output (issue
    14); an input that does not exist is bad usage, exit 2."""
    budget = write_budget(tmp_path, PASSING)
    broken = tmp_path / "broken.jsonl"
    broken.write_text('{"t_ns": 1, "op": "explode"}\n', encoding="utf-8")
    status, out, err = run(["check", str(broken), "--budget", str(budget)], capsys)
    assert status == 1
    assert f"ERROR {broken}:1: " in out
    assert "check failed: 1 of 1 run could not be read" in out
    assert err == ""
    status, _, err = run(["check", str(tmp_path / "absent.mcap"), "--budget", str(budget)], capsys)
    assert status == 2
    assert "absent.mcap: input not found" in err


def test_a_bad_budget_fails_before_any_replay(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = write_budget(tmp_path, "- never_confirm: []", name="bad.yaml")
    status, out, err = run(["check", str(tmp_path / "absent.mcap"), "--budget", str(bad)], capsys)
    assert status == 2
    assert out == ""
    assert f"{bad}:3: rule 1: never_confirm: the list of patterns is empty" in err


def _quiet_script(tmp_path: Path) -> Path:
    """A run with one WARN fault at 100 s after its start, no other fault."""
    return write_script(
        tmp_path / "quiet.jsonl",
        [report(T0, "WIFI_WEAK", severity=1), report(T0 + 100 * SEC, "WIFI_WEAK", severity=1)],
    )


def test_each_input_is_its_own_run_unless_merged(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    first = mission(tmp_path)
    second = _quiet_script(tmp_path)
    budget = write_budget(tmp_path, "- never_confirm: [ESTOP]\n- max_confirmed: {WARN: 2}")
    common = ["--budget", str(budget), "--config", str(NAV2)]
    junit = tmp_path / "runs.xml"
    status, out, err = run(
        ["check", str(first), str(second), *common, "--junit", str(junit)], capsys
    )
    assert status == 1
    assert err.splitlines()[-1] == f"wrote {junit}"  # the file written, after the rest
    assert "wrote" not in out
    assert f"check {first} against budget.yaml: 1 of 2 rules failed" in out
    assert f"check {second} against budget.yaml: all 2 rules passed" in out
    assert out.splitlines()[-1] == "budget exceeded: 1 rule verdict failed in 1 of 2 runs"
    suites = list(JUnitXml.fromfile(str(junit)))
    assert [s.name for s in suites] == [str(first), str(second)]
    assert [(s.tests, s.failures) for s in suites] == [(2, 1), (2, 0)]

    merged = tmp_path / "merged.xml"
    status, out, _ = run(
        ["check", str(first), str(second), *common, "--merge", "--junit", str(merged)], capsys
    )
    assert status == 1
    label = f"{first} + {second}"
    assert f"check {label} against budget.yaml: 2 of 2 rules failed" in out  # 3 WARN faults
    assert "- WIFI_WEAK at 0.000 s: WARN, confirmed" in out
    (suite,) = list(JUnitXml.fromfile(str(merged)))
    assert suite.name == label
    assert (suite.tests, suite.failures) == (2, 2)


def _cases(suite: TestSuite) -> list[TestCase]:
    return list(suite)


def test_junit_one_testcase_per_rule_with_offenders(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    junit = tmp_path / "out" / "budget.xml"
    junit.parent.mkdir()
    status, _, _ = check(tmp_path, FAILING, capsys, "--junit", str(junit))
    assert status == 1
    xml = JUnitXml.fromfile(str(junit))
    assert (xml.tests, xml.failures, xml.errors) == (3, 2, 0)
    (suite,) = list(xml)
    assert suite.name == str(tmp_path / "mission.jsonl")
    assert (suite.tests, suite.failures, suite.errors, suite.skipped) == (3, 2, 0, 0)
    properties = {
        p.get("name"): p.get("value")
        for p in ET.parse(junit).getroot().iterfind("testsuite/properties/property")
    }
    assert properties["budget"] == str(tmp_path / "budget.yaml")
    assert properties["input"] == str(tmp_path / "mission.jsonl")
    cases = _cases(suite)
    assert [c.name for c in cases] == ["few criticals", "no e-stop", "all resolved"]
    assert {c.classname for c in cases} == {str(tmp_path / "mission.jsonl")}
    assert [c.is_passed for c in cases] == [True, False, False]
    assert cases[0].system_out == "confirmed: CRITICAL 1 of at most 1"
    (failure,) = cases[1].result
    assert isinstance(failure, Failure)
    assert failure.type == "never_confirm"
    assert failure.message == (
        "1 fault confirmed that must never confirm: "
        "ESTOP at 25.000 s: confirmed 2 times (ESTOP must never confirm)"
    )
    assert failure.text == (
        "1 fault confirmed that must never confirm\n"
        "- ESTOP at 25.000 s: confirmed 2 times (ESTOP must never confirm)"
    )
    (resolved,) = cases[2].result
    assert resolved.message is not None
    for code in ("WHEEL_SLIP", "BATTERY_LOW", "LIDAR_TIMEOUT", "CAMERA_TIMEOUT"):
        assert f"{code} at " in resolved.message
    assert cases[2]._elem.get("line") == "7"  # where the rule is written
    assert cases[2]._elem.get("file") == str(tmp_path / "budget.yaml")


def test_junit_holds_any_recorded_text(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    odd = tmp_path / "run <&> \x1b[31m\u202e .jsonl"
    mission(tmp_path).rename(odd)
    budget = write_budget(tmp_path, FAILING)
    junit = tmp_path / "odd.xml"
    status, out, _ = run(
        ["check", str(odd), "--budget", str(budget), "--config", str(NAV2), "--junit", str(junit)],
        capsys,
    )
    assert status == 1
    assert "\x1b" not in out and "\u202e" not in out
    assert "run <&> \\x1b[31m\\u202e .jsonl against budget.yaml" in out
    (suite,) = list(JUnitXml.fromfile(str(junit)))
    assert suite.name == str(odd).replace("\x1b", "\\x1b").replace("\u202e", "\\u202e")
    assert suite.failures == 2


def test_junit_write_error_is_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    blocker = tmp_path / "blocker"  # a missing folder is made (tests/commands); not this one
    blocker.write_text("", encoding="utf-8")
    status, _, err = check(tmp_path, PASSING, capsys, "--junit", str(blocker / "x.xml"))
    assert status == 2
    assert "cannot write JUnit XML" in err


def _unescape(value: str) -> str:
    for code, char in (("%2C", ","), ("%3A", ":"), ("%0A", "\n"), ("%0D", "\r"), ("%25", "%")):
        value = value.replace(code, char)
    return value


COMMAND = re.compile(r"^::(error|warning) (?:file=([^,:]*),line=(\d+),)?title=([^,:]*)::(.*)$")


def test_github_annotations_and_step_summary(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    odd = tmp_path / "50% a,b: c\r\n::error::x | <b>*y*<i> @team.jsonl"
    mission(tmp_path).rename(odd)
    budget = write_budget(tmp_path, FAILING)
    summary = tmp_path / "summary.md"
    summary.write_text("earlier step\n", encoding="utf-8")
    monkeypatch.setenv("GITHUB_STEP_SUMMARY", str(summary))
    status, out, _ = run(
        ["check", str(odd), "--budget", str(budget), "--config", str(NAV2), "--github"], capsys
    )
    assert status == 1
    commands = [line for line in out.splitlines() if line.startswith("::")]
    assert len(commands) == 2  # one per failed rule; "::error::x" in the path never starts a line
    parsed = [COMMAND.match(line) for line in commands]
    assert all(parsed)
    first = parsed[0]
    assert first is not None
    kind, file, line, title, message = first.groups()
    assert kind == "error"
    assert _unescape(file) == str(budget)
    assert line == "5"
    shown = str(odd).replace("\r\n", "  ")  # line breaks in recorded text become spaces
    assert _unescape(title) == f"fault budget exceeded: no e-stop ({shown})"
    assert _unescape(message) == (
        "1 fault confirmed that must never confirm\n"
        "ESTOP at 25.000 s: confirmed 2 times (ESTOP must never confirm)"
    )
    page = summary.read_text(encoding="utf-8")
    assert page.startswith("earlier step\n## medkit-replay check: budget exceeded ❌\n")
    assert "| ✅ pass | few criticals | confirmed\\: CRITICAL 1 of at most 1 |" in page
    assert (
        "| ❌ **fail** | no e\\-stop | 1 fault confirmed that must never confirm<br>• ESTOP" in page
    )
    heading = next(line for line in page.splitlines() if line.startswith("### "))
    assert "&lt;b&gt;\\*y\\*&lt;i&gt;" in heading
    assert "\\|" in heading and "\\@team" in heading
    assert "\r" not in page and "<b>" not in page
    assert heading.endswith(": 2 of 3 rules failed")


def test_github_without_a_step_summary(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("GITHUB_STEP_SUMMARY", raising=False)
    status, out, _ = check(tmp_path, PASSING, capsys, "--github")
    assert status == 0
    assert not [line for line in out.splitlines() if line.startswith("::")]
    assert list(tmp_path.glob("*.md")) == []


def test_github_step_summary_write_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("GITHUB_STEP_SUMMARY", str(tmp_path / "no" / "summary.md"))
    status, _, err = check(tmp_path, PASSING, capsys, "--github")
    assert status == 2
    assert "cannot append the step summary" in err


SAMPLE_CONFIG = ["--config", str(NAV2), "--config", str(BRIDGES)]


def test_example_budget_holds_on_the_sample_bag(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    junit = tmp_path / "pass.xml"
    budget = BUDGETS / "nav2_mission_pass.yaml"
    argv = ["check", str(SAMPLE), "--budget", str(budget), *SAMPLE_CONFIG, "--junit", str(junit)]
    status, out, _ = run(argv, capsys)
    assert status == 0, out
    assert out.splitlines()[-1] == "budget holds: 10 rules passed on 1 run"
    assert "FAIL" not in out
    (suite,) = list(JUnitXml.fromfile(str(junit)))
    assert (suite.tests, suite.failures) == (10, 0)


def test_example_budget_is_exceeded_on_the_sample_bag(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    junit = tmp_path / "fail.xml"
    budget = BUDGETS / "nav2_mission_fail.yaml"
    argv = ["check", str(SAMPLE), "--budget", str(budget), *SAMPLE_CONFIG, "--junit", str(junit)]
    status, out, _ = run(argv, capsys)
    assert status == 1
    (suite,) = list(JUnitXml.fromfile(str(junit)))
    verdicts = {c.name: c.is_passed for c in _cases(suite)}
    assert verdicts == {
        "no critical fault": False,
        "the motors never overheat": False,
        "everything recovers by the end": False,
        "WiFi drops are short": False,
        "WiFi trouble shows in the first minute": False,
        "drive faults cluster": False,
        "no recurring fault": True,
    }
    assert "- LOG_MOTOR_DRIVER_e76c6116 at 78.372 s: CRITICAL, confirmed" in out
    assert "- MOTOR_LEFT_OVERHEAT at 77.005 s:" in out
    assert "- WIFI_SIGNAL_STRENGTH at 136.754 s: CONFIRMED for 13.996 s" in out


def test_readme_budget_holds_on_the_sample_bag(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    page = (ROOT / "docs" / "commands" / "check.md").read_text(encoding="utf-8")
    block = page.split("```yaml\n", 1)[1].split("```", 1)[0]
    budget = tmp_path / "readme.yaml"
    budget.write_text(block, encoding="utf-8")
    status, out, _ = run(["check", str(SAMPLE), "--budget", str(budget), *SAMPLE_CONFIG], capsys)
    assert status == 0, out
