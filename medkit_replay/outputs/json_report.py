"""The JSON report, schema ``medkit-replay/report/v1`` (cli-and-report.md §3).

Schema history: v1 (0.1.0) — first version. Byte-identical for the same Result. Strict JSON:
every number in it is an integer (times, counts), and the encoders refuse NaN and Infinity.
"""

from __future__ import annotations

import json
from dataclasses import fields, is_dataclass
from operator import attrgetter
from typing import IO, TYPE_CHECKING, Any, Protocol, cast, get_args, get_origin, get_type_hints

from medkit_replay.captures import EvidenceRecording, SnapshotCapture
from medkit_replay.model import (
    CLEAR_ROWS,
    EVENT_ROWS,
    REPORT_ROWS,
    TRANSITION_ROWS,
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
from medkit_replay.outputs.json_rows import ROW_SEPARATOR, Chunk, RecordLines, Row
from medkit_replay.result import REPORT_SCHEMA
from medkit_replay.rows import RecordRows
from medkit_replay.spool import Spool

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Iterator, Sequence

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


class EncodedAhead(Protocol):
    """Spilled batches of the long lists already encoded as report lines (elsewhere)."""

    def encoded(self, spool: Spool[Any], index: int, /) -> bytes | None:
        """Batch ``index`` of ``spool`` as report lines, or None if it is not at hand."""
        ...


class _Rows:
    """A long list written batch by batch, so a long report is never held in memory whole."""

    def __init__(self, lines: RecordLines, records: Sequence[Any]) -> None:
        self.lines = lines
        self.records = records

    def dicts(self) -> list[JsonObject]:
        """Every record as the report lists it."""
        return [self.lines.as_dict(r) for r in self.records]

    def chunks(self, ahead: EncodedAhead | None = None) -> Iterator[Chunk]:
        """The records as report lines, in batches; spooled rows are never made records, and a
        batch ``ahead`` holds already is taken as it is."""
        records = self.records
        if not (isinstance(records, Spool) and isinstance(records.codec, RecordRows)):
            yield from self.lines.chunks(records)
            return
        for index in range(records.batch_count):
            done = ahead.encoded(records, index) if ahead is not None else None
            if done is None:
                yield from encode_batch(self.lines, records.codec, records.row_batch(index))
            elif done:
                yield done


def encode_batch(lines: RecordLines, codec: RecordRows[Any], rows: list[Row]) -> Iterator[Chunk]:
    """One batch of spooled rows as report lines (pieces to be joined by ROW_SEPARATOR)."""
    if rows:
        yield from lines.row_chunks([rows], codec.names, codec.decode)


_EVENTS = RecordLines(FaultEvent, event_dict)
_TRANSITIONS = RecordLines(Transition, transition_dict)
_REPORTS = RecordLines(ReportRecord, report_dict)
_CLEARS = RecordLines(ClearRecord, clear_dict)
_NEAR_MISSES = RecordLines(NearMiss, near_miss_dict)
SPOOLED_LISTS: dict[str, tuple[RecordLines, RecordRows[Any]]] = {
    "FaultEvent": (_EVENTS, EVENT_ROWS),
    "Transition": (_TRANSITIONS, TRANSITION_ROWS),
    "ReportRecord": (_REPORTS, REPORT_ROWS),
    "ClearRecord": (_CLEARS, CLEAR_ROWS),
}
"""The long lists the replay spools, by record class name: how their rows are written."""


def _sections(result: Result) -> list[tuple[str, object]]:
    """The report's keys in the contract's order; long lists stay lazy."""
    summary = result.summary
    return [
        ("schema", REPORT_SCHEMA),
        ("tool_version", result.tool_version),
        ("upstream_release", result.upstream_release),
        ("inputs", [input_dict(i) for i in result.inputs]),
        ("faults", [fault_dict(f) for f in result.faults]),
        ("events", _Rows(_EVENTS, result.events)),
        ("transitions", _Rows(_TRANSITIONS, result.transitions)),
        ("reports", _Rows(_REPORTS, result.reports)),
        ("clears", _Rows(_CLEARS, result.clears)),
        ("muted_faults", [muted_dict(m) for m in result.muted_faults]),
        ("clusters", [cluster_dict(c) for c in result.clusters]),
        ("near_misses", _Rows(_NEAR_MISSES, result.near_misses)),
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
        key: value.dicts() if isinstance(value, _Rows) else value
        for key, value in _sections(result)
    }


def _dump(value: object) -> bytes:
    text = json.dumps(value, indent=2, ensure_ascii=True, allow_nan=False)
    return text.replace("\n", "\n  ").encode("ascii")


def report_chunks(result: Result, ahead: EncodedAhead | None = None) -> Iterator[Chunk]:
    """The report as ASCII bytes, piece by piece, keys in the contract's order.

    Small sections are indented; the long record lists (events, transitions, reports,
    clears, near misses) hold one record per line, which keeps the file greppable and
    diffable (and lets them be encoded in bulk: ``outputs/json_rows.py``).
    """
    yield b"{"
    for number, (key, value) in enumerate(_sections(result)):
        yield ("," if number else "").encode() + b"\n  " + json.dumps(key).encode() + b": "
        if not isinstance(value, _Rows):
            yield _dump(value)
            continue
        empty = True
        for chunk in value.chunks(ahead):
            yield b"[\n    " if empty else ROW_SEPARATOR
            yield chunk
            empty = False
        yield b"[]" if empty else b"\n  ]"
    yield b"\n}\n"


def write_json_bytes(result: Result, stream: IO[bytes], ahead: EncodedAhead | None = None) -> None:
    """Stream the report to a binary stream (ASCII-only); ``ahead`` may hold batches of the
    long lists already encoded."""
    for chunk in report_chunks(result, ahead):
        stream.write(chunk)


def write_json(result: Result, stream: IO[str]) -> None:
    """Stream the report to a text stream (ASCII-only)."""
    for chunk in report_chunks(result):
        stream.write(str(chunk, "ascii"))


def dumps(result: Result) -> str:
    """The report as text (held in memory; prefer write_json for big recordings)."""
    return b"".join(report_chunks(result)).decode("ascii")
