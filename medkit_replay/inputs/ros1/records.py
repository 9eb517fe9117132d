"""The records of a ROS 1 bag (format 2.0): headers, bag header, connections, chunk infos, chunks.

Pure: parses bytes already read, never trusting a length field past the bytes it was given.
"""

from __future__ import annotations

from struct import Struct
from typing import TYPE_CHECKING, NamedTuple

if TYPE_CHECKING:
    from collections.abc import Iterator

MAGIC = b"#ROSBAG V2.0\n"
OP_MSG_DATA = 0x02
OP_BAG_HEADER = 0x03
OP_INDEX_DATA = 0x04
OP_CHUNK = 0x05
OP_CHUNK_INFO = 0x06
OP_CONNECTION = 0x07

HEADER_SIZE_LIMIT = 16 * 1024 * 1024
"""Largest record header (bytes) a length field may make a reader allocate.

The largest header a recorder writes is a connection's, with its full message definition:
kilobytes, rarely more than a few hundred. A larger one is damage.
"""

_U32 = Struct("<I")
_U32_PAIR = Struct("<II")
_U64 = Struct("<Q")


class RecordDamageError(Exception):
    """A record's bytes do not hold what its lengths and fields declare."""


class BagHeader(NamedTuple):
    """The bag header record: where the index starts (0: not indexed) and what it holds."""

    index_pos: int
    conn_count: int
    chunk_count: int


class Ros1Connection(NamedTuple):
    """One connection (topic and type) of a ROS 1 bag, as its connection record declares it."""

    id: int
    topic: str
    msgtype: str  # as recorded: ``pkg/Name``
    md5sum: str
    definition: str
    callerid: str


class ChunkInfo(NamedTuple):
    """A chunk info record of the index: where a chunk is, its time span, its connections."""

    chunk_pos: int
    start_ns: int
    end_ns: int
    counts: dict[int, int]  # messages per connection id


class ChunkRecord(NamedTuple):
    """One record inside a decompressed chunk: its fields and where its data lies in the chunk."""

    op: int
    fields: dict[str, bytes]
    data_start: int
    data_end: int


def parse_fields(header: bytes | memoryview) -> dict[str, bytes]:
    """The ``name=value`` fields of a record header.

    Raises:
        RecordDamageError: a field runs past the header or has no ``=``.
    """
    fields: dict[str, bytes] = {}
    pos, end = 0, len(header)
    while pos < end:
        if end - pos < 4:
            raise RecordDamageError(f"header ends inside a field length at byte {pos}")
        (length,) = _U32.unpack_from(header, pos)
        pos += 4
        if length > end - pos:
            raise RecordDamageError(f"header field of {length} bytes runs past the header")
        field = bytes(header[pos : pos + length])
        pos += length
        name, equals, value = field.partition(b"=")
        if not equals:
            raise RecordDamageError("header field without '='")
        fields[name.decode("utf-8", "replace")] = value
    return fields


def op_of(fields: dict[str, bytes]) -> int:
    """The record's ``op`` field.

    Raises:
        RecordDamageError: the field is missing or not one byte.
    """
    op = fields.get("op")
    if op is None or len(op) != 1:
        raise RecordDamageError("record header without a one-byte 'op'")
    return op[0]


def uint32(fields: dict[str, bytes], name: str) -> int:
    """An unsigned 32-bit field (RecordDamageError when missing or of another size)."""
    return _fixed(fields, name, _U32)[0]


def uint64(fields: dict[str, bytes], name: str) -> int:
    """An unsigned 64-bit field (RecordDamageError when missing or of another size)."""
    return _fixed(fields, name, _U64)[0]


def time_ns(fields: dict[str, bytes], name: str) -> int:
    """A ``time`` field (seconds and nanoseconds, two uint32) in nanoseconds."""
    sec, nsec = _fixed(fields, name, _U32_PAIR)
    return sec * 1_000_000_000 + nsec


def string(fields: dict[str, bytes], name: str, default: str | None = None) -> str:
    """A string field, decoded as UTF-8 with replacement (RecordDamageError when missing)."""
    value = fields.get(name)
    if value is None:
        if default is not None:
            return default
        raise RecordDamageError(f"record header without {name!r}")
    return value.decode("utf-8", "replace")


def _fixed(fields: dict[str, bytes], name: str, shape: Struct) -> tuple[int, ...]:
    value = fields.get(name)
    if value is None or len(value) != shape.size:
        raise RecordDamageError(f"record header field {name!r} missing or not {shape.size} bytes")
    return shape.unpack(value)


def bag_header(fields: dict[str, bytes]) -> BagHeader:
    """The bag header record's fields (RecordDamageError when it is not one)."""
    if op_of(fields) != OP_BAG_HEADER:
        raise RecordDamageError("first record is not a bag header")
    return BagHeader(
        uint64(fields, "index_pos"), uint32(fields, "conn_count"), uint32(fields, "chunk_count")
    )


def connection(fields: dict[str, bytes], data: bytes | memoryview) -> Ros1Connection:
    """A connection record: its header names the id and topic, its data holds the type's header.

    Raises:
        RecordDamageError: a field is missing or the data is not a header.
    """
    described = parse_fields(data)
    return Ros1Connection(
        id=uint32(fields, "conn"),
        topic=string(described, "topic", string(fields, "topic", "")),
        msgtype=string(described, "type"),
        md5sum=string(described, "md5sum", ""),
        definition=string(described, "message_definition", ""),
        callerid=string(described, "callerid", ""),
    )


def chunk_info(fields: dict[str, bytes], data: bytes | memoryview) -> ChunkInfo:
    """A chunk info record (version 1): a chunk's position, time span and per-connection counts.

    Raises:
        RecordDamageError: another version, a missing field, data of the wrong length.
    """
    if uint32(fields, "ver") != 1:
        raise RecordDamageError(f"chunk info version {uint32(fields, 'ver')} is not 1")
    count = uint32(fields, "count")
    if len(data) != count * 8:
        raise RecordDamageError(f"chunk info lists {count} connections in {len(data)} bytes")
    pairs = [_U32_PAIR.unpack_from(data, 8 * k) for k in range(count)]
    return ChunkInfo(
        chunk_pos=uint64(fields, "chunk_pos"),
        start_ns=time_ns(fields, "start_time"),
        end_ns=time_ns(fields, "end_time"),
        counts=dict(pairs),
    )


def chunk_records(data: bytes | memoryview) -> Iterator[ChunkRecord]:
    """The records of a decompressed chunk, in order; stops at the first damaged one.

    Raises:
        RecordDamageError: after the intact records before it, the first record that runs past
            the chunk or has a damaged header.
    """
    pos, end = 0, len(data)
    while pos < end:
        if end - pos < 4:
            raise RecordDamageError(f"chunk ends inside a record length at byte {pos}")
        (header_len,) = _U32.unpack_from(data, pos)
        if header_len > end - pos - 8:
            raise RecordDamageError(f"record at byte {pos} of the chunk runs past it")
        fields = parse_fields(data[pos + 4 : pos + 4 + header_len])
        (data_len,) = _U32.unpack_from(data, pos + 4 + header_len)
        start = pos + 8 + header_len
        if data_len > end - start:
            raise RecordDamageError(f"record at byte {pos} of the chunk runs past it")
        yield ChunkRecord(op_of(fields), fields, start, start + data_len)
        pos = start + data_len


def index_records(data: bytes | memoryview) -> Iterator[tuple[int, dict[str, bytes], memoryview]]:
    """The records of a whole index section read into memory: (op, fields, data).

    Raises:
        RecordDamageError: after the intact records, one that runs past the section.
    """
    view = memoryview(data)
    for record in chunk_records(view):
        yield record.op, record.fields, view[record.data_start : record.data_end]
