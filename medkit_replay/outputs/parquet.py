"""Parquet files of the report's tables (pandas + pyarrow), one file per table.

pyarrow is optional (``pip install 'medkit-replay[parquet]'``); without it, asking for Parquet
is a one-line error, exit 2. Every table keeps a fixed Arrow schema, even when it is empty.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from medkit_replay.errors import MedkitReplayError
from medkit_replay.outputs.atomic import atomic_binary
from medkit_replay.outputs.console import warn as warn_stderr
from medkit_replay.outputs.tables import (
    SECONDS_COLUMNS,
    TABLE_COLUMNS,
    encodable,
    result_tables,
)

if TYPE_CHECKING:
    from collections.abc import Callable
    from pathlib import Path

    import pandas as pd

    from medkit_replay.result import Result

EXTRA_HINT = "pip install 'medkit-replay[parquet]'"

INT_COLUMNS = frozenset(
    {
        "t_ns",
        "severity",
        "first_occurred_ns",
        "last_occurred_ns",
        "last_passed_ns",
        "occurrence_count",
        "debounce_counter",
        "confirmation_threshold",
        "healing_threshold",
        "delay_ms",
        "count",
        "first_at_ns",
        "last_at_ns",
        "capture_id",
        "message_t_ns",
        "start_ns",
        "end_ns",
        "messages",
        "bytes",
        "deleted_ns",
    }
)
"""Columns stored as int64 (nullable where the report has nulls); nanoseconds stay exact."""
BOOL_COLUMNS = frozenset(
    {"muted", "accepted", "success", "skip_correlation_auto_clear", "retained", "freeze_frame"}
)
LIST_COLUMNS = frozenset({"reporting_sources", "cluster_ids", "auto_cleared_codes", "fault_codes"})
"""Columns stored as list<string>; seconds from the start are float64; every other column is a
(nullable) string."""
INT64_MIN = -(2**63)
INT64_MAX = 2**63 - 1


class MissingDependencyError(MedkitReplayError):
    """An optional dependency an output needs is not installed (exit 2)."""


def require_pyarrow() -> Any:  # pyarrow ships no type information
    """The pyarrow module, or a one-line error naming the extra that installs it.

    Raises:
        MissingDependencyError: pyarrow cannot be imported.
    """
    try:
        return importlib.import_module("pyarrow")
    except ImportError:
        raise MissingDependencyError(
            f"--parquet needs pyarrow, which is not installed: {EXTRA_HINT}"
        ) from None


def arrow_schema(table: str) -> Any:
    """The Arrow schema of one report table (column order as in TABLE_COLUMNS)."""
    pa = require_pyarrow()
    fields = []
    for column in TABLE_COLUMNS[table]:
        if column in INT_COLUMNS:
            kind = pa.int64()
        elif column in SECONDS_COLUMNS:
            kind = pa.float64()
        elif column in BOOL_COLUMNS:
            kind = pa.bool_()
        elif column in LIST_COLUMNS:
            kind = pa.list_(pa.string())
        else:
            kind = pa.string()
        fields.append(pa.field(column, kind, nullable=True))
    return pa.schema(fields)


def _clamp(value: object) -> object:
    if isinstance(value, int) and not INT64_MIN <= value <= INT64_MAX:
        return min(max(value, INT64_MIN), INT64_MAX)
    return value


def clamped(frame: pd.DataFrame) -> tuple[pd.DataFrame, int]:
    """The table with every integer int64 cannot hold (a time at or after 2^63 ns, from a
    script or a damaged bag) saturated to int64's range, and how many cells were."""
    count = 0
    for column in INT_COLUMNS.intersection(frame.columns):
        series = frame[column]
        if series.dtype == "int64":
            continue
        outside = int(series.map(lambda v: _clamp(v) is not v).sum())
        if outside:
            frame[column] = series.map(_clamp)
            count += outside
    return frame, count


def write_parquet(
    result: Result, directory: Path, *, warn: Callable[[str], None] = warn_stderr
) -> list[Path]:
    """Write ``<table>.parquet`` for every report table into ``directory``.

    Each file goes through a temporary file renamed into place (whole or not at all). An
    integer outside int64 (a bag time at or after 2^63 ns) is saturated to -2^63 .. 2^63-1,
    with one warning per file saying how many cells were; the JSON report holds them exactly.

    Raises:
        MissingDependencyError: pyarrow is not installed.
        OSError: the directory or a file cannot be written.
    """
    pa = require_pyarrow()
    parquet = importlib.import_module("pyarrow.parquet")
    directory.mkdir(parents=True, exist_ok=True)
    written = []
    for name, frame in result_tables(result).items():
        safe, saturated = clamped(encodable(frame))
        table = pa.Table.from_pandas(safe, schema=arrow_schema(name), preserve_index=False)
        path = directory / f"{name}.parquet"
        with atomic_binary(path) as stream:
            parquet.write_table(table, stream)
        if saturated:
            warn(
                f"{path}: {saturated:,} value(s) outside int64 (times at or after 2^63 ns) "
                f"saturated to {INT64_MIN} .. {INT64_MAX}; the JSON report holds them exactly"
            )
        written.append(path)
    return written
