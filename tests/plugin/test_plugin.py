"""The pytest plugin, run in pytester sessions: fixtures, helpers, failure output, goldens."""

from __future__ import annotations

import json
import textwrap
from importlib.metadata import entry_points
from pathlib import Path

import pytest

from medkit_replay.pytest_plugin import (
    RecordingReplayer,
    assert_confirmed,
    assert_matches_golden,
    assert_not_confirmed,
    assert_status,
    fault_timeline,
    recording_start_ns,
)

pytest_plugins = ["pytester"]

ROOT = Path(__file__).resolve().parents[2]
MISSION = ROOT / "sample_bags" / "nav2_mission_mcap"
NAV2 = ROOT / "rules" / "nav2"
CONFIGS = [NAV2 / "fault_manager.yaml", NAV2 / "bridges.yaml"]
EXAMPLE = ROOT / "examples" / "nav2_mission.jsonl"
BUDGETS = ROOT / "rules" / "budgets"

HEADER = f"""
from pathlib import Path

from medkit_replay.pytest_plugin import (
    assert_confirmed,
    assert_matches_golden,
    assert_not_confirmed,
    assert_status,
    assert_within_budget,
)

MISSION = Path({str(MISSION)!r})
CONFIGS = [Path({str(CONFIGS[0])!r}), Path({str(CONFIGS[1])!r})]
EXAMPLE = Path({str(EXAMPLE)!r})
NAV2 = Path({str(NAV2 / "fault_manager.yaml")!r})
BUDGETS = Path({str(BUDGETS)!r})
"""


def make_test(pytester: pytest.Pytester, body: str, name: str = "test_mission") -> Path:
    return pytester.makepyfile(**{name: HEADER + textwrap.dedent(body)})


@pytest.fixture(scope="module")
def mission() -> RecordingReplayer:
    return RecordingReplayer()


def test_registered_as_a_pytest11_entry_point() -> None:
    plugins = {e.name: e.value for e in entry_points(group="pytest11")}
    assert plugins.get("medkit_replay") == "medkit_replay.pytest_plugin"


def test_a_passing_test_file(pytester: pytest.Pytester) -> None:
    make_test(
        pytester,
        """
        CALLS = []

        def test_confirmed(replay_recording):
            result = replay_recording(MISSION, CONFIGS)
            CALLS.append(result)
            first = assert_confirmed(result, "MOTOR_LEFT_OVERHEAT", within=(75.0, 80.0))
            assert first.to_status == "CONFIRMED"
            assert_confirmed(result, "WIFI_SIGNAL_STRENGTH", within=(130, None))
            assert_confirmed(result, "WIFI_SIGNAL_STRENGTH", within=(None, 66))
            assert_status(result, "MOTOR_LEFT_OVERHEAT", "HEALED")

        def test_not_confirmed(replay_recording):
            result = replay_recording([str(MISSION)], [str(c) for c in CONFIGS])
            assert result is CALLS[0]  # replayed once per session
            assert_not_confirmed(result, "BATTERY_*")
            assert_not_confirmed(result, "WIFI_*", within=(0, 60))
            assert_not_confirmed(result, "LOCALIZATION_POSE_CONFIDENC?", within=(30, 200))

        def test_budget(replay_recording):
            assert_within_budget(
                replay_recording(MISSION, CONFIGS), BUDGETS / "nav2_mission_pass.yaml"
            )

        def test_a_script(replay_recording):
            result = replay_recording(EXAMPLE, [NAV2])
            assert result is not CALLS[0]
            assert_confirmed(result, "ESTOP_PRESSED", within=(24, 24))
        """,
    )
    result = pytester.runpytest()
    result.assert_outcomes(passed=4)
    assert "golden" not in result.stdout.str()


def test_failures_show_the_fault_timeline(pytester: pytest.Pytester) -> None:
    make_test(
        pytester,
        """
        def test_too_late(replay_recording):
            result = replay_recording(MISSION, CONFIGS)
            assert_confirmed(result, "MOTOR_LEFT_OVERHEAT", within=(10, 20))

        def test_confirmed_after_all(replay_recording):
            assert_not_confirmed(replay_recording(MISSION, CONFIGS), "WIFI_*")

        def test_unknown_code(replay_recording):
            assert_confirmed(replay_recording(MISSION, CONFIGS), "MOTOR_OVERHEAT")

        def test_wrong_status(replay_recording):
            assert_status(replay_recording(MISSION, CONFIGS), "WIFI_SIGNAL_STRENGTH", "HEALED")
        """,
    )
    result = pytester.runpytest()
    result.assert_outcomes(failed=4)
    result.stdout.fnmatch_lines(
        [
            "*test_too_late*",
            '>*assert_confirmed(result, "MOTOR_LEFT_OVERHEAT", within=(10, 20))',
            "E       AssertionError: expected MOTOR_LEFT_OVERHEAT to be confirmed between 10.000 s"
            " and 20.000 s",
            "E         it was confirmed at 77.005 s (status at the end: HEALED)",
            "E         timeline of MOTOR_LEFT_OVERHEAT (t in s from the recording's start):"
            " 2 status change(s), 21 event(s)",
            "E                           t  status change        cause   source              event",
            "E           !          77.005  (new) -> CONFIRMED   report  /diagnostic_bridge "
            " fault_confirmed",
            "E              77.999-100.004 * fault_updated x19",
            "E                     101.005  CONFIRMED -> HEALED  report  /diagnostic_bridge "
            " fault_cleared",
            "*test_confirmed_after_all*",
            "E       AssertionError: expected no fault matching 'WIFI_*' to be confirmed; 1 was",
            "E         WIFI_SIGNAL_STRENGTH: confirmed at 65.751 s, 136.754 s (status at the end:"
            " CONFIRMED)",
            "E         timeline of WIFI_SIGNAL_STRENGTH *",
            "E           ! * 65.751  (new) -> CONFIRMED   report *",
            "E             * 70.751  CONFIRMED -> HEALED  report *",
            "E           ! * 136.754  HEALED -> CONFIRMED  report *",
            "*test_unknown_code*",
            "E       AssertionError: expected MOTOR_OVERHEAT to be confirmed",
            "E         MOTOR_OVERHEAT was never reported in this run; did you mean"
            " MOTOR_LEFT_OVERHEAT?",
            "E         faults of this run: ACTION_FOLLOW_PATH_ABORTED, *",
            "*test_wrong_status*",
            "E       AssertionError: expected WIFI_SIGNAL_STRENGTH to end HEALED",
            "E         it ended CONFIRMED",
        ]
    )
    # the helpers' own frames are hidden: the traceback points at the test's line
    assert "pytest_plugin/" not in result.stdout.str()


def test_a_failing_budget(pytester: pytest.Pytester) -> None:
    make_test(
        pytester,
        """
        def test_budget(replay_recording):
            result = replay_recording(MISSION, CONFIGS)
            assert_within_budget(result, BUDGETS / "nav2_mission_fail.yaml")
        """,
    )
    result = pytester.runpytest()
    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(
        [
            "E       AssertionError: fault budget * exceeded: * rule(s) failed"
            " (*nav2_mission_fail.yaml)",
            "E         FAIL rule * (line *) *",
            "E           - *",
            "E         timeline of *",
        ]
    )


def test_golden_reports_and_the_update_flag(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch
) -> None:
    test_file = make_test(
        pytester,
        """
        import os

        def test_mission(replay_recording, golden):
            configs = CONFIGS[:1] if os.environ.get("ONLY_MANAGER") else CONFIGS
            golden(replay_recording(MISSION, configs))

        def test_named(replay_recording, golden):
            golden(replay_recording(EXAMPLE, [NAV2]), "script.json", time_tolerance=0.5)

        def test_by_path(replay_recording, tmp_path):
            path = Path(os.environ["GOLDEN_DIR"]) / "by_path.json"
            assert_matches_golden(replay_recording(EXAMPLE, [NAV2]), path)
        """,
        name="test_goldens",
    )
    goldens = test_file.parent / "goldens"
    mission_golden = goldens / "test_goldens" / "test_mission.json"
    script_golden = goldens / "script.json"
    by_path = pytester.path / "elsewhere" / "by_path.json"
    monkeypatch.setenv("GOLDEN_DIR", str(by_path.parent))

    # missing goldens fail, and say how to write them
    result = pytester.runpytest()
    result.assert_outcomes(failed=3)
    result.stdout.fnmatch_lines(
        [
            f"E       AssertionError: golden report {mission_golden} does not exist",
            "E         run pytest with --update-golden to write it from this run",
        ]
    )
    assert not goldens.exists() and not by_path.exists()

    # --update-golden writes them (the JSON report, as analyze --json writes it) and lists them
    result = pytester.runpytest("--update-golden")
    result.assert_outcomes(passed=3)
    result.stdout.fnmatch_lines(
        [
            "*= medkit-replay golden reports written =*",
            str(mission_golden),
            str(script_golden),
            str(by_path),
        ]
    )
    report = json.loads(mission_golden.read_text(encoding="utf-8"))
    assert report["schema"] == "medkit-replay/report/v1"
    assert {f["fault_code"] for f in report["faults"]} >= {"MOTOR_LEFT_OVERHEAT"}

    # unchanged runs pass, and nothing is rewritten
    stamp = mission_golden.stat().st_mtime_ns
    result = pytester.runpytest()
    result.assert_outcomes(passed=3)
    assert "golden reports written" not in result.stdout.str()
    result = pytester.runpytest("--update-golden")
    result.assert_outcomes(passed=3)
    assert "golden reports written" not in result.stdout.str()
    assert mission_golden.stat().st_mtime_ns == stamp

    # a changed run fails with the diff
    monkeypatch.setenv("ONLY_MANAGER", "1")
    result = pytester.runpytest("-k", "test_mission")
    result.assert_outcomes(failed=1, deselected=2)
    result.stdout.fnmatch_lines(
        [
            "E       AssertionError: the run differs from its golden report",
            f"E       baseline: {mission_golden}",
            "E       current:  this run",
            "E       reports differ: 14 differences (fault removed: 4, fault changed: 4,*",
            "E       ACTION_FOLLOW_PATH_ABORTED",
            "E         ~ status *HEALED *CONFIRMED",
            "E       LOG_BT_NAVIGATOR_4fc83613",
            "E         - fault *CONFIRMED *absent",
            "E       run pytest with --update-golden to accept this run as the new golden report",
        ]
    )
    # accepted with the flag
    result = pytester.runpytest("-k", "test_mission", "--update-golden")
    result.assert_outcomes(passed=1, deselected=2)
    result.stdout.fnmatch_lines(["*golden reports written*", str(mission_golden)])
    pytester.runpytest("-k", "test_mission").assert_outcomes(passed=1, deselected=2)

    # the time tolerance: a golden 0.4 s off passes with time_tolerance=0.5
    script = json.loads(script_golden.read_text(encoding="utf-8"))
    for item in script["events"] + script["transitions"]:
        item["t_ns"] += 400_000_000
    script_golden.write_text(json.dumps(script), encoding="utf-8")
    pytester.runpytest("-k", "test_named").assert_outcomes(passed=1, deselected=2)
    for item in script["events"]:
        item["t_ns"] += 200_000_000
    script_golden.write_text(json.dumps(script), encoding="utf-8")
    result = pytester.runpytest("-k", "test_named")
    result.assert_outcomes(failed=1, deselected=2)
    result.stdout.fnmatch_lines(
        ["E       reports differ: * (event shifted: *; time tolerance 0.500 s)"]
    )


def test_a_broken_golden_is_an_error_naming_it(pytester: pytest.Pytester) -> None:
    make_test(
        pytester,
        """
        def test_mission(replay_recording, golden):
            golden(replay_recording(EXAMPLE, [NAV2]), "broken.json")
        """,
    )
    (pytester.path / "goldens").mkdir()
    (pytester.path / "goldens" / "broken.json").write_text("{}", encoding="utf-8")
    result = pytester.runpytest()
    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(["*InputError: *broken.json: not a medkit-replay report*"])


def test_no_side_effects_in_sessions_that_do_not_use_it(pytester: pytest.Pytester) -> None:
    pytester.makepyfile(
        test_plain="""
        import sys

        def test_plain():
            assert "medkit_replay.pipeline" not in sys.modules
            assert "medkit_replay.diffing" not in sys.modules
        """
    )
    result = pytester.runpytest_subprocess()
    result.assert_outcomes(passed=1)
    result.stdout.fnmatch_lines(["plugins:*medkit-replay*"])
    assert "golden" not in result.stdout.str()
    help_text = pytester.runpytest_subprocess("--help").stdout.str()
    assert "--update-golden" in help_text


def test_helpers_outside_the_fixtures(mission: RecordingReplayer) -> None:
    result = mission(EXAMPLE, [NAV2 / "fault_manager.yaml"])
    assert recording_start_ns(result) == 1_000_000_000
    assert mission(str(EXAMPLE), [str(NAV2 / "fault_manager.yaml")]) is result
    with pytest.raises(ValueError, match="the window ends before it starts"):
        assert_confirmed(result, "ESTOP_PRESSED", within=(30, 20))
    with pytest.raises(AssertionError, match=r"ESTOP_PRESSED: confirmed at 24\.000 s"):
        assert_not_confirmed(result, "ESTOP_*")
    assert_not_confirmed(result, "ESTOP_*", within=(24.001, None))
    timeline = fault_timeline(result, "NEVER_SEEN")
    assert timeline.endswith("0 status change(s), 0 event(s)")
    with pytest.raises(AssertionError, match="does not exist"):
        assert_matches_golden(result, Path("/nonexistent/golden.json"), update=False)


def test_long_timelines_are_shortened(mission: RecordingReplayer, tmp_path: Path) -> None:
    lines = []
    for n in range(120):
        kind = "FAILED" if n % 8 < 4 else "PASSED"
        request = {"t_ns": n * 10**9, "op": "report", "fault_code": "FLAP", "event_type": kind}
        lines.append(json.dumps({**request, "source_id": "/flapper"}))
    script = tmp_path / "flap.jsonl"
    script.write_text("\n".join(lines) + "\n", encoding="utf-8")
    config = tmp_path / "fm.yaml"
    config.write_text(
        "fault_manager:\n  ros__parameters:\n    confirmation_threshold: -1\n"
        "    healing_enabled: true\n    healing_threshold: 1\n",
        encoding="utf-8",
    )
    result = mission(script, [config])
    timeline = fault_timeline(result, "FLAP").splitlines()
    assert len(timeline) == 2 + 40 + 1  # the heading, the column names, 40 rows and "..."
    assert any(line.strip().startswith("... ") and "rows ..." in line for line in timeline)
    with pytest.raises(AssertionError) as caught:
        assert_status(result, "FLAP", "CLEARED")
    last_change = [t for t in result.transitions if t.fault_code == "FLAP"][-1]
    assert fault_timeline(result, "FLAP", marked=[last_change]) in str(caught.value)
    assert str(caught.value).splitlines()[-1].startswith("    !")
