"""The MCAP format's records: opcodes, fixed layouts, and a cursor over one record's bytes.

Pure: parses bytes already read, never trusting a length field past the bytes it was given.
"""

from __future__ import annotations

from operator import itemgetter
from struct import Struct

from medkit_replay.inputs.mcap.plan import PLAIN_CHUNK_HEAD, ChunkIndex
from medkit_replay.inputs.storage import RECORD_SIZE_LIMIT

MAGIC = b"\x89MCAP0\r\n"
OP_HEADER, OP_FOOTER, OP_SCHEMA, OP_CHANNEL, OP_MESSAGE, OP_CHUNK = (
    0x01,
    0x02,
    0x03,
    0x04,
    0x05,
    0x06,
)
OP_CHUNK_INDEX, OP_STATISTICS, OP_DATA_END = 0x08, 0x0B, 0x0F
FOOTER_SIZE = 9 + 20 + len(MAGIC)
MESSAGE_HEADER = 22  # channel id, sequence, log time, publish time
CHUNK_HEAD = Struct("<BQQQQII")  # opcode, length, start, end, size, crc, compression length
U64 = Struct("<Q")
MESSAGE_HEAD = Struct("<BQHIQ")  # opcode, length, channel id, sequence, log time
ORDER = itemgetter(0, 1)  # (log time, position) of a Timed
T_NS = itemgetter(0)  # log time of a Timed
SEEN_T_NS = itemgetter(1)  # log time of a (channel id, log time) pair
LOG_TIME_LIMIT = 2**63
"""Log times at or above it cannot come from ROS 2 (int64 nanoseconds): such a message is damage."""
NO_FOOTER = "no footer (the recorder did not close the file)"
new_tuple = tuple.__new__  # builds a Timed or Raw from a tuple without its Python-level __new__


class DamageError(Exception):
    """A record's content does not fit its declared length."""


class Cursor:
    """Little-endian reader over one record's bytes that refuses to run past its end."""

    __slots__ = ("data", "pos")

    def __init__(self, data: bytes | memoryview) -> None:
        self.data = memoryview(data)
        self.pos = 0

    def take(self, size: int) -> memoryview:
        if size < 0 or self.pos + size > len(self.data):
            raise DamageError(f"field of {size} bytes overruns its record")
        self.pos += size
        return self.data[self.pos - size : self.pos]

    def uint(self, size: int) -> int:
        return int.from_bytes(self.take(size), "little")

    def string(self) -> str:
        return bytes(self.take(self.uint(4))).decode("utf-8", "replace")

    def rest(self) -> memoryview:
        return self.take(len(self.data) - self.pos)


def plain_chunk(head: bytes) -> bool:
    """Whether a chunk's head declares it uncompressed, without checksum, its size plausible."""
    _, length, _, _, size, crc, compression = CHUNK_HEAD.unpack_from(head)
    if compression or crc or size > RECORD_SIZE_LIMIT:
        return False
    declared = int(U64.unpack_from(head, PLAIN_CHUNK_HEAD - 8)[0])
    return bool(declared == size and 40 + size <= length)


_CHUNK_INDEX_HEAD = Struct("<QQQQI")  # start, end, chunk offset, chunk length, map length
_CHUNK_INDEX_ENTRY = Struct("<HQ")  # channel id, message index offset


def chunk_index_record(body: memoryview) -> ChunkIndex | None:
    """A well-formed chunk index record, parsed in one go; None for the careful parser."""
    if len(body) < _CHUNK_INDEX_HEAD.size:
        return None
    start_ns, end_ns, offset, length, map_length = _CHUNK_INDEX_HEAD.unpack_from(body)
    end = _CHUNK_INDEX_HEAD.size + map_length
    if end > len(body) or map_length % _CHUNK_INDEX_ENTRY.size:
        return None
    channels = frozenset(
        cid for cid, _ in _CHUNK_INDEX_ENTRY.iter_unpack(body[_CHUNK_INDEX_HEAD.size : end])
    )
    index_length = U64.unpack_from(body, end)[0] if end + 8 <= len(body) else 0
    return ChunkIndex(start_ns, offset, length, channels, index_length, end_ns)


def chunk_span(body: memoryview) -> tuple[int, int] | None:
    """The log time span a chunk record's header gives (None: cut before it, or past int64)."""
    if len(body) < 16:
        return None
    start_ns, end_ns = int.from_bytes(body[:8], "little"), int.from_bytes(body[8:16], "little")
    return (start_ns, end_ns) if start_ns <= end_ns < LOG_TIME_LIMIT else None
