"""The JSON report, schema ``medkit-replay/report/v1`` (cli-and-report.md §3).

Schema history: v1 (0.1.0) — first version. Byte-identical for the same Result. Strict JSON:
every number in it is an integer (times, counts), and the encoders refuse NaN and Infinity.
"""

from __future__ import annotations

import io
import json
from dataclasses import fields, is_dataclass
from operator import attrgetter
from typing import IO, TYPE_CHECKING, Any, cast, get_args, get_origin, get_type_hints

from medkit_replay.model import (
    ClearRecord,
    Cluster,
    EvidenceRecording,
    FaultEvent,
    FaultSnapshot,
    InputSummary,
    MutedFault,
    NearMiss,
    ReportRecord,
    SnapshotCapture,
    Transition,
)
from medkit_replay.result import REPORT_SCHEMA

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable

    from medkit_replay.result import Result

JsonObject = dict[str, object]


def record_dict(cls: type[Any]) -> Callable[[Any], JsonObject]:
    """The report's form of a record class: its fields in declaration order, tuples as lists,
    nested records as objects. Built once per class from the class itself."""
    names = tuple(field.name for field in fields(cls))
    hints = get_type_hints(cls)
    convert: list[tuple[str, Callable[[Any], object]]] = []
    for name in names:
        hint = hints[name]
        if get_origin(hint) is tuple:
            item = get_args(hint)[0]
            if is_dataclass(item):
                convert.append((name, _each(record_dict(cast("type[Any]", item)))))
            else:
                convert.append((name, list))
        elif is_dataclass(hint):
            convert.append((name, record_dict(cast("type[Any]", hint))))
    get = attrgetter(*names)

    def as_dict(record: Any) -> JsonObject:
        built = dict(zip(names, get(record), strict=True))
        for name, function in convert:
            built[name] = function(built[name])
        return built

    as_dict.__doc__ = f"A {cls.__name__} as the report lists it."
    return as_dict


def _each(as_dict: Callable[[Any], JsonObject]) -> Callable[[Any], object]:
    def each(items: Iterable[Any]) -> list[JsonObject]:
        return [as_dict(item) for item in items]

    return each


fault_dict = record_dict(FaultSnapshot)
event_dict = record_dict(FaultEvent)
transition_dict = record_dict(Transition)
report_dict = record_dict(ReportRecord)
clear_dict = record_dict(ClearRecord)
muted_dict = record_dict(MutedFault)
cluster_dict = record_dict(Cluster)
near_miss_dict = record_dict(NearMiss)
input_dict = record_dict(InputSummary)
snapshot_dict = record_dict(SnapshotCapture)
recording_dict = record_dict(EvidenceRecording)


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
        ("snapshots", [snapshot_dict(s) for s in result.snapshots]),
        ("recordings", [recording_dict(r) for r in result.recordings]),
        ("evidence_notes", list(result.evidence_notes)),
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
