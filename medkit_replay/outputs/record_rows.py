"""A Result's long record lists as batches of rows (``rows.RecordRows``): a spool hands over the
rows it stores, a list's records are taken apart; no record is rebuilt just to be read."""

from __future__ import annotations

from itertools import islice
from typing import TYPE_CHECKING, Any, TypeVar

from medkit_replay.spool import Spool

if TYPE_CHECKING:
    from collections.abc import Iterator, Sequence

    from medkit_replay.rows import RecordRows

Row = tuple[Any, ...]
"""A record's fields in order (see ``rows.RecordRows``), read by position."""
R = TypeVar("R")
BATCH = 4096


def row_batches(records: Sequence[R], codec: RecordRows[R]) -> Iterator[list[Row]]:
    """``records`` as lists of rows laid out as ``codec`` says."""
    if isinstance(records, Spool) and records.codec is codec:
        yield from records.row_batches()
        return
    it = iter(records)
    while batch := list(islice(it, BATCH)):
        yield [codec.encode(record) for record in batch]
