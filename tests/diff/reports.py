"""Small hand-made reports (schema medkit-replay/report/v1) for diff tests."""

from __future__ import annotations

import copy
from typing import Any

SEC = 1_000_000_000
START = 1_000 * SEC
Report = dict[str, Any]


def fault(code: str, status: str = "CONFIRMED", **fields: object) -> dict[str, object]:
    """A fault as the report lists it."""
    value: dict[str, object] = {
        "fault_code": code,
        "severity": 2,
        "description": "d",
        "first_occurred_ns": START + SEC,
        "last_occurred_ns": START + SEC,
        "last_passed_ns": 0,
        "occurrence_count": 1,
        "status": status,
        "reporting_sources": ["/node"],
        "muted": False,
        "root_cause_code": None,
        "cluster_ids": [],
    }
    value.update(fields)
    return value


def transition(
    code: str, t_s: float, to: str, origin: str | None = None, cause: str = "report"
) -> dict[str, object]:
    """A status change ``t_s`` seconds after the start."""
    return {
        "t_ns": START + round(t_s * SEC),
        "fault_code": code,
        "from_status": origin,
        "to_status": to,
        "cause": cause,
        "source_id": "/node" if cause == "report" else None,
    }


def event(code: str, t_s: float, kind: str) -> dict[str, object]:
    """A FaultEvent ``t_s`` seconds after the start."""
    return {
        "t_ns": START + round(t_s * SEC),
        "event_type": kind,
        "fault": fault(code),
        "auto_cleared_codes": [],
    }


def cluster(cluster_id: str, codes: list[str]) -> dict[str, object]:
    """An active cluster."""
    return {
        "cluster_id": cluster_id,
        "rule_id": cluster_id.rsplit("_", 1)[0],
        "rule_name": "Storm",
        "label": "Storm",
        "representative_code": codes[0],
        "representative_severity": "ERROR",
        "fault_codes": codes,
        "count": len(codes),
        "first_at_ns": START + SEC,
        "last_at_ns": START + SEC,
    }


def base_report() -> Report:
    """Two faults (one healed, one confirmed and clustered) and one cluster."""
    return copy.deepcopy(
        {
            "schema": "medkit-replay/report/v1",
            "tool_version": "0.1.0",
            "inputs": [{"path": "run.jsonl", "storage": "jsonl", "start_ns": START}],
            "faults": [
                fault("LIDAR_SCAN_RATE", "CONFIRMED", cluster_ids=["storm_1"]),
                fault("MOTOR_OVERHEAT", "HEALED", last_passed_ns=START + 5 * SEC),
            ],
            "events": [
                event("LIDAR_SCAN_RATE", 1.0, "fault_confirmed"),
                event("MOTOR_OVERHEAT", 2.0, "fault_confirmed"),
                event("MOTOR_OVERHEAT", 3.0, "fault_updated"),
                event("MOTOR_OVERHEAT", 5.0, "fault_cleared"),
            ],
            "transitions": [
                transition("LIDAR_SCAN_RATE", 1.0, "CONFIRMED"),
                transition("MOTOR_OVERHEAT", 2.0, "CONFIRMED"),
                transition("MOTOR_OVERHEAT", 5.0, "HEALED", "CONFIRMED"),
            ],
            "clusters": [cluster("storm_1", ["LIDAR_SCAN_RATE"])],
            "summary": {"start_ns": START},
        }
    )
