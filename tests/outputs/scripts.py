"""Small JSON-lines scripts written to tmp_path for the output tests (terminal, progress, files)."""

from __future__ import annotations

import json
from io import StringIO
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from pathlib import Path

SEC = 1_000_000_000
T0 = 1_700_000_000 * SEC  # bag times of a real recording (2023-11-14 22:13:20 UTC)


def report(
    t_ns: int,
    code: str,
    event: str = "FAILED",
    *,
    severity: int = 2,
    description: str = "",
    source: str = "/robot/node",
) -> dict[str, object]:
    """A ReportFault line."""
    return {
        "t_ns": t_ns,
        "op": "report",
        "fault_code": code,
        "event_type": event,
        "severity": severity,
        "description": description,
        "source_id": source,
    }


def clear(t_ns: int, code: str) -> dict[str, object]:
    """A ClearFault line."""
    return {"t_ns": t_ns, "op": "clear", "fault_code": code}


def write_script(path: Path, lines: list[dict[str, object]]) -> Path:
    """Write the lines as a ``.jsonl`` script; returns its path."""
    path.write_text("".join(json.dumps(line) + "\n" for line in lines), encoding="utf-8")
    return path


def mission(tmp_path: Path, name: str = "mission.jsonl") -> Path:
    """Confirmed, healed (with healing_config) and cleared faults, a rejected report; 40 s."""
    return write_script(
        tmp_path / name,
        [
            report(
                T0, "MOTOR_OVERHEAT", severity=3, description="85 C", source="/powertrain/motor"
            ),
            report(T0 + 1 * SEC, "LIDAR_DROPOUT", severity=1, source="/sensors/lidar"),
            report(T0 + 2 * SEC, "LIDAR_DROPOUT", "PASSED", source="/sensors/lidar"),
            report(T0 + 3 * SEC, "LIDAR_DROPOUT", "PASSED", source="/sensors/lidar"),
            report(T0 + 4 * SEC, "LIDAR_DROPOUT", "PASSED", source="/sensors/lidar"),
            report(T0 + 5 * SEC, "LIDAR_DROPOUT", "PASSED", source="/sensors/lidar"),
            report(T0 + 6 * SEC, "BATTERY_LOW", severity=1, source="/power/bms"),
            report(T0 + 7 * SEC, "BATTERY_LOW", severity=1, source="/power/bms2"),
            clear(T0 + 20 * SEC, "BATTERY_LOW"),
            report(T0 + 40 * SEC, "bad code!", source="/misconfigured"),
        ],
    )


class FakeTTY(StringIO):
    """A text stream that says it is a terminal."""

    def isatty(self) -> bool:
        return True


def healing_config(tmp_path: Path) -> Path:
    """A fault_manager parameter file with healing on (3 net PASSED heal a fault)."""
    path = tmp_path / "fault_manager.yaml"
    path.write_text(
        "fault_manager:\n"
        "  ros__parameters:\n"
        "    confirmation_threshold: -1\n"
        "    healing_enabled: true\n"
        "    healing_threshold: 3\n",
        encoding="utf-8",
    )
    return path
