"""The JSON report, schema ``medkit-replay/report/v1`` (cli-and-report.md §3).

Schema history: v1 (0.1.0) — first version. Byte-identical for the same Result. Strict JSON:
every number in it is an integer (times, counts), and the encoders refuse NaN and Infinity.
"""

from __future__ import annotations

import io
import json
from typing import IO, TYPE_CHECKING

from medkit_replay.result import REPORT_SCHEMA

if TYPE_CHECKING:
    from medkit_replay.model import (
        ClearRecord,
        Cluster,
        FaultEvent,
        FaultSnapshot,
        InputSummary,
        MutedFault,
        NearMiss,
        ReportRecord,
        Transition,
    )
    from medkit_replay.result import Result

if TYPE_CHECKING:
    from collections.abc import Iterable

JsonObject = dict[str, object]


def fault_dict(fault: FaultSnapshot) -> JsonObject:
    """A fault as the report lists it."""
    return {
        "fault_code": fault.fault_code,
        "severity": fault.severity,
        "description": fault.description,
        "first_occurred_ns": fault.first_occurred_ns,
        "last_occurred_ns": fault.last_occurred_ns,
        "last_passed_ns": fault.last_passed_ns,
        "occurrence_count": fault.occurrence_count,
        "status": fault.status,
        "reporting_sources": list(fault.reporting_sources),
        "muted": fault.muted,
        "root_cause_code": fault.root_cause_code,
        "cluster_ids": list(fault.cluster_ids),
    }


def event_dict(event: FaultEvent) -> JsonObject:
    """A FaultEvent as the report lists it."""
    return {
        "t_ns": event.t_ns,
        "event_type": event.event_type,
        "fault": fault_dict(event.fault),
        "auto_cleared_codes": list(event.auto_cleared_codes),
    }


def transition_dict(transition: Transition) -> JsonObject:
    """A status change."""
    return {
        "t_ns": transition.t_ns,
        "fault_code": transition.fault_code,
        "from_status": transition.from_status,
        "to_status": transition.to_status,
        "cause": transition.cause,
        "source_id": transition.source_id,
    }


def report_dict(report: ReportRecord) -> JsonObject:
    """A ReportFault request and its verdict."""
    return {
        "t_ns": report.t_ns,
        "origin": report.origin,
        "topic": report.topic,
        "fault_code": report.fault_code,
        "event_type": report.event_type,
        "severity": report.severity,
        "description": report.description,
        "source_id": report.source_id,
        "accepted": report.accepted,
        "reject_reason": report.reject_reason,
        "status": report.status,
        "debounce_counter": report.debounce_counter,
        "confirmation_threshold": report.confirmation_threshold,
        "healing_threshold": report.healing_threshold,
        "withheld_event": report.withheld_event,
    }


def clear_dict(clear: ClearRecord) -> JsonObject:
    """A ClearFault request and its response."""
    return {
        "t_ns": clear.t_ns,
        "fault_code": clear.fault_code,
        "skip_correlation_auto_clear": clear.skip_correlation_auto_clear,
        "success": clear.success,
        "message": clear.message,
        "auto_cleared_codes": list(clear.auto_cleared_codes),
    }


def muted_dict(muted: MutedFault) -> JsonObject:
    """A MutedFaultInfo."""
    return {
        "fault_code": muted.fault_code,
        "root_cause_code": muted.root_cause_code,
        "rule_id": muted.rule_id,
        "delay_ms": muted.delay_ms,
    }


def cluster_dict(cluster: Cluster) -> JsonObject:
    """A ClusterInfo with bag times."""
    return {
        "cluster_id": cluster.cluster_id,
        "rule_id": cluster.rule_id,
        "rule_name": cluster.rule_name,
        "label": cluster.label,
        "representative_code": cluster.representative_code,
        "representative_severity": cluster.representative_severity,
        "fault_codes": list(cluster.fault_codes),
        "count": cluster.count,
        "first_at_ns": cluster.first_at_ns,
        "last_at_ns": cluster.last_at_ns,
    }


def near_miss_dict(near_miss: NearMiss) -> JsonObject:
    """A near-miss record."""
    return {
        "fault_code": near_miss.fault_code,
        "t_ns": near_miss.t_ns,
        "debounce_counter": near_miss.debounce_counter,
        "confirmation_threshold": near_miss.confirmation_threshold,
        "severity": near_miss.severity,
        "source_id": near_miss.source_id,
        "resulting_status": near_miss.resulting_status,
    }


def input_dict(summary: InputSummary) -> JsonObject:
    """One input file and the topics it held."""
    return {
        "path": summary.path,
        "storage": summary.storage,
        "start_ns": summary.start_ns,
        "end_ns": summary.end_ns,
        "message_count": summary.message_count,
        "topics": [
            {"topic": t.topic, "type": t.type, "role": t.role, "messages": t.messages}
            for t in summary.topics
        ],
    }


class _Rows:
    """A list written item by item, so a long report is never held in memory whole."""

    def __init__(self, items: Iterable[JsonObject]) -> None:
        self.items = items


def _sections(result: Result) -> list[tuple[str, object]]:
    """The report's keys in the contract's order; long lists stay lazy."""
    summary = result.summary
    return [
        ("schema", REPORT_SCHEMA),
        ("tool_version", result.tool_version),
        ("inputs", [input_dict(i) for i in result.inputs]),
        ("faults", [fault_dict(f) for f in result.faults]),
        ("events", _Rows(event_dict(e) for e in result.events)),
        ("transitions", _Rows(transition_dict(t) for t in result.transitions)),
        ("reports", _Rows(report_dict(r) for r in result.reports)),
        ("clears", _Rows(clear_dict(c) for c in result.clears)),
        ("muted_faults", [muted_dict(m) for m in result.muted_faults]),
        ("clusters", [cluster_dict(c) for c in result.clusters]),
        ("near_misses", _Rows(near_miss_dict(n) for n in result.near_misses)),
        (
            "retroactive_cluster_mutes",
            [
                {"t_ns": r.t_ns, "cluster_id": r.cluster_id, "fault_codes": list(r.fault_codes)}
                for r in result.retroactive_mutes
            ],
        ),
        ("parity", result.parity),
        ("warnings", list(result.warnings)),
        (
            "summary",
            {
                "messages_read": summary.messages_read,
                "reports": summary.reports,
                "reports_accepted": summary.reports_accepted,
                "reports_rejected": summary.reports_rejected,
                "clears": summary.clears,
                "events": dict(summary.events),
                "faults": summary.faults,
                "faults_by_status": dict(summary.faults_by_status),
                "transitions": summary.transitions,
                "start_ns": summary.start_ns,
                "end_ns": summary.end_ns,
                "duration_ns": summary.duration_ns,
            },
        ),
    ]


def to_report(result: Result) -> JsonObject:
    """The whole report as a JSON-ready dict (materialises every list)."""
    return {
        key: list(value.items) if isinstance(value, _Rows) else value
        for key, value in _sections(result)
    }


def _dump(value: object, indent: str) -> str:
    text = json.dumps(value, indent=2, ensure_ascii=True, allow_nan=False)
    return text.replace("\n", "\n" + indent)


_ROW = json.JSONEncoder(ensure_ascii=True, separators=(", ", ": "), allow_nan=False)


def write_json(result: Result, stream: IO[str]) -> None:
    """Stream the report, ASCII-only, keys in the contract's order.

    Small sections are indented; the long record lists (events, transitions, reports,
    clears, near misses) hold one record per line, which keeps the file greppable and
    diffable and lets the C encoder write them (an indenting encoder is pure Python).
    """
    stream.write("{")
    for number, (key, value) in enumerate(_sections(result)):
        stream.write(("," if number else "") + f"\n  {json.dumps(key)}: ")
        if not isinstance(value, _Rows):
            stream.write(_dump(value, "  "))
            continue
        empty = True
        for item in value.items:
            stream.write(("[\n    " if empty else ",\n    ") + _ROW.encode(item))
            empty = False
        stream.write("[]" if empty else "\n  ]")
    stream.write("\n}\n")


def dumps(result: Result) -> str:
    """The report as text (held in memory; prefer write_json for big recordings)."""
    buffer = io.StringIO()
    write_json(result, buffer)
    return buffer.getvalue()
