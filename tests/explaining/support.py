"""Scripts and configs for the explain tests, written into a temporary folder."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from pathlib import Path

S = 1_000_000_000

FAULT_MANAGER = """\
fault_manager:
  ros__parameters:
    confirmation_threshold: {conf}
    healing_enabled: true
    healing_threshold: 2
    auto_confirm_after_sec: {auto}
    entity_thresholds:
      config_file: entities.yaml
    correlation:
      config_file: correlation.yaml
      cleanup_interval_sec: 5.0
"""
ENTITIES = """\
/robot/arm:
  confirmation_threshold: -1
  healing_threshold: 0
"""
CORRELATION = """\
correlation:
  enabled: true
  default_window_ms: 2000
  patterns:
    drive:
      codes: ["WHEEL_*"]
    sensors:
      codes: ["CAM_*", "LIDAR_*"]
  rules:
    - id: overheat
      name: "Overheat drags the wheels"
      mode: hierarchical
      root_cause: {codes: ["MOTOR_OVERHEAT"]}
      symptoms: [{pattern: drive}]
      window_ms: 3000
      mute_symptoms: true
      auto_clear_with_root: true
    - id: storm
      name: "Sensor storm"
      mode: auto_cluster
      match: [{pattern: sensors}]
      min_count: 2
      window_ms: 2000
      show_as_single: true
      representative: first
"""


def write_config(folder: Path, *, conf: int = -3, auto: float = 0.0) -> Path:
    """A fault manager parameter file with per-entity thresholds and correlation rules."""
    (folder / "entities.yaml").write_text(ENTITIES)
    (folder / "correlation.yaml").write_text(CORRELATION)
    path = folder / "fault_manager.yaml"
    path.write_text(FAULT_MANAGER.format(conf=conf, auto=auto))
    return path


def failed(
    t_s: float, code: str, severity: int = 2, source: str = "/robot/base", **more: object
) -> dict[str, object]:
    return {
        "t_ns": round(t_s * S),
        "op": "report",
        "fault_code": code,
        "event_type": "FAILED",
        "severity": severity,
        "source_id": source,
        **more,
    }


def passed(t_s: float, code: str, source: str = "/robot/base") -> dict[str, object]:
    return {
        "t_ns": round(t_s * S),
        "op": "report",
        "fault_code": code,
        "event_type": "PASSED",
        "source_id": source,
    }


def clear(t_s: float, code: str) -> dict[str, object]:
    return {"t_ns": round(t_s * S), "op": "clear", "fault_code": code}


def write_script(folder: Path, lines: list[dict[str, object]], name: str = "run.jsonl") -> Path:
    """A JSON-lines script of these requests."""
    path = folder / name
    path.write_text("".join(json.dumps(line) + "\n" for line in lines))
    return path
