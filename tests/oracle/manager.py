"""The fault manager node's report handling written plainly, with request and record objects.

An oracle for ``FaultManager.report_fields``: it drives a manager's own storage, resolver and
correlation engine and appends records to its (list) output, as the node did before speed work.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.engine.correlation.engine import severity_name
from medkit_replay.engine.debounce import DebounceConfig, sanitize
from medkit_replay.engine.validation import report_error
from medkit_replay.model import (
    EventKind,
    FaultEvent,
    ReportRecord,
    ReportRequest,
    RetroactiveMute,
    Transition,
)

if TYPE_CHECKING:
    from medkit_replay.engine.manager import FaultManager
    from medkit_replay.engine.storage import FaultRecord

_NAMES = {0: "FAILED", 1: "PASSED"}


def oracle_report(manager: FaultManager, request: ReportRequest) -> bool:
    """Handle one ReportFault request on ``manager`` the plain way; returns ``accepted``."""
    output = manager.output
    reason = report_error(
        request.fault_code,
        request.event_type,
        request.severity,
        request.source_id,
        manager.config.release.max_fault_code_length,
    )
    if reason is not None:
        _record(manager, request, reason, None, None)
        return False
    config = sanitize(manager.resolver.resolve(request.source_id))
    before, after, is_new = manager.storage.report(
        request.fault_code,
        request.event_type,
        request.severity,
        request.description,
        request.source_id,
        request.t_ns,
        config,
    )
    fault = manager.storage.faults.get(request.fault_code)
    if fault is None:
        _record(manager, request, None, None, config)
        return True
    if before != after and after is not None:
        output.transitions.append(
            Transition(
                t_ns=request.t_ns,
                fault_code=request.fault_code,
                from_status=before,
                to_status=after,
                cause="report",
                source_id=request.source_id,
            )
        )
    muted = False
    if manager.correlation is not None and request.event_type == 0:
        result = manager.correlation.process_fault(
            request.fault_code, severity_name(request.severity), request.t_ns
        )
        muted = result.should_mute
        if result.retroactive_mute_codes:
            output.retroactive_mutes.append(
                RetroactiveMute(
                    t_ns=request.t_ns,
                    cluster_id=result.cluster_id,
                    fault_codes=result.retroactive_mute_codes,
                )
            )
    kind: EventKind | None = None
    if after == "CONFIRMED":
        again = not is_new and before == "CONFIRMED"
        kind = "fault_updated" if again else "fault_confirmed"
    _record(
        manager,
        request,
        None,
        fault,
        config,
        withheld=kind if muted else None,
    )
    if kind is not None and not muted:
        _event(manager, request.t_ns, kind, fault)
    if not is_new and before != "HEALED" and after == "HEALED":
        _event(manager, request.t_ns, "fault_cleared", fault)
    return True


def _event(manager: FaultManager, t_ns: int, kind: EventKind, fault: FaultRecord) -> None:
    counts = manager.output.event_counts
    counts[kind] = counts.get(kind, 0) + 1
    _count(manager.output.published_by_code, fault.fault_code, kind)
    manager.output.events.append(
        FaultEvent(t_ns=t_ns, event_type=kind, fault=manager.snapshot(fault))
    )


def _record(
    manager: FaultManager,
    request: ReportRequest,
    reason: str | None,
    fault: FaultRecord | None,
    config: DebounceConfig | None,
    *,
    withheld: EventKind | None = None,
) -> None:
    if reason is None:
        manager.output.reports_accepted += 1
    if withheld is not None:
        _count(manager.output.withheld_by_code, request.fault_code, withheld)
    manager.output.reports.append(
        ReportRecord(
            t_ns=request.t_ns,
            origin=request.origin,
            topic=request.topic,
            fault_code=request.fault_code,
            event_type=_NAMES.get(request.event_type, str(request.event_type)),
            severity=request.severity,
            description=request.description,
            source_id=request.source_id,
            accepted=reason is None,
            reject_reason=reason,
            status=fault.status if fault is not None else None,
            debounce_counter=fault.counter if fault is not None else None,
            confirmation_threshold=config.confirmation_threshold if config else None,
            healing_threshold=config.healing_threshold if config else None,
            withheld_event=withheld,
        )
    )


def _count(by_code: dict[str, dict[str, int]], code: str, kind: str) -> None:
    counts = by_code.setdefault(code, {})
    counts[kind] = counts.get(kind, 0) + 1
