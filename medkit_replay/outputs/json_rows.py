"""The JSON report's long record lists, encoded in bulk by msgspec: one record per line, the very
bytes the standard library's encoder gives (``ensure_ascii``, ``", "`` and ``": "``).

Driven by the record classes: a class whose fields hold only strings, integers, booleans, None,
tuples of those and nested records is encoded in bulk; anything else (a float) by the stdlib.
"""

from __future__ import annotations

import json
import re
import types
from dataclasses import fields, is_dataclass
from itertools import islice, starmap
from typing import (
    TYPE_CHECKING,
    Any,
    Literal,
    TypeGuard,
    Union,
    cast,
    get_args,
    get_origin,
    get_type_hints,
)

import msgspec

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Iterator, Sequence

ROW_SEPARATOR = b",\n    "
"""Between two records of a long list (each on its own line, indented under its key)."""
STDLIB_ROW = json.JSONEncoder(ensure_ascii=True, separators=(", ", ": "), allow_nan=False)
"""The encoder whose bytes the bulk path reproduces; also the path for what it cannot take."""
BATCH = 4096

_ENCODER = msgspec.json.Encoder()
# Between two records in a batch: an empty string, so that "}, "", {" after formatting can only
# be a boundary (inside a string a quote is escaped; record lists hold no mixed arrays).
_GAP = ""
_BOUNDARY = b'}, "", {'
_NOT_ASCII = re.compile("[\x7f-\U0010ffff]+")
_escape_ascii = cast("Callable[[str], str]", json.encoder.c_encode_basestring_ascii)  # type: ignore[attr-defined]
_PLAIN = (int, str, bool, type(None))

Row = tuple[object, ...]
Chunk = bytes | memoryview
"""A piece of the report's text, ASCII."""


def _bulk_safe(hint: object) -> bool:
    """A type whose values msgspec writes exactly as the stdlib does (no floats: repr differs,
    and msgspec writes NaN as null where the report refuses it)."""
    if hint in _PLAIN:
        return True
    origin = get_origin(hint)
    if origin is Literal:
        return all(type(arg) in _PLAIN for arg in get_args(hint))
    if origin in (Union, types.UnionType):
        return all(_bulk_safe(arg) for arg in get_args(hint))
    if origin is tuple:
        args = get_args(hint)
        if len(args) != 2 or args[1] is not Ellipsis or not _bulk_safe(args[0]):
            return False
        # Records or no records: an array mixing them with strings could hold the boundary.
        return _is_record(args[0]) or not _holds_record(args[0])
    if _is_record(hint):
        hints = get_type_hints(hint)
        return all(_bulk_safe(hints[f.name]) for f in fields(hint))
    return False


def _is_record(hint: object) -> TypeGuard[type[Any]]:
    return isinstance(hint, type) and is_dataclass(hint)


def _holds_record(hint: object) -> bool:
    return _is_record(hint) or any(_holds_record(arg) for arg in get_args(hint))


def _struct(cls: type[Any]) -> type[msgspec.Struct]:
    """A msgspec struct with ``cls``'s fields in declaration order (nested records nested)."""
    hints = get_type_hints(cls)
    spec = [
        (f.name, _struct(hints[f.name]) if is_dataclass(hints[f.name]) else object)
        for f in fields(cls)
    ]
    return msgspec.defstruct(f"{cls.__name__}Row", spec, gc=False)


def _row_builder(cls: type[Any], names: Sequence[str]) -> Callable[[list[Row]], list[object]]:
    """Rows (a record's fields in order, one nested record's fields spliced in where it stands,
    as ``rows.RecordRows`` lays them out) to structs msgspec encodes."""
    struct = _struct(cls)
    hints = get_type_hints(cls)
    own = [f.name for f in fields(cls)]
    if list(names) == own:
        return lambda rows: list(starmap(struct, rows))
    for at, name in enumerate(own):
        hint = hints[name]
        if not (isinstance(hint, type) and is_dataclass(hint)):
            continue
        inner = [f.name for f in fields(hint)]
        if list(names) == [*own[:at], *inner, *own[at + 1 :]]:
            return _spliced(struct, _struct(hint), at, at + len(inner))
    raise ValueError(f"rows of {names} do not lay out {cls.__name__}")


def _spliced(
    struct: type[msgspec.Struct], nested: type[msgspec.Struct], at: int, end: int
) -> Callable[[list[Row]], list[object]]:
    def build(rows: list[Row]) -> list[object]:
        return [struct(*row[:at], nested(*row[at:end]), *row[end:]) for row in rows]

    return build


def _ascii(chunk: bytes) -> bytes:
    """``chunk`` with every character beyond ASCII (and DEL) escaped as the stdlib does. Only
    strings can hold them, so the whole text can be searched."""
    if chunk.isascii() and b"\x7f" not in chunk:
        return chunk
    text = _NOT_ASCII.sub(lambda m: _escape_ascii(m.group())[1:-1], chunk.decode("utf-8"))
    return text.encode("ascii")


def _lines(items: list[object]) -> memoryview:
    """Records (structs or dataclass instances) as report lines joined by ROW_SEPARATOR."""
    spaced: list[object] = [_GAP] * (2 * len(items) - 1)
    spaced[::2] = items
    text = msgspec.json.format(_ENCODER.encode(spaced), indent=0)
    return memoryview(_ascii(text.replace(_BOUNDARY, b"},\n    {")))[1:-1]  # no [ ]


class RecordLines:
    """Writes one record class's long list: records or rows in, report lines out."""

    def __init__(self, cls: type[Any], as_dict: Callable[[Any], dict[str, object]]) -> None:
        self.cls = cls
        self.as_dict = as_dict
        self._bulk = _bulk_safe(cls)
        self._builders: dict[tuple[str, ...], Callable[[list[Row]], list[object]]] = {}

    def _stdlib(self, records: Iterable[Any]) -> Chunk:
        as_dict = self.as_dict
        return ROW_SEPARATOR.join(STDLIB_ROW.encode(as_dict(r)).encode("ascii") for r in records)

    def chunks(self, records: Iterable[Any]) -> Iterator[Chunk]:
        """Batches of records as report lines (no separator before the first of a batch)."""
        it = iter(records)
        while batch := list(islice(it, BATCH)):
            yield self._encode(batch, batch)

    def row_chunks(
        self, batches: Iterable[list[Row]], names: Sequence[str], record: Callable[[Row], Any]
    ) -> Iterator[Chunk]:
        """Batches of rows (``names`` lay them out; ``record`` rebuilds one) as report lines."""
        key = tuple(names)
        build = self._builders.get(key)
        if build is None:
            build = self._builders[key] = _row_builder(self.cls, names)
        for rows in batches:
            for start in range(0, len(rows), BATCH):
                yield self._rows(rows[start : start + BATCH], build, record)

    def _rows(
        self,
        batch: list[Row],
        build: Callable[[list[Row]], list[object]],
        record: Callable[[Row], Any],
    ) -> Chunk:
        if self._bulk:
            return self._encode(build(batch), batch, record)
        return self._stdlib(map(record, batch))

    def _encode(
        self, items: list[object], originals: list[Any], record: Callable[[Row], Any] | None = None
    ) -> Chunk:
        if self._bulk:
            try:
                return _lines(items)
            except (UnicodeEncodeError, TypeError, ValueError, OverflowError):
                pass  # a lone surrogate, or a value of a type the class does not declare
        return self._stdlib(originals if record is None else map(record, originals))
