"""Builders and runners for end-to-end pipeline tests: recordings written in tmp_path, JSON reports.

Messages are built with the same typestore the replay decodes with; bags are written with
rosbags' Writer through tests.inputs.builders.write_bag, in MCAP or sqlite3 storage.
"""

from __future__ import annotations

import json
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from medkit_replay.cli import main
from medkit_replay.outputs.json_report import to_report
from medkit_replay.pipeline import replay
from tests.inputs.builders import TS, Rec, stamp, write_bag

if TYPE_CHECKING:
    from collections.abc import Iterable, Sequence
    from pathlib import Path

    import pytest

    from tests.inputs.builders import Storage

SEC = 1_000_000_000
MS = 1_000_000
SCHEMA = "medkit-replay/report/v1"

DIAGNOSTICS = "diagnostic_msgs/msg/DiagnosticArray"
GOAL_STATUS_ARRAY = "action_msgs/msg/GoalStatusArray"
REPORT_FAULT = "ros2_medkit_msgs/srv/ReportFault_Event"
CLEAR_FAULT = "ros2_medkit_msgs/srv/ClearFault_Event"
FAULT_EVENT = "ros2_medkit_msgs/msg/FaultEvent"
REPORT_TOPIC = "/fault_manager/report_fault/_service_event"
CLEAR_TOPIC = "/fault_manager/clear_fault/_service_event"
EVENTS_TOPIC = "/fault_manager/events"

# service_msgs/msg/ServiceEventInfo.event_type
REQUEST_SENT = 0
REQUEST_RECEIVED = 1
RESPONSE_SENT = 2
RESPONSE_RECEIVED = 3

# diagnostic_msgs/msg/DiagnosticStatus levels
OK, WARN, ERROR, STALE = 0, 1, 2, 3
# action_msgs/msg/GoalStatus
EXECUTING, SUCCEEDED, CANCELED, ABORTED = 2, 4, 5, 6

Report = dict[str, Any]

# The keys cli-and-report.md §3 fixes; a report may carry more (added freely).
REPORT_KEYS = (
    "t_ns",
    "origin",
    "topic",
    "fault_code",
    "event_type",
    "severity",
    "description",
    "source_id",
    "accepted",
    "reject_reason",
)
TRANSITION_KEYS = ("t_ns", "fault_code", "from_status", "to_status", "cause", "source_id")


def new(msgtype: str, /, **fields: Any) -> Any:
    """A message object of ``msgtype`` from the replay's own typestore."""
    return TS.types[msgtype](**fields)


# --- /diagnostics -------------------------------------------------------------------------------


def status(
    name: str,
    level: int,
    message: str = "",
    *,
    hardware_id: str = "",
    values: Iterable[tuple[str, str]] = (),
) -> Any:
    """One diagnostic_msgs/msg/DiagnosticStatus."""
    return new(
        "diagnostic_msgs/msg/DiagnosticStatus",
        level=level,
        name=name,
        message=message,
        hardware_id=hardware_id,
        values=[new("diagnostic_msgs/msg/KeyValue", key=k, value=v) for k, v in values],
    )


def diagnostics(t_ns: int, *statuses: Any, topic: str = "/diagnostics") -> Rec:
    """A DiagnosticArray holding ``statuses`` in order."""
    header = new("std_msgs/msg/Header", stamp=stamp(t_ns), frame_id="")
    msg = new(DIAGNOSTICS, header=header, status=list(statuses))
    return Rec(topic, DIAGNOSTICS, t_ns, msg)


# --- action status ------------------------------------------------------------------------------


def goals(t_ns: int, action: str, *states: int) -> Rec:
    """A GoalStatusArray on ``<action>/_action/status``, one goal per state (distinct ids)."""
    goal_list = []
    for index, state in enumerate(states):
        uuid = np.full(16, index + 1, dtype=np.uint8)
        info = new(
            "action_msgs/msg/GoalInfo",
            goal_id=new("unique_identifier_msgs/msg/UUID", uuid=uuid),
            stamp=stamp(t_ns),
        )
        goal_list.append(new("action_msgs/msg/GoalStatus", goal_info=info, status=state))
    msg = new(GOAL_STATUS_ARRAY, status_list=goal_list)
    return Rec(f"{action}/_action/status", GOAL_STATUS_ARRAY, t_ns, msg)


# --- service events -----------------------------------------------------------------------------


def _info(t_ns: int, kind: int, gid: int, sequence: int) -> Any:
    return new(
        "service_msgs/msg/ServiceEventInfo",
        event_type=kind,
        stamp=stamp(t_ns),
        client_gid=np.full(16, gid, dtype=np.uint8),
        sequence_number=sequence,
    )


def report_event(
    t_ns: int,
    kind: int,
    code: str,
    *,
    event_type: int = 0,
    severity: int = 2,
    description: str = "",
    source_id: str = "/motor",
    gid: int = 7,
    sequence: int = 1,
    accepted: bool = True,
    contents: bool = True,
    topic: str = REPORT_TOPIC,
) -> Rec:
    """One ReportFault service event: REQUEST_* carry the request, RESPONSE_* the response.

    ``contents=False`` writes it as metadata-only introspection does: no payload at all.
    """
    request: list[Any] = []
    response: list[Any] = []
    if contents and kind in (REQUEST_SENT, REQUEST_RECEIVED):
        request = [
            new(
                "ros2_medkit_msgs/srv/ReportFault_Request",
                fault_code=code,
                event_type=event_type,
                severity=severity,
                description=description,
                source_id=source_id,
            )
        ]
    elif contents:
        response = [new("ros2_medkit_msgs/srv/ReportFault_Response", accepted=accepted)]
    msg = new(
        REPORT_FAULT, info=_info(t_ns, kind, gid, sequence), request=request, response=response
    )
    return Rec(topic, REPORT_FAULT, t_ns, msg)


def report_call(
    times: Sequence[int],
    code: str,
    *,
    kinds: Sequence[int] = (REQUEST_SENT, REQUEST_RECEIVED, RESPONSE_SENT, RESPONSE_RECEIVED),
    **fields: Any,
) -> list[Rec]:
    """The copies of one ReportFault call, ``kinds[i]`` logged at ``times[i]``."""
    assert len(times) == len(kinds)
    return [report_event(t, k, code, **fields) for t, k in zip(times, kinds, strict=True)]


def clear_event(
    t_ns: int,
    kind: int,
    code: str,
    *,
    gid: int = 9,
    sequence: int = 1,
    success: bool = True,
    contents: bool = True,
) -> Rec:
    """One ClearFault service event (request on REQUEST_*, response on RESPONSE_*)."""
    request: list[Any] = []
    response: list[Any] = []
    if contents and kind in (REQUEST_SENT, REQUEST_RECEIVED):
        request = [
            new(
                "ros2_medkit_msgs/srv/ClearFault_Request",
                fault_code=code,
                skip_correlation_auto_clear=False,
            )
        ]
    elif contents:
        response = [
            new(
                "ros2_medkit_msgs/srv/ClearFault_Response",
                success=success,
                message=f"Fault cleared: {code}",
                auto_cleared_codes=[],
            )
        ]
    msg = new(
        CLEAR_FAULT, info=_info(t_ns, kind, gid, sequence), request=request, response=response
    )
    return Rec(CLEAR_TOPIC, CLEAR_FAULT, t_ns, msg)


# --- the live manager's FaultEvents -------------------------------------------------------------


def fault_event(
    t_ns: int,
    event_type: str,
    code: str,
    *,
    status: str = "CONFIRMED",
    severity: int = 2,
    occurrence_count: int = 1,
    sources: Sequence[str] = ("/motor",),
    description: str = "",
    auto_cleared_codes: Sequence[str] = (),
    topic: str = EVENTS_TOPIC,
) -> Rec:
    """A ros2_medkit_msgs/msg/FaultEvent as the live fault manager publishes it."""
    fault = new(
        "ros2_medkit_msgs/msg/Fault",
        fault_code=code,
        severity=severity,
        description=description,
        first_occurred=stamp(t_ns),
        last_occurred=stamp(t_ns),
        last_passed=stamp(0),
        occurrence_count=occurrence_count,
        status=status,
        reporting_sources=list(sources),
    )
    msg = new(
        FAULT_EVENT,
        event_type=event_type,
        fault=fault,
        timestamp=stamp(t_ns),
        auto_cleared_codes=list(auto_cleared_codes),
    )
    return Rec(topic, FAULT_EVENT, t_ns, msg)


# --- recordings, configs and runs ---------------------------------------------------------------


def on_topic(rec: Rec, topic: str) -> Rec:
    """The same message on another topic."""
    return replace(rec, topic=topic)


def bag(
    tmp_path: Path, name: str, records: Iterable[Rec], storage: Storage, **options: Any
) -> Path:
    """A rosbag2 directory ``tmp_path/name`` holding ``records`` in the given order."""
    return write_bag(tmp_path / name, list(records), storage=storage, **options)


def config(tmp_path: Path, text: str, name: str = "params.yaml") -> Path:
    """A ROS 2 parameter file in tmp_path."""
    path = tmp_path / name
    path.write_text(text)
    return path


def run(inputs: Sequence[Path], configs: Sequence[Path] = ()) -> Report:
    """The replay's JSON report as a dict (the Python API, same content as --json)."""
    report = to_report(replay(list(inputs), list(configs)))
    # Round-trip through JSON so the dict holds exactly what the file would.
    result: Report = json.loads(json.dumps(report))
    return result


def run_cli(
    args: Sequence[str], out: Path, capsys: pytest.CaptureFixture[str]
) -> tuple[int, Report | None, str]:
    """``medkit-replay analyze ARGS --json OUT --quiet``: exit status, parsed report, stderr."""
    status_code = main(["analyze", *args, "--json", str(out), "--quiet"])
    captured = capsys.readouterr()
    assert "Traceback" not in captured.out + captured.err
    report: Report | None = None
    if status_code == 0:
        report = json.loads(out.read_text())
    return status_code, report, captured.err


def contract(row: Report, keys: Sequence[str]) -> Report:
    """The contract's keys of one row (all of them must be there)."""
    return {key: row[key] for key in keys}


def reports(report: Report, *keys: str) -> list[tuple[Any, ...]]:
    """The ``reports`` rows as tuples of the given keys."""
    return [tuple(r[k] for k in keys) for r in report["reports"]]


def events(report: Report) -> list[tuple[int, str, str, str]]:
    """(t_ns, event_type, fault_code, status) of every replayed event."""
    return [
        (e["t_ns"], e["event_type"], e["fault"]["fault_code"], e["fault"]["status"])
        for e in report["events"]
    ]


def fault(report: Report, code: str) -> Report:
    """The final state of one fault (fails the test when the fault is absent)."""
    found: list[Report] = [f for f in report["faults"] if f["fault_code"] == code]
    assert len(found) == 1, f"{code} not among {[f['fault_code'] for f in report['faults']]}"
    return found[0]


def warnings_with(report: Report, needle: str) -> list[str]:
    """The report's warnings that contain ``needle``."""
    return [w for w in report["warnings"] if needle in w]
