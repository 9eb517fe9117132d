"""A replay written plainly: rosbags decodes every message, chunks are read whole, bridges and the
manager handle request and record objects one by one (the shape of the replay before speed work).

An oracle for ``medkit_replay.replay``: the report sections the engine produces must agree.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.bridges.action_status import ActionStatusBridge
from medkit_replay.bridges.diagnostic import DiagnosticBridge
from medkit_replay.bridges.log import LogBridge
from medkit_replay.bridges.service_calls import ServiceCallReplayer
from medkit_replay.config.fault_manager import fault_manager_config
from medkit_replay.config.params import load_parameters
from medkit_replay.config.replay_options import replay_options
from medkit_replay.engine.manager import FaultManager
from medkit_replay.engine.timeline import Timeline
from medkit_replay.inputs import open_recording
from medkit_replay.model import ClearRequest, ReportRequest
from medkit_replay.outputs.json_report import (
    clear_dict,
    cluster_dict,
    event_dict,
    fault_dict,
    muted_dict,
    near_miss_dict,
    report_dict,
    transition_dict,
)
from tests.oracle.bridges import oracle_diagnostic, oracle_log
from tests.oracle.manager import oracle_report

if TYPE_CHECKING:
    from collections.abc import Sequence
    from pathlib import Path

ENGINE_SECTIONS = (
    "faults",
    "events",
    "transitions",
    "reports",
    "clears",
    "muted_faults",
    "clusters",
    "near_misses",
    "summary",
)
"""The report's keys the oracle reproduces: everything the engine concludes."""

_BRIDGES = ("diagnostic_bridge", "action_status_bridge", "log_bridge")


def oracle_sections(inputs: Sequence[Path], configs: Sequence[Path]) -> dict[str, object]:
    """The engine's report sections for ``inputs`` under ``configs``, computed plainly."""
    params = load_parameters(configs)
    manager_config, _ = fault_manager_config(params.node("fault_manager"))
    options, _ = replay_options(params)
    manager = FaultManager(manager_config)  # records as objects in plain lists
    timeline = Timeline(manager)
    diagnostic = DiagnosticBridge(options.diagnostic)
    action = ActionStatusBridge(options.action_status, action_sources=options.action_sources)
    log = LogBridge(options.log) if options.log_bridge else None
    services = ServiceCallReplayer()
    recorded = _recorded_codes(inputs)
    messages = 0
    with open_recording(
        list(inputs),
        rosout=log is not None,
        diagnostics_topics=(diagnostic.topic,),
        rosout_topic=log.topic if log is not None else "/rosout",
        light=False,
        reference=True,
    ) as recording:
        for message in recording.messages():
            messages += 1
            timeline.advance(message.t_ns)
            t_ns, topic, msg = message.t_ns, message.topic, message.msg
            requests: Sequence[ReportRequest | ClearRequest | tuple[object, ...]] = ()
            if message.role == "script":
                assert isinstance(msg, ReportRequest | ClearRequest)
                requests = (msg,)
            elif message.role == "action_status":
                requests = action.on_message(t_ns, topic, msg)
            elif message.role in ("report_fault", "clear_fault"):
                requests = services.on_message(t_ns, topic, message.msgtype, msg)
            elif diagnostic.wants(topic, message.msgtype):
                requests = oracle_diagnostic(diagnostic, t_ns, topic, msg)
            elif log is not None and log.wants(topic, message.msgtype):
                requests = oracle_log(log, t_ns, topic, msg)
            for request in requests:
                _apply(manager, _as_request(request), recorded)
    out = manager.output
    faults = manager.faults()
    correlation = manager.correlation
    accepted = out.reports_accepted
    by_status = dict.fromkeys(("PREFAILED", "PREPASSED", "CONFIRMED", "HEALED", "CLEARED"), 0)
    for fault in faults:
        by_status[fault.status] += 1
    kinds = ("fault_confirmed", "fault_updated", "fault_cleared")
    near = [
        near_miss_dict(entry)
        for code in sorted(manager.storage.near_misses, key=lambda c: c.encode("utf-8"))
        for entry in manager.storage.near_misses[code]
    ]
    start, end = timeline.t0_ns, timeline.last_ns
    return {
        "faults": [fault_dict(f) for f in faults],
        "events": [event_dict(e) for e in out.events],
        "transitions": [transition_dict(t) for t in out.transitions],
        "reports": [report_dict(r) for r in out.reports],
        "clears": [clear_dict(c) for c in out.clears],
        "muted_faults": [muted_dict(m) for m in correlation.muted_faults()] if correlation else [],
        "clusters": [cluster_dict(c) for c in correlation.clusters()] if correlation else [],
        "near_misses": near,
        "summary": {
            "messages_read": messages,
            "reports": len(out.reports),
            "reports_accepted": accepted,
            "reports_rejected": len(out.reports) - accepted,
            "clears": len(out.clears),
            "events": {kind: out.event_counts.get(kind, 0) for kind in kinds},
            "faults": len(faults),
            "faults_by_status": by_status,
            "transitions": len(out.transitions),
            "start_ns": start,
            "end_ns": end,
            "duration_ns": end - start if start is not None and end is not None else 0,
        },
    }


def _recorded_codes(inputs: Sequence[Path]) -> set[str]:
    """Codes in recorded ReportFault calls: the bridges' requests for them are not applied."""
    bags = [path for path in inputs if path.suffix != ".jsonl"]
    if not bags:
        return set()
    services = ServiceCallReplayer()
    codes: set[str] = set()
    with open_recording(
        bags, only_roles=("report_fault",), light=False, reference=True
    ) as recording:
        for message in recording.messages():
            for request in services.on_message(
                message.t_ns, message.topic, message.msgtype, message.msg
            ):
                codes.add(request.fault_code)
    return codes


def _as_request(
    request: ReportRequest | ClearRequest | tuple[object, ...],
) -> ReportRequest | ClearRequest:
    if not isinstance(request, tuple):
        return request
    t_ns, origin, topic, code, event_type, severity, description, source_id = request
    return ReportRequest(
        t_ns=t_ns,  # type: ignore[arg-type]
        origin=origin,  # type: ignore[arg-type]
        topic=topic,  # type: ignore[arg-type]
        fault_code=code,  # type: ignore[arg-type]
        event_type=event_type,  # type: ignore[arg-type]
        severity=severity,  # type: ignore[arg-type]
        description=description,  # type: ignore[arg-type]
        source_id=source_id,  # type: ignore[arg-type]
    )


def _apply(
    manager: FaultManager, request: ReportRequest | ClearRequest, recorded: set[str]
) -> None:
    if request.origin in _BRIDGES and request.fault_code in recorded:
        return  # recorded service traffic wins for this code
    if isinstance(request, ReportRequest):
        oracle_report(manager, request)
    else:
        manager.clear(request)
