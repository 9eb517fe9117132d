"""A small mission script and budget helpers for the fault-budget tests."""

from __future__ import annotations

import textwrap
from pathlib import Path

from tests.outputs.scripts import SEC, T0, clear, report, write_script

ROOT = Path(__file__).resolve().parents[2]
NAV2 = ROOT / "rules" / "nav2" / "fault_manager.yaml"
"""Confirm on the first FAILED, heal after 3 net PASSED, the Nav2 correlation rules."""
BRIDGES = ROOT / "rules" / "nav2" / "bridges.yaml"
SAMPLE = ROOT / "sample_bags" / "nav2_mission_mcap"
BUDGETS = ROOT / "rules" / "budgets"


def mission(tmp_path: Path, name: str = "mission.jsonl") -> Path:
    """40 s of faults, run with NAV2 (times in s from the start):

    - MOTOR_LEFT_OVERHEAT ERROR confirmed at 0, healed at 5 (4 PASSED): root cause;
    - WHEEL_SLIP WARN confirmed at 1, muted by MOTOR_LEFT_OVERHEAT, CONFIRMED to the end (39 s);
    - BATTERY_LOW WARN confirmed at 10, CONFIRMED to the end (30 s);
    - LIDAR_TIMEOUT and CAMERA_TIMEOUT ERROR confirmed at 20 and 20.5: cluster sensor_storm_1;
    - ESTOP CRITICAL confirmed at 25, cleared at 26, again at 27 (occurrence 2), cleared at 28;
    - a PASSED for an unknown code at 40 ends the recording.
    """
    motor = "/powertrain/motor_left"
    return write_script(
        tmp_path / name,
        [
            report(T0, "MOTOR_LEFT_OVERHEAT", severity=2, source=motor),
            report(T0 + 1 * SEC, "WHEEL_SLIP", severity=1, source="/odometry"),
            *(
                report(T0 + t * SEC, "MOTOR_LEFT_OVERHEAT", "PASSED", source=motor)
                for t in (2, 3, 4, 5)
            ),
            report(T0 + 10 * SEC, "BATTERY_LOW", severity=1, source="/power/bms"),
            report(T0 + 20 * SEC, "LIDAR_TIMEOUT", severity=2, source="/sensors/lidar"),
            report(T0 + 20 * SEC + SEC // 2, "CAMERA_TIMEOUT", severity=2, source="/sensors/cam"),
            report(T0 + 25 * SEC, "ESTOP", severity=3, source="/safety"),
            clear(T0 + 26 * SEC, "ESTOP"),
            report(T0 + 27 * SEC, "ESTOP", severity=3, source="/safety"),
            clear(T0 + 28 * SEC, "ESTOP"),
            report(T0 + 40 * SEC, "HEARTBEAT", "PASSED", source="/robot"),
        ],
    )


def budget_text(rules: str, *, header: str = "version: 1\nrules:\n") -> str:
    """A budget file's text: ``rules`` is the YAML of the rules list, written flush left."""
    return header + textwrap.indent(textwrap.dedent(rules).strip("\n"), "  ") + "\n"


def write_budget(tmp_path: Path, rules: str, name: str = "budget.yaml") -> Path:
    """Write a budget with these rules; returns its path."""
    path = tmp_path / name
    path.write_text(budget_text(rules), encoding="utf-8")
    return path
