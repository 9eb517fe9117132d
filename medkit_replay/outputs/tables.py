"""The report's tables as pandas DataFrames, and CSV files of them.

Built from one Result with the JSON report's field names; list fields stay Python lists. For
people, each nanosecond time gains seconds from the recording's start beside it, and each
severity number its name.
CSV cells that a spreadsheet would run as formulas are neutralised (outputs/csv_safety.py).
"""

from __future__ import annotations

import json
from dataclasses import fields
from numbers import Integral
from typing import TYPE_CHECKING, Any

import pandas as pd

from medkit_replay.model import (
    NS_PER_SEC,
    ClearRecord,
    Cluster,
    FaultSnapshot,
    MutedFault,
    NearMiss,
    ReportRecord,
    Transition,
)
from medkit_replay.outputs.atomic import atomic_text
from medkit_replay.outputs.csv_safety import write_frame
from medkit_replay.outputs.json_report import (
    clear_dict,
    cluster_dict,
    event_dict,
    fault_dict,
    muted_dict,
    near_miss_dict,
    recording_dict,
    report_dict,
    transition_dict,
)
from medkit_replay.outputs.muting import NO_EVENTS, event_counts, muting_sentence
from medkit_replay.text import severity_name

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.result import Result


def _columns(cls: type[Any]) -> list[str]:
    return [field.name for field in fields(cls)]


EVENT_COLUMNS = [
    "t_ns",
    "event_type",
    "fault_code",
    "status",
    "severity",
    "occurrence_count",
    "reporting_sources",
    "muted",
    "auto_cleared_codes",
]
"""The events table: each FaultEvent with the fields of its fault a table reader filters on."""
SNAPSHOT_COLUMNS = [
    "fault_code",
    "capture_id",
    "t_ns",
    "retained",
    "freeze_frame",
    "topic",
    "message_type",
    "message_t_ns",
    "data",
]
"""The snapshots table: one row per captured topic (``data`` as JSON text); a capture that
sampled nothing has one row with no topic."""
RECORDING_COLUMNS = [
    "recording_id",
    "fault_codes",
    "start_ns",
    "end_ns",
    "messages",
    "bytes",
    "deleted_ns",
    "deleted_reason",
    "path",
]
"""The recordings table: one row per black-box recording (its per-topic counts are in the JSON)."""
TIME_COLUMNS = frozenset(
    {
        "t_ns",
        "first_occurred_ns",
        "last_occurred_ns",
        "last_passed_ns",
        "first_at_ns",
        "last_at_ns",
        "message_t_ns",
        "start_ns",
        "end_ns",
        "deleted_ns",
    }
)
"""Bag-time columns (exact nanoseconds); each gets a seconds-from-start column beside it."""
SEVERITY_NAME = "severity_name"
"""The column beside ``severity`` naming it (INFO, WARN, ERROR, CRITICAL)."""
MUTING = "muting"
"""The muted-faults column saying which FaultEvents were withheld and published (muting.py)."""


def seconds_column(column: str) -> str:
    """The seconds-from-start column beside a time column: ``t_ns`` -> ``t_s``."""
    return column.removesuffix("_ns") + "_s"


SECONDS_COLUMNS = frozenset(seconds_column(c) for c in TIME_COLUMNS)
"""Seconds since the recording's start (float), for people; the ``_ns`` column stays exact.
Empty where the time is: ``last_passed_ns`` 0 (never passed)."""


def _for_people(columns: list[str]) -> list[str]:
    out: list[str] = []
    for column in columns:
        out.append(column)
        if column in TIME_COLUMNS:
            out.append(seconds_column(column))
        elif column == "severity":
            out.append(SEVERITY_NAME)
    return out


TABLE_COLUMNS: dict[str, list[str]] = {
    name: _for_people(columns)
    for name, columns in {
        "faults": _columns(FaultSnapshot),
        "events": EVENT_COLUMNS,
        "transitions": _columns(Transition),
        "reports": _columns(ReportRecord),
        "clears": _columns(ClearRecord),
        "muted_faults": [*_columns(MutedFault), MUTING],
        "clusters": _columns(Cluster),
        "near_misses": _columns(NearMiss),
        "snapshots": SNAPSHOT_COLUMNS,
        "recordings": RECORDING_COLUMNS,
    }.items()
}
"""Every table's columns: the record's fields in declaration order, as the JSON report has them,
each time column followed by its seconds from the recording's start, ``severity`` by its name,
and the muted faults by what muting withheld and published."""


def _event_row(event: dict[str, object]) -> dict[str, object]:
    fault = event["fault"]
    assert isinstance(fault, dict)
    return {
        "t_ns": event["t_ns"],
        "event_type": event["event_type"],
        "fault_code": fault["fault_code"],
        "status": fault["status"],
        "severity": fault["severity"],
        "occurrence_count": fault["occurrence_count"],
        "reporting_sources": fault["reporting_sources"],
        "muted": fault["muted"],
        "auto_cleared_codes": event["auto_cleared_codes"],
    }


def _snapshot_rows(result: Result) -> list[dict[str, object]]:
    rows: list[dict[str, object]] = []
    for capture in result.snapshots:
        head: dict[str, object] = {
            "fault_code": capture.fault_code,
            "capture_id": capture.capture_id,
            "t_ns": capture.t_ns,
            "retained": capture.retained,
            "freeze_frame": capture.freeze_frame,
        }
        rows.extend(
            {
                **head,
                "topic": topic.topic,
                "message_type": topic.message_type,
                "message_t_ns": topic.message_t_ns,
                "data": json.dumps(topic.data, ensure_ascii=True, allow_nan=False),
            }
            for topic in capture.topics
        )
        if not capture.topics:
            rows.append(head)
    return rows


def _recording_row(recording: dict[str, object]) -> dict[str, object]:
    return {column: recording[column] for column in RECORDING_COLUMNS}


def result_tables(result: Result) -> dict[str, pd.DataFrame]:
    """One DataFrame per report table, with stable columns even when empty."""
    # Counted in one pass, and only when something was muted.
    counts = event_counts(result) if result.muted_faults else {}
    rows: dict[str, list[dict[str, object]]] = {
        "faults": [fault_dict(f) for f in result.faults],
        "events": [_event_row(event_dict(e)) for e in result.events],
        "transitions": [transition_dict(t) for t in result.transitions],
        "reports": [report_dict(r) for r in result.reports],
        "clears": [clear_dict(c) for c in result.clears],
        "muted_faults": [
            {**muted_dict(m), MUTING: muting_sentence(counts.get(m.fault_code, NO_EVENTS), m)}
            for m in result.muted_faults
        ],
        "clusters": [cluster_dict(c) for c in result.clusters],
        "near_misses": [near_miss_dict(n) for n in result.near_misses],
        "snapshots": _snapshot_rows(result),
        "recordings": [_recording_row(recording_dict(r)) for r in result.recordings],
    }
    start = result.span()[0] or 0
    frames = {}
    for name, columns in TABLE_COLUMNS.items():
        base = [c for c in columns if c not in SECONDS_COLUMNS and c != SEVERITY_NAME]
        frame = _frame(rows[name], base)
        for column in base:
            if column in TIME_COLUMNS:
                frame[seconds_column(column)] = _seconds(frame[column], start, column)
            elif column == "severity":
                frame[SEVERITY_NAME] = frame[column].map(_severity_name).astype(object)
        frames[name] = frame[columns]
    return frames


def _seconds(times: pd.Series, start_ns: int, column: str) -> pd.Series:
    """Seconds from the start of a time column (vectorised when it is int64); empty where the
    time is, and where ``last_passed_ns`` is 0 (upstream's "never passed")."""
    never = column == "last_passed_ns"
    if times.dtype == "int64":
        shown = ((times - start_ns) / NS_PER_SEC).round(9)
        return shown.where(times != 0) if never else shown
    return times.map(
        lambda v: (
            round((v - start_ns) / NS_PER_SEC, 9)
            if isinstance(v, int) and not (never and v == 0)
            else None
        )
    ).astype("float64")


def _severity_name(value: object) -> str | None:
    if isinstance(value, Integral) and not isinstance(value, bool):
        return severity_name(int(value))
    return None


def _frame(rows: list[dict[str, object]], columns: list[str]) -> pd.DataFrame:
    try:
        return pd.DataFrame(rows, columns=pd.Index(columns))
    except UnicodeEncodeError:  # Arrow-backed strings refuse lone surrogates
        return pd.DataFrame([_encodable_row(row) for row in rows], columns=pd.Index(columns))


def _encodable_text(value: object) -> object:
    # A lone surrogate (a reader let "\udcff" through) cannot be written as UTF-8: its escape.
    if isinstance(value, str) and not value.isascii():
        return value.encode("utf-8", "backslashreplace").decode("utf-8")
    if isinstance(value, list):
        return [_encodable_text(item) for item in value]
    return value


def _encodable_row(row: dict[str, object]) -> dict[str, object]:
    return {key: _encodable_text(value) for key, value in row.items()}


def encodable(frame: pd.DataFrame) -> pd.DataFrame:
    """The table with every text cell UTF-8 can encode (lone surrogates as ``\\udcff``); lists
    of text likewise. Only columns of Python objects can hold such text (Arrow-backed string
    columns refuse it when built); valid text is unchanged."""
    safe = frame.copy()
    for column in safe.columns:
        if safe[column].dtype == object:
            safe[column] = safe[column].map(_encodable_text)
    return safe


def write_csv(result: Result, directory: Path) -> list[Path]:
    """Write ``<table>.csv`` for every table into ``directory``; lists joined with ``;``.

    Each file goes through a temporary file renamed into place, so a file of the folder is
    whole (the old one or the new one), never partial. Text cells a spreadsheet would run as a
    formula get a leading single quote (see csv_safety.neutralise); numbers stay numbers.
    """
    directory.mkdir(parents=True, exist_ok=True)
    written = []
    for name, frame in result_tables(result).items():
        flat = encodable(frame)
        for column in flat.columns:
            if flat[column].map(lambda v: isinstance(v, list)).any():
                flat[column] = flat[column].map(
                    lambda v: ";".join(map(str, v)) if isinstance(v, list) else v
                )
        path = directory / f"{name}.csv"
        with atomic_text(path) as stream:
            write_frame(flat, stream)
        written.append(path)
    return written
