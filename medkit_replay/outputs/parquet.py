"""Parquet files of the report's tables (pandas + pyarrow), one file per table.

pyarrow is optional (``pip install 'medkit-replay[parquet]'``); without it, asking for Parquet
is a one-line error, exit 2. Every table keeps a fixed Arrow schema, even when it is empty.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from medkit_replay.errors import MedkitReplayError
from medkit_replay.outputs.tables import TABLE_COLUMNS, result_tables

if TYPE_CHECKING:
    from pathlib import Path

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
    }
)
"""Columns stored as int64 (nullable where the report has nulls); nanoseconds stay exact."""
BOOL_COLUMNS = frozenset({"muted", "accepted", "success", "skip_correlation_auto_clear"})
LIST_COLUMNS = frozenset({"reporting_sources", "cluster_ids", "auto_cleared_codes", "fault_codes"})
"""Columns stored as list<string>; every other column is a (nullable) string."""


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
        elif column in BOOL_COLUMNS:
            kind = pa.bool_()
        elif column in LIST_COLUMNS:
            kind = pa.list_(pa.string())
        else:
            kind = pa.string()
        fields.append(pa.field(column, kind, nullable=True))
    return pa.schema(fields)


def write_parquet(result: Result, directory: Path) -> list[Path]:
    """Write ``<table>.parquet`` for every report table into ``directory``.

    Raises:
        MissingDependencyError: pyarrow is not installed.
        OSError: the directory or a file cannot be written.
    """
    pa = require_pyarrow()
    parquet = importlib.import_module("pyarrow.parquet")
    directory.mkdir(parents=True, exist_ok=True)
    written = []
    for name, frame in result_tables(result).items():
        table = pa.Table.from_pandas(frame, schema=arrow_schema(name), preserve_index=False)
        path = directory / f"{name}.parquet"
        parquet.write_table(table, path)
        written.append(path)
    return written
