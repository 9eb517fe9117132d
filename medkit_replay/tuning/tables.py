"""A sweep's tables written as rows arrive: CSV and (with pyarrow) Parquet, side by side.

Rows are written in the order given and Parquet row groups have a fixed size, so the same rows
make the same bytes whatever the number of workers; memory holds one row group at most.
"""

from __future__ import annotations

import csv
from contextlib import ExitStack, suppress
from dataclasses import fields
from typing import IO, TYPE_CHECKING, Any

from medkit_replay.outputs.atomic import atomic_binary, atomic_text
from medkit_replay.outputs.csv_safety import neutralise

if TYPE_CHECKING:
    from collections.abc import Sequence
    from pathlib import Path
    from types import TracebackType

ROW_GROUP = 4096
"""Rows per Parquet row group (and the most rows held before they are written)."""


def column_kinds(record: type[Any]) -> dict[str, str]:
    """``int``, ``bool`` or ``str`` for every field of a row dataclass, from its annotations
    (``float`` is for varied values only)."""
    kinds = {}
    for field in fields(record):
        annotation = str(field.type)
        kind = annotation.split("|", maxsplit=1)[0].strip()
        kinds[field.name] = kind if kind in ("int", "bool") else "str"
    return kinds


class TableWriter:
    """One table as ``NAME.csv`` and ``NAME.parquet`` in a folder, appended row by row.

    ``parquet`` False writes the CSV only (pyarrow is imported only when it is True). Files
    appear (atomically) when the writer closes without an error.
    """

    def __init__(
        self, folder: Path, name: str, columns: Sequence[str], kinds: dict[str, str], parquet: bool
    ) -> None:
        self.columns = list(columns)
        self.kinds = kinds
        self._stack = ExitStack()
        self._csv: IO[str] = self._stack.enter_context(
            atomic_text(folder / f"{name}.csv", newline="")
        )
        self._rows = csv.writer(self._csv, lineterminator="\n")
        # Python's csv leaves a lone carriage return unquoted with \n line ends, and readers end
        # the row there: a row holding one has its text quoted (outputs/csv_safety.py does the
        # same per table).
        self._quoted = csv.writer(self._csv, lineterminator="\n", quoting=csv.QUOTE_NONNUMERIC)
        self._rows.writerow(self.columns)
        self._batch: list[Sequence[object]] = []
        self._parquet: Any = None
        if parquet:
            import pyarrow  # noqa: PLC0415  # optional and heavy
            import pyarrow.parquet as pq  # noqa: PLC0415

            self._pa = pyarrow

            types = {
                "int": pyarrow.int64(),
                "float": pyarrow.float64(),
                "bool": pyarrow.bool_(),
                "str": pyarrow.string(),
            }
            self._schema = pyarrow.schema([(c, types[kinds.get(c, "str")]) for c in self.columns])
            stream = self._stack.enter_context(atomic_binary(folder / f"{name}.parquet"))
            self._parquet = pq.ParquetWriter(
                stream, self._schema, compression="zstd", write_statistics=False
            )

    def write(self, row: Sequence[object]) -> None:
        """Append one row (values in column order; None is an empty cell, a null)."""
        cells = ["" if v is None else neutralise(v) for v in row]
        if any(isinstance(v, str) and "\r" in v for v in cells):
            self._quoted.writerow(cells)
        else:
            self._rows.writerow(cells)
        if self._parquet is not None:
            self._batch.append(row)
            if len(self._batch) >= ROW_GROUP:
                self._flush()

    def _flush(self) -> None:
        if not self._batch:
            return
        arrays = [
            self._pa.array([row[i] for row in self._batch], type=self._schema.field(i).type)
            for i in range(len(self.columns))
        ]
        self._parquet.write_table(self._pa.Table.from_arrays(arrays, schema=self._schema))
        self._batch = []

    def __enter__(self) -> TableWriter:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        try:
            if kind is None and self._parquet is not None:
                self._flush()
        except BaseException as failure:
            kind, error, trace = type(failure), failure, failure.__traceback__
            raise
        finally:
            if self._parquet is not None:
                parquet, self._parquet = self._parquet, None
                with suppress(Exception):  # its file is being removed anyway on a failure
                    parquet.close()
            self._stack.__exit__(kind, error, trace)
