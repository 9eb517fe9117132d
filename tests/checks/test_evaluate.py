"""Verdicts: every rule kind passing and failing on a small mission script, with its offenders."""

from __future__ import annotations

import json
import subprocess
import sys
from typing import TYPE_CHECKING

import pytest

from medkit_replay import replay
from medkit_replay.checks.budget_file import parse_budget
from medkit_replay.checks.evaluate import Verdict, check_run, evaluate
from medkit_replay.checks.facts import Offender
from tests.checks.support import NAV2, budget_text, mission
from tests.outputs.scripts import SEC, T0, clear, report, write_script

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.result import Result


@pytest.fixture(scope="module")
def result(tmp_path_factory: pytest.TempPathFactory) -> Result:
    return replay([mission(tmp_path_factory.mktemp("mission"))], [NAV2])


def verdict(result: Result, rule: str) -> Verdict:
    """The verdict of a budget holding this one rule."""
    (only,) = evaluate(parse_budget(budget_text(rule), "b.yaml"), result)
    return only


def offenders(v: Verdict) -> list[tuple[str, float | None, str]]:
    return [
        (o.fault_code, o.offset_ns / 1e9 if o.offset_ns is not None else None, o.detail)
        for o in v.offenders
    ]


def test_max_confirmed_counts_each_confirmed_fault_once_under_its_final_severity(
    result: Result,
) -> None:
    held = verdict(result, "- max_confirmed: {INFO: 0, WARN: 2, ERROR: 3, CRITICAL: 1}")
    assert held.passed
    assert held.message == (
        "confirmed: INFO 0 of at most 0, WARN 2 of at most 2, ERROR 3 of at most 3, "
        "CRITICAL 1 of at most 1"
    )
    assert held.offenders == ()
    # ESTOP confirmed twice and ends CLEARED: still one CRITICAL fault; WHEEL_SLIP is muted: counts.
    failed = verdict(result, "- max_confirmed: {WARN: 1, CRITICAL: 0}")
    assert not failed.passed
    assert failed.message == (
        "WARN 2 confirmed, at most 1 allowed; CRITICAL 1 confirmed, at most 0 allowed"
    )
    assert offenders(failed) == [
        ("WHEEL_SLIP", 1.0, "WARN, confirmed"),
        ("BATTERY_LOW", 10.0, "WARN, confirmed"),
        ("ESTOP", 25.0, "CRITICAL, confirmed"),
    ]


def test_never_confirm(result: Result) -> None:
    held = verdict(result, "- never_confirm: [FIRE*, 'BATTERY_?']")
    assert held.passed
    assert held.message == "no fault matching FIRE*, BATTERY_? confirmed"
    failed = verdict(result, "- never_confirm: [ESTOP, 'BATTERY_*']")
    assert not failed.passed
    assert failed.message == "2 faults confirmed that must never confirm"
    assert offenders(failed) == [
        ("BATTERY_LOW", 10.0, "confirmed (BATTERY_* must never confirm)"),
        ("ESTOP", 25.0, "confirmed 2 times (ESTOP must never confirm)"),
    ]


def test_allow_confirm(result: Result) -> None:
    everything = "[MOTOR_*, WHEEL_*, BATTERY_*, LIDAR_*, CAMERA_*, ESTOP]"
    held = verdict(result, f"- allow_confirm: {everything}")
    assert held.passed
    assert held.message == "6 faults confirmed, all allowed"
    failed = verdict(result, "- allow_confirm: [MOTOR_*, WHEEL_*, BATTERY_*, ESTOP]")
    assert not failed.passed
    assert failed.message == "2 faults confirmed that no allowed pattern matches"
    assert offenders(failed) == [
        ("LIDAR_TIMEOUT", 20.0, "ERROR, confirmed but not allowed to"),
        ("CAMERA_TIMEOUT", 20.5, "ERROR, confirmed but not allowed to"),
    ]


def test_max_occurrences(result: Result) -> None:
    held = verdict(result, "- max_occurrences: {ESTOP: 2, '*': 2}")
    assert held.passed
    assert held.message == "within limits; highest: ESTOP with 2 occurrence(s)"
    failed = verdict(result, "- max_occurrences: {'E*': 1, 'NOTHING': 0}")
    assert not failed.passed
    assert failed.message == "1 fault occurred more often than allowed"
    # shown at its last occurrence: the reactivation at 27 s
    assert offenders(failed) == [("ESTOP", 27.0, "2 occurrences, at most 1 allowed (E*)")]
    assert verdict(result, "- max_occurrences: {NOTHING*: 0}").message == (
        "no fault matching the patterns was reported"
    )


def test_max_confirmed_duration_counts_a_fault_still_confirmed_until_the_end(
    result: Result,
) -> None:
    held = verdict(result, "- max_confirmed_duration_sec: {MOTOR_*: 5, ESTOP: 1, WHEEL_*: 39}")
    assert held.passed  # 0 to 5 s; two stretches of 1 s; 1 s to the end at 40 s
    assert held.message == "within limits; longest: WHEEL_SLIP for 39.000 s"
    failed = verdict(result, "- max_confirmed_duration_sec: {MOTOR_*: 4.999, '*': 30}")
    assert not failed.passed
    assert failed.message == "2 faults stayed CONFIRMED longer than allowed"
    assert offenders(failed) == [
        (
            "MOTOR_LEFT_OVERHEAT",
            0.0,
            "CONFIRMED for 5.000 s, at most 4.999 s allowed (MOTOR_*); until 5.000 s",
        ),
        (
            "WHEEL_SLIP",
            1.0,
            "CONFIRMED for 39.000 s, at most 30 s allowed (*); "
            "still CONFIRMED at the end of the recording",
        ),
    ]
    # BATTERY_LOW: 10 s to the end is exactly 30 s, which is allowed
    assert verdict(result, "- max_confirmed_duration_sec: {BATTERY_LOW: 30}").passed
    assert not verdict(result, "- max_confirmed_duration_sec: {BATTERY_LOW: 29.9}").passed


def test_resolved_by_end(result: Result) -> None:
    held = verdict(result, "- resolved_by_end: [MOTOR_*, ESTOP, NOT_REPORTED]")
    assert held.passed  # HEALED and CLEARED
    assert held.message == "2 faults confirmed, all healed or cleared by the end"
    failed = verdict(result, "- resolved_by_end: ['*']")
    assert not failed.passed
    assert failed.message == "4 faults not healed or cleared by the end"
    assert [o.fault_code for o in failed.offenders] == [
        "WHEEL_SLIP",
        "BATTERY_LOW",
        "LIDAR_TIMEOUT",
        "CAMERA_TIMEOUT",
    ]
    assert failed.offenders[0].detail == "confirmed, still CONFIRMED at the end"
    assert verdict(result, "- resolved_by_end: [NOTHING*]").message == (
        "no fault matching NOTHING* confirmed"
    )


def test_expect_confirmed_in_a_window(result: Result) -> None:
    held = verdict(result, "- expect_confirmed: {code: BATTERY_LOW, between: [9.5, 10]}")
    assert held.passed  # both ends included
    assert held.message == "BATTERY_LOW confirmed at 10.000 s between 9.5 and 10 s"
    assert verdict(result, "- expect_confirmed: {code: 'LIDAR_*'}").passed
    early = verdict(result, "- expect_confirmed: {code: ESTOP, between: [0, 20]}")
    assert not early.passed
    assert early.message == "ESTOP confirmed, but not between 0 and 20 s"
    assert offenders(early) == [
        ("ESTOP", 25.0, "confirmed outside the window"),
        ("ESTOP", 27.0, "confirmed outside the window"),
    ]
    never = verdict(result, "- expect_confirmed: {code: FIRE}")
    assert not never.passed
    assert never.message == "no fault matching FIRE confirmed"
    assert never.offenders == ()


def test_expect_confirmed_muted_by_a_root_cause(result: Result) -> None:
    held = verdict(result, "- expect_confirmed: {code: WHEEL_SLIP, muted_by: 'MOTOR_*_OVERHEAT'}")
    assert held.passed
    assert held.message == "WHEEL_SLIP confirmed at 1.000 s, muted by MOTOR_LEFT_OVERHEAT"
    other_root = verdict(result, "- expect_confirmed: {code: WHEEL_SLIP, muted_by: ESTOP}")
    assert not other_root.passed
    assert other_root.message == "WHEEL_SLIP confirmed, but not muted by ESTOP"
    assert offenders(other_root) == [("WHEEL_SLIP", 1.0, "muted by MOTOR_LEFT_OVERHEAT")]
    unmuted = verdict(result, "- expect_confirmed: {code: BATTERY_LOW, muted_by: '*'}")
    assert not unmuted.passed
    assert offenders(unmuted) == [("BATTERY_LOW", 10.0, "never muted by a root cause")]


def test_expect_not_confirmed(result: Result) -> None:
    assert verdict(result, "- expect_not_confirmed: {code: FIRE}").passed
    held = verdict(result, "- expect_not_confirmed: {code: ESTOP, between: [0, 24.999]}")
    assert held.passed
    assert held.message == "no fault matching ESTOP confirmed between 0 and 24.999 s"
    failed = verdict(result, "- expect_not_confirmed: {code: 'E*'}")
    assert not failed.passed
    assert failed.message == "E* confirmed"
    assert offenders(failed) == [("ESTOP", 25.0, "confirmed"), ("ESTOP", 27.0, "confirmed")]
    window = verdict(result, "- expect_not_confirmed: {code: ESTOP, between: [26, 30]}")
    assert offenders(window) == [("ESTOP", 27.0, "confirmed")]


def test_expect_cluster(result: Result) -> None:
    by_rule = verdict(result, "- expect_cluster: {rule: 'sensor_*'}")
    assert by_rule.passed
    assert by_rule.message == (
        "sensor_storm_1 formed at 20.000 s (rule sensor_storm: LIDAR_TIMEOUT, CAMERA_TIMEOUT)"
    )
    assert verdict(result, "- expect_cluster: {cluster: 'sensor_storm_?'}").passed
    failed = verdict(result, "- expect_cluster: {rule: drive_storm}")
    assert not failed.passed
    assert (
        failed.message == "no cluster of rule drive_storm formed (clusters formed: sensor_storm_1)"
    )
    assert not verdict(result, "- expect_cluster: {cluster: sensor_storm_2}").passed


def test_a_cluster_gone_by_the_end_still_formed(tmp_path: Path) -> None:
    script = write_script(
        tmp_path / "storm.jsonl",
        [
            report(T0, "LIDAR_TIMEOUT", source="/sensors/lidar"),
            report(T0 + SEC // 2, "IMU_TIMEOUT", source="/sensors/imu"),  # active; muted
            report(T0 + SEC, "LIDAR_TIMEOUT", source="/sensors/lidar"),  # an event naming it
            clear(T0 + 5 * SEC, "LIDAR_TIMEOUT"),
            clear(T0 + 6 * SEC, "IMU_TIMEOUT"),
        ],
    )
    result = replay([script], [NAV2])
    assert result.clusters == ()  # dissolved by the clears
    held = verdict(result, "- expect_cluster: {rule: sensor_storm}")
    assert held.passed
    assert held.message == "sensor_storm_1 formed (rule sensor_storm: LIDAR_TIMEOUT)"


def test_no_messages_at_all(tmp_path: Path) -> None:
    script = tmp_path / "empty.jsonl"
    script.write_text("# nothing\n", encoding="utf-8")
    result = replay([script])
    rules = """
    - max_confirmed: {CRITICAL: 0}
    - expect_not_confirmed: {code: '*', between: [0, 1]}
    - max_confirmed_duration_sec: {'*': 0}
    - expect_confirmed: {code: '*'}
    """
    verdicts = evaluate(parse_budget(budget_text(rules), "b"), result)
    assert [v.passed for v in verdicts] == [True, True, True, False]


def test_check_run_labels_and_failures(result: Result) -> None:
    budget = parse_budget(budget_text("- never_confirm: [ESTOP]\n- never_confirm: [FIRE]"), "b")
    run = check_run(budget, result, ["a.jsonl", "b.jsonl"])
    assert run.label == "a.jsonl + b.jsonl"
    assert not run.passed
    assert [v.rule.index for v in run.failures] == [1]
    assert run.budget is budget


def test_offender_text() -> None:
    assert Offender("A", 5, 2_500_000_000, "confirmed").text() == "A at 2.500 s: confirmed"
    assert Offender("A", None, None, "x").text() == "A: x"


def test_evaluation_is_pure() -> None:
    code = (
        "import json, sys; import medkit_replay.checks.evaluate; "
        "print(json.dumps(sorted(sys.modules)))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], check=True, capture_output=True, text=True
    ).stdout
    loaded = set(json.loads(out))
    forbidden = (
        "click",
        "rich",
        "pandas",
        "rosbags",
        "medkit_replay.pipeline",
        "medkit_replay.inputs",
        "medkit_replay.outputs",
        "medkit_replay.engine",
        "medkit_replay.cli",
    )
    assert sorted(m for m in loaded if m.startswith(forbidden)) == []
