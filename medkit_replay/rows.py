"""Records as rows for spools: a record class's fields as one flat tuple, and a flat pickle form.

Neutral ground, like ``model``: it imports nothing of ours.
"""

from __future__ import annotations

from dataclasses import fields
from operator import attrgetter
from typing import TYPE_CHECKING, Any, Generic, TypeVar

if TYPE_CHECKING:
    from collections.abc import Callable


_R = TypeVar("_R")


def _restore(cls: type[_R], names: tuple[str, ...], values: tuple[object, ...]) -> _R:
    record = object.__new__(cls)
    for name, value in zip(names, values, strict=True):
        object.__setattr__(record, name, value)
    return record


def spoolable(cls: type[_R]) -> type[_R]:
    """Give a frozen record class a flat pickle form.

    The dataclass default looks its fields up on every object, which dominated the cost of
    spooling millions of records to disk; this does the lookup once per class.
    """
    names = tuple(f.name for f in fields(cls))  # type: ignore[arg-type]  # a dataclass

    def reduce(self: _R) -> tuple[object, ...]:
        return (_restore, (cls, names, tuple([getattr(self, n) for n in names])))

    cls.__reduce__ = reduce  # type: ignore[method-assign,assignment]
    return cls


class RecordRows(Generic[_R]):
    """A record class's row form for spools: its fields in declaration order, as one flat tuple.

    A nested record (a FaultEvent's snapshot) has its fields spliced in where it stands (flat
    rows pickle faster). The engine's hot path builds rows directly; ``decode`` rebuilds the
    record when a spool is read. ``names`` are the row's fields, nested ones included.
    """

    def __init__(self, cls: type[_R], nested: tuple[str, RecordRows[Any]] | None = None) -> None:
        self.cls = cls
        self.fields: tuple[str, ...] = tuple(f.name for f in fields(cls))  # type: ignore[arg-type]
        self._get: Callable[[_R], tuple[object, ...]] = attrgetter(*self.fields)
        self._nested: tuple[int, RecordRows[Any]] | None = None
        self.names = self.fields
        if nested is not None:
            at = self.fields.index(nested[0])
            self._nested = (at, nested[1])
            self.names = (*self.fields[:at], *nested[1].names, *self.fields[at + 1 :])

    def encode(self, item: _R, /) -> tuple[object, ...]:
        """The record's row."""
        row = self._get(item)
        if self._nested is None:
            return row
        at, rows = self._nested
        return (*row[:at], *rows.encode(row[at]), *row[at + 1 :])

    def decode(self, row: tuple[object, ...], /) -> _R:
        """The record a row stands for."""
        if self._nested is not None:
            at, rows = self._nested
            end = at + len(rows.names)
            row = (*row[:at], rows.decode(row[at:end]), *row[end:])
        return _restore(self.cls, self.fields, row)
