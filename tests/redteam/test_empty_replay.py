"""Red team, nothing replayed: a recording in which nothing reached the fault manager never
holds a budget, in ``check``, ``fleet --budget``, ``sweep --budget`` and the pytest plugin,
whatever the rules; ``--allow-empty`` (``--allow-empty-replay``, ``allow_empty=``) opts out.

The budget is the issue's: negative rules only, which an empty replay would trivially keep.
"""

from __future__ import annotations

import dataclasses
import json
import textwrap
import xml.etree.ElementTree as ET
from typing import TYPE_CHECKING

import pytest

from medkit_replay.checks import load_budget, nothing_replayed
from medkit_replay.checks.github import escape_data
from medkit_replay.pipeline import replay
from medkit_replay.result import Consumption, TopicUse
from tests.checks.support import write_budget
from tests.inputs.builders import (
    diag,
    goal_status,
    log,
    report_fault,
    string_msg,
    truncated,
    write_bag,
    write_bare,
)
from tests.redteam.support import run_limited

if TYPE_CHECKING:
    from pathlib import Path

    from tests.redteam.support import Outcome

pytest_plugins = ["pytester"]

SECOND = 1_000_000_000
NEGATIVE_RULES = """
- max_confirmed: {CRITICAL: 0}
- never_confirm: ['ESTOP*']
"""
NONE = "no /diagnostics, no */_action/status"
LINES = {
    "unrelated": f"nothing replayed: {NONE}, no ReportFault/ClearFault calls",
    "rosout_off": (
        f"nothing replayed: {NONE}, /rosout present but the log bridge is off "
        "(medkit_replay: {enable_log_bridge: true} to read it), no ReportFault/ClearFault calls"
    ),
    "truncated": f"nothing replayed: no readable message, {NONE}, no ReportFault/ClearFault calls",
}
"""The one line of each empty recording, exactly."""
KINDS = [*LINES, "replayed"]
LOG_BRIDGE_ON = "medkit_replay:\n  ros__parameters: {enable_log_bridge: true}\n"


@pytest.fixture(scope="module")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """One recording of each kind, each alone in its own folder (a fleet's input):

    - ``unrelated``: /chatter only;
    - ``rosout_off``: /chatter and ERROR lines on /rosout, read only with the log bridge on;
    - ``truncated``: a bare MCAP of 200 /diagnostics arrays cut to its first 1,000 bytes;
    - ``replayed``: three SUCCEEDED goals on an action: read, and no report at all.
    """
    root = tmp_path_factory.mktemp("recordings")
    made: dict[str, Path] = {}
    for kind in KINDS:
        (root / kind).mkdir()
    made["unrelated"] = write_bag(
        root / "unrelated" / "bag", [string_msg(k * SECOND) for k in range(1, 6)]
    )
    made["rosout_off"] = write_bag(
        root / "rosout_off" / "bag",
        [rec for k in range(1, 6) for rec in (string_msg(k * SECOND), log(k * SECOND + 1))],
    )
    whole = write_bare(root / "whole.mcap", [diag(k * SECOND) for k in range(1, 201)])
    made["truncated"] = truncated(whole, root / "truncated" / "cut.mcap", 1000)
    whole.unlink()
    made["replayed"] = write_bag(
        root / "replayed" / "bag", [goal_status(k * SECOND, 4) for k in range(1, 4)]
    )
    return made


@pytest.fixture(scope="module")
def budget(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_budget(tmp_path_factory.mktemp("budget"), NEGATIVE_RULES)


def flag(allow: bool) -> list[str]:
    return ["--allow-empty"] if allow else []


def sane(outcome: Outcome) -> None:
    assert "Traceback" not in outcome.stderr and "internal error" not in outcome.stderr, (
        outcome.stderr[-2000:]
    )


# --- the fact: what each path took ---------------------------------------------------------


def test_the_replay_says_what_each_path_took(tmp_path: Path) -> None:
    bag = write_bag(
        tmp_path / "bag",
        [
            *(diag(k * SECOND) for k in range(1, 4)),
            goal_status(SECOND, 2, "/a/_action/status"),
            goal_status(2 * SECOND, 4, "/b/_action/status"),
            goal_status(3 * SECOND, 4, "/b/_action/status"),
            log(SECOND),
            report_fault(4 * SECOND, "A", sequence=1),
            report_fault(4 * SECOND, "A", event_type=0, sequence=1),  # the client's copy
            report_fault(5 * SECOND, "B", sequence=2),
            string_msg(SECOND),
        ],
    )
    consumed = replay([bag]).consumed
    assert consumed is not None and not consumed.empty
    assert consumed.taken == (
        TopicUse("diagnostic_bridge", "/diagnostics", 3),
        TopicUse("action_status_bridge", "/a/_action/status", 1),
        TopicUse("action_status_bridge", "/b/_action/status", 2),
        TopicUse("report_fault", "/fault_manager/report_fault/_service_event", 3),
    )
    assert (consumed.report_calls, consumed.clear_calls) == (2, 0)
    assert consumed.messages_read == 9
    assert consumed.unread == (TopicUse("log_bridge", "/rosout", 1),)
    assert consumed.lines() == [
        "diagnostic bridge: 3 messages on /diagnostics",
        "action status bridge: 1 message on /a/_action/status, 2 messages on /b/_action/status",
        "log bridge: off; /rosout holds 1 log message (medkit_replay: {enable_log_bridge: true} "
        "to read them)",
        "recorded ReportFault calls: 2, ClearFault calls: 0",
    ]


@pytest.mark.parametrize("kind", KINDS)
def test_the_fact_for_each_recording(recordings: dict[str, Path], budget: Path, kind: str) -> None:
    result = replay([recordings[kind]])
    assert result.consumed is not None
    assert result.consumed.empty == (kind != "replayed")
    assert nothing_replayed(load_budget(budget), result) == LINES.get(kind)
    assert nothing_replayed(load_budget(budget, allow_empty=True), result) is None


def test_recorded_calls_alone_are_a_replay(tmp_path: Path, budget: Path) -> None:
    bag = write_bag(tmp_path / "bag", [report_fault(SECOND, "MOTOR_HOT"), string_msg(SECOND)])
    result = replay([bag])
    assert result.consumed is not None and result.consumed.report_calls == 1
    assert nothing_replayed(load_budget(budget), result) is None


def test_the_log_bridge_the_line_names_reads_the_recording(
    tmp_path: Path, recordings: dict[str, Path], budget: Path
) -> None:
    params = tmp_path / "params.yaml"
    params.write_text(LOG_BRIDGE_ON, encoding="utf-8")
    outcome = run_limited(
        ["check", recordings["rosout_off"], "--budget", budget, "--config", params]
    )
    sane(outcome)
    assert outcome.status == 0, outcome.stdout[-2000:]
    assert "budget holds" in outcome.stdout


def test_diagnostics_on_another_topic_are_named_with_the_parameter_that_reads_them(
    tmp_path: Path, budget: Path
) -> None:
    records = [dataclasses.replace(diag(k * SECOND), topic="/diag_agg") for k in range(1, 4)]
    bag = write_bag(tmp_path / "bag", records)
    outcome = run_limited(["check", bag, "--budget", budget])
    sane(outcome)
    assert outcome.status == 1
    hint = "(/diag_agg holds 3 DiagnosticArrays: diagnostic_bridge.diagnostics_topic: /diag_agg"
    assert f"ERROR {bag}: nothing replayed: no /diagnostics {hint} to read it), " in outcome.stdout
    params = tmp_path / "params.yaml"
    params.write_text(
        "diagnostic_bridge:\n  ros__parameters: {diagnostics_topic: /diag_agg}\n", encoding="utf-8"
    )
    read = run_limited(["check", bag, "--budget", budget, "--config", params])
    assert read.status == 0, read.stdout[-2000:]


def test_the_line_for_each_missing_path() -> None:
    base = Consumption(
        messages_read=4,
        holds_messages=True,
        diagnostics_topic="/diagnostics",
        rosout_topic="/rosout",
        log_bridge=True,
        taken=(TopicUse("fault_events", "/fault_manager/events", 4),),
        metadata_only=2,
    )
    assert base.empty
    assert base.nothing_replayed() == (
        f"nothing replayed: {NONE}, no /rosout, 2 ReportFault/ClearFault calls recorded without "
        "the request (metadata-only service introspection)"
    )
    assert base.lines()[2:] == [
        "log bridge: nothing on /rosout",
        "recorded ReportFault calls: 0, ClearFault calls: 0 (2 more recorded without their "
        "request)",
        "recorded fault manager events: 4 (compared under parity; they raise no fault)",
    ]
    for fed in (
        dataclasses.replace(base, clear_calls=1),
        dataclasses.replace(base, taken=(TopicUse("script", "", 3),)),
        dataclasses.replace(base, taken=(TopicUse("log_bridge", "/rosout", 0),)),
    ):
        assert not fed.empty


# --- check ----------------------------------------------------------------------------------


@pytest.mark.parametrize("allow", [False, True], ids=["default", "allow-empty"])
@pytest.mark.parametrize("kind", KINDS)
def test_check(
    tmp_path: Path, recordings: dict[str, Path], budget: Path, kind: str, allow: bool
) -> None:
    path = recordings[kind]
    junit = tmp_path / "check.xml"
    summary = tmp_path / "summary.md"
    outcome = run_limited(
        ["check", path, "--budget", budget, "--junit", junit, "--github", *flag(allow)],
        env={"GITHUB_STEP_SUMMARY": str(summary)},
    )
    sane(outcome)
    root = ET.parse(junit).getroot()
    if kind == "replayed" or allow:
        assert outcome.status == 0, outcome.stdout[-2000:]
        assert "budget holds: 2 rules passed on 1 run" in outcome.stdout
        assert "nothing replayed" not in outcome.stdout
        assert (root.get("tests"), root.get("errors"), root.get("failures")) == ("2", "0", "0")
        return
    line = f"{path}: {LINES[kind]}"
    assert outcome.status == 1, outcome.stdout[-2000:]
    assert f"not checked, nothing was replayed\nERROR {line}\n" in outcome.stdout
    assert outcome.stdout.count("nothing replayed:") == 2  # the run's line, its annotation
    assert "check failed: 1 of 1 run replayed nothing" in outcome.stdout
    assert "PASS" not in outcome.stdout
    # JUnit: the run's one testcase is an error saying so.
    assert (root.get("tests"), root.get("errors"), root.get("failures")) == ("1", "1", "0")
    (case,) = root.iter("testcase")
    assert case.get("name") == "something was replayed"
    (error,) = case.iter("error")
    assert (error.get("type"), error.get("message"), error.text) == ("empty", line, line)
    # GitHub: an error annotation, the replay's warnings as warnings, the step summary.
    title = f"nothing replayed ({path})".replace(":", "%3A").replace(",", "%2C")
    assert f"::error title={title}::{escape_data(line)}\n" in outcome.stdout
    assert "::warning title=" in outcome.stdout
    page = summary.read_text(encoding="utf-8")
    assert page.startswith("## medkit-replay check: nothing replayed ❌")
    assert ": nothing replayed\n" in page


def test_check_with_an_empty_run_among_others(
    tmp_path: Path, recordings: dict[str, Path], budget: Path
) -> None:
    junit = tmp_path / "check.xml"
    paths = [recordings["replayed"], recordings["unrelated"]]
    outcome = run_limited(["check", *paths, "--budget", budget, "--junit", junit])
    sane(outcome)
    assert outcome.status == 1
    assert "all 2 rules passed" in outcome.stdout
    assert "check failed: 1 of 2 runs replayed nothing" in outcome.stdout
    root = ET.parse(junit).getroot()
    assert (root.get("tests"), root.get("errors"), root.get("failures")) == ("3", "1", "0")
    # --merge: one run, replayed (the goals reached the action bridge).
    merged = run_limited(["check", *paths, "--budget", budget, "--merge"])
    assert merged.status == 0, merged.stdout[-2000:]


# --- fleet --budget -------------------------------------------------------------------------


@pytest.mark.parametrize("allow", [False, True], ids=["default", "allow-empty"])
@pytest.mark.parametrize("kind", KINDS)
def test_fleet(
    tmp_path: Path, recordings: dict[str, Path], budget: Path, kind: str, allow: bool
) -> None:
    folder = recordings[kind].parent
    out = tmp_path / "fleet"
    options: list[str | Path] = ["--budget", budget, "--jobs", "1", "--out", out, *flag(allow)]
    outcome = run_limited(["fleet", folder, *options])
    sane(outcome)
    (run,) = json.loads((out / "runs.json").read_text(encoding="utf-8"))
    assert run["error"] is None
    if kind == "replayed" or allow:
        assert outcome.status == 0, outcome.stdout[-2000:]
        assert (run["budget"], run["budget_failures"]) == ("pass", [])
        return
    assert outcome.status == 1, outcome.stdout[-2000:]
    assert (run["budget"], run["budget_failures"]) == ("fail", [LINES[kind]])
    shown = " ".join(outcome.stdout.split())  # the summary wraps at 80 columns
    # The whole line, then the next section (the runs' warnings, or where the report went).
    whole = f"over budget: {recordings[kind]}: {LINES[kind]} "
    assert any(whole + after in shown for after in ("warnings:", "report:")), shown


def test_fleet_without_a_budget_checks_nothing(tmp_path: Path, recordings: dict[str, Path]) -> None:
    out = tmp_path / "fleet"
    folder = recordings["unrelated"].parent
    outcome = run_limited(["fleet", folder, "--jobs", "1", "--out", out, "--quiet"])
    assert outcome.status == 0, outcome.stderr[-2000:]


# --- sweep --budget -------------------------------------------------------------------------


@pytest.mark.parametrize("allow", [False, True], ids=["default", "allow-empty"])
@pytest.mark.parametrize("kind", KINDS)
def test_sweep(
    tmp_path: Path, recordings: dict[str, Path], budget: Path, kind: str, allow: bool
) -> None:
    out = tmp_path / "sweep"
    path = recordings[kind]
    vary = ["--vary", "fault_manager.confirmation_threshold=-1,-2"]
    options: list[str | Path] = ["--budget", budget, "--jobs", "1", "--out", out, *flag(allow)]
    outcome = run_limited(["sweep", path, *vary, *options])
    sane(outcome)
    rows = (out / "runs.csv").read_text(encoding="utf-8")
    if kind == "replayed" or allow:
        assert outcome.status == 0, outcome.stdout[-2000:]
        assert "nothing replayed" not in rows and ",fail," not in rows
        return
    assert outcome.status == 1, outcome.stdout[-2000:]
    assert rows.count(f'fail,"{LINES[kind]}"') == 2  # both variants, the line as it is
    shown = " ".join(outcome.stdout.split())  # the summary wraps at 80 columns
    assert f"over budget: {path}: {LINES[kind]} (2 variants)" in shown


def test_sweep_varying_the_log_bridge(
    tmp_path: Path, recordings: dict[str, Path], budget: Path
) -> None:
    """The bridge settings of a variant decide: with the log bridge on, /rosout is replayed."""
    out = tmp_path / "sweep"
    vary = ["--vary", "medkit_replay.enable_log_bridge=false,true"]
    path = recordings["rosout_off"]
    outcome = run_limited(["sweep", path, *vary, "--budget", budget, "--out", out, "--quiet"])
    sane(outcome)
    assert outcome.status == 1
    rows = (out / "runs.csv").read_text(encoding="utf-8").splitlines()
    assert rows[1].startswith("v01,False,") and f'fail,"{LINES["rosout_off"]}"' in rows[1]
    assert rows[2].startswith("v02,True,") and ",pass," in rows[2]


# --- the pytest plugin ----------------------------------------------------------------------


def plugin_tests(recordings: dict[str, Path], budget: Path) -> str:
    paths = {kind: str(path) for kind, path in recordings.items()}
    return textwrap.dedent(
        f"""
        import pytest

        from medkit_replay.pytest_plugin import assert_within_budget

        PATHS = {paths!r}
        BUDGET = {str(budget)!r}

        @pytest.mark.parametrize("kind", sorted(PATHS))
        def test_default(replay_recording, kind):
            assert_within_budget(replay_recording(PATHS[kind]), BUDGET)

        @pytest.mark.parametrize("kind", sorted(PATHS))
        def test_allowed(replay_recording, kind):
            assert_within_budget(replay_recording(PATHS[kind]), BUDGET, allow_empty=True)

        @pytest.mark.parametrize("kind", sorted(PATHS))
        def test_refused(replay_recording, kind):
            assert_within_budget(replay_recording(PATHS[kind]), BUDGET, allow_empty=False)
        """
    )


@pytest.mark.parametrize("option", [False, True], ids=["default", "allow-empty-replay"])
def test_plugin(
    pytester: pytest.Pytester, recordings: dict[str, Path], budget: Path, option: bool
) -> None:
    pytester.makepyfile(test_budget=plugin_tests(recordings, budget))
    result = pytester.runpytest(*(["--allow-empty-replay"] if option else []))
    failing = {f"test_refused[{kind}]" for kind in LINES}
    if not option:
        failing |= {f"test_default[{kind}]" for kind in LINES}
    reports = result.reprec.getreports("pytest_runtest_logreport")  # type: ignore[attr-defined]
    failed = {r.nodeid.split("::")[-1] for r in reports if r.when == "call" and r.failed}
    assert failed == failing
    result.assert_outcomes(passed=12 - len(failing), failed=len(failing))
    for line in LINES.values():
        result.stdout.fnmatch_lines(
            [f"E * AssertionError: fault budget budget.yaml not checked (*budget.yaml): {line}"]
        )
