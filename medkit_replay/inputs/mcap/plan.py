"""How uncompressed MCAP chunks are read through their message indexes, planned without reading.

Which byte ranges of a chunk hold its wanted records (runs of other topics' records worth a
request are skipped), and what of the chunks after the one being decoded is asked for ahead:
heads and indexes, then pieces, in a window bounded in chunks and in bytes.
"""

from __future__ import annotations

from functools import cache
from operator import sub
from struct import Struct
from typing import TYPE_CHECKING, NamedTuple, Protocol

if TYPE_CHECKING:
    from collections.abc import Callable

OP_MESSAGE_INDEX = 0x07
PAYLOAD_AT = 9 + 22  # a message record's payload, from the record's first byte
PLAIN_CHUNK_HEAD = 9 + 8 + 8 + 8 + 4 + 4 + 8  # an uncompressed chunk's bytes before its records
RECORD_HEAD = Struct("<BQH")  # opcode, length, channel id (of a message record)
SKIP_AT_LEAST = 4 * 1024
"""A run of unwanted records this long is skipped when reading by index (only the first
record's header is read), at the price of one more request: in S3's prices ($0.0004 per
1,000 GETs, $0.09 per GB out) a request costs what 4 KB do. (On loopback it costs what
about 300 KB do, but reading across camera frames would fetch ten times the bytes.)"""
HEADS_AHEAD = 128
"""Chunks ahead whose heads and message indexes are asked for."""
PIECES_AHEAD = 32
"""Chunks ahead whose pieces (or whole records) are asked for, once their heads are at hand."""
AHEAD_BYTES = 16 * 1024 * 1024
"""Most bytes of pieces asked for ahead of the chunk being read."""

_INDEX_HEAD = Struct("<BQHI")  # opcode, length, channel id, entries' byte length
_INDEX_ENTRY = Struct("<QQ")  # log time, offset in the chunk's records


@cache
def _u64s(count: int) -> Callable[[bytes, int], tuple[int, ...]]:
    """Unpacks ``count`` little-endian uint64 values in one call."""
    return Struct(f"<{count}Q").unpack_from


class ChunkIndex(NamedTuple):
    """A chunk as the summary's chunk index describes it."""

    start_ns: int
    offset: int
    length: int
    channels: frozenset[int]  # channels with a message index record (empty: not said)
    index_length: int = 0  # bytes of message index records after the chunk (0: unknown)
    end_ns: int = 2**63 - 1  # log time of its last message (the largest: not said)


class Plan(NamedTuple):
    """How a chunk is read by index: its records' starts, ends (in its records), channels and
    wanted flags, the pieces ``[start, end)`` to read, and the channels it took as wanted."""

    starts: list[int]
    ends: list[int]
    channels: list[int]
    flags: list[bool]
    pieces: list[tuple[int, int]]
    wanted: frozenset[int]


def plan_chunk(
    chunk: ChunkIndex, size: int, index: bytes, wants: Callable[[int], bool]
) -> Plan | None:
    """How to read an uncompressed chunk of ``size`` bytes of records by its message index;
    None when it cannot (an irregular index) or does not pay (most of it is wanted).

    The index must hold one record per channel the summary's chunk index names, and its
    entries must tile the records from the first message on; the pieces then hold what comes
    before it (schema and channel records), every wanted record whole and, of each run of
    unwanted records skipped, the first record's header.
    """
    total = len(index)
    keys: list[int] = []  # offset << 16 | channel id, per message record
    seen: set[int] = set()
    at = 0
    while at < total:
        if at + _INDEX_HEAD.size > total:
            return None
        op, record_length, cid, entries_length = _INDEX_HEAD.unpack_from(index, at)
        end = at + 9 + record_length
        if (
            op != OP_MESSAGE_INDEX
            or record_length != 6 + entries_length
            or entries_length % _INDEX_ENTRY.size
            or end > total
            or cid in seen
        ):
            return None
        seen.add(cid)
        if entries_length:
            words = _u64s(entries_length >> 3)(index, at + _INDEX_HEAD.size)
            keys += [offset << 16 | cid for offset in words[1::2]]  # (log time, offset)
        at = end
    if not keys or total != chunk.index_length or seen != chunk.channels:
        return None
    keys.sort()
    starts = [key >> 16 for key in keys]  # before the first: schemas and channels (read)
    channels = [key & 0xFFFF for key in keys]
    ends = [*starts[1:], size]
    if min(map(sub, ends, starts)) < PAYLOAD_AT:
        return None
    wanted = {cid: wants(cid) for cid in seen}
    flags = [wanted[cid] for cid in channels]
    pieces = _pieces(starts, ends, flags, size)
    if 2 * sum(stop - start for start, stop in pieces) > size:
        return None  # reading the whole chunk costs about the same
    return Plan(
        starts, ends, channels, flags, pieces, frozenset(cid for cid in seen if wanted[cid])
    )


def indexed_count(chunk: ChunkIndex, index: bytes) -> int | None:
    """How many messages a chunk's message index records list (what a damaged chunk lost);
    None when they are not what the chunk index says they are."""
    count, at, total = 0, 0, len(index)
    while at < total:
        if at + _INDEX_HEAD.size > total:
            return None
        op, record_length, _, entries_length = _INDEX_HEAD.unpack_from(index, at)
        if (
            op != OP_MESSAGE_INDEX
            or record_length != 6 + entries_length
            or entries_length % _INDEX_ENTRY.size
        ):
            return None
        count += entries_length // _INDEX_ENTRY.size
        at += 9 + record_length
    return count if at == total == chunk.index_length and total else None


def _pieces(
    starts: list[int], ends: list[int], flags: list[bool], size: int
) -> list[tuple[int, int]]:
    """The ranges to read: everything but the runs of unwanted records worth skipping."""
    count = len(flags)
    turns = [k for k in range(1, count) if flags[k] != flags[k - 1]]
    pieces: list[tuple[int, int]] = []
    at = 0
    for first, stop in zip([0, *turns], [*turns, count], strict=True):
        if flags[first]:
            continue
        skip_from, skip_to = starts[first] + RECORD_HEAD.size, ends[stop - 1]
        if skip_to - skip_from >= SKIP_AT_LEAST:
            pieces.append((at, skip_from))
            at = skip_to
    if at < size:
        pieces.append((at, size))
    return pieces


class Hints(Protocol):
    """What the window needs of a :class:`~medkit_replay.inputs.ranges.RangeReader`."""

    def cached(self, offset: int, length: int) -> bytes | None: ...

    def will_need(self, offset: int, length: int) -> None: ...


class ReadAhead:
    """What is asked for ahead of the chunk being read, topped up in strides of half a window.

    Heads and message indexes of the next HEADS_AHEAD chunks; then, of the next PIECES_AHEAD
    chunks whose head and index are at hand, the pieces of their plans (kept for the reader)
    or, when a chunk is not read by index, the whole chunk record: at most AHEAD_BYTES.
    """

    def __init__(
        self,
        chunks: list[ChunkIndex],
        plan: Callable[[ChunkIndex, bytes, bytes], Plan | None],
        data_end: int,
    ) -> None:
        self._chunks = chunks
        self._plan = plan  # (chunk, head, index) -> its plan
        self._data_end = data_end
        self._heads = 0  # chunks whose heads and indexes are asked for
        self._pieces = 0  # chunks whose pieces are asked for
        self._asked: dict[int, int] = {}  # bytes asked for, by chunk number
        self.plans: dict[int, Plan] = {}  # by chunk number: made while asking ahead

    def advance(self, reader: Hints, number: int) -> None:
        """Chunk ``number`` is read next: ask for what the window lacks."""
        for done in [k for k in self._asked if k < number]:
            del self._asked[done]
            self.plans.pop(done, None)
        chunks = self._chunks
        if self._heads - number <= HEADS_AHEAD // 2:
            for chunk in chunks[self._heads : number + HEADS_AHEAD]:
                if self._inside(chunk):
                    reader.will_need(chunk.offset, PLAIN_CHUNK_HEAD)
                    reader.will_need(chunk.offset + chunk.length, chunk.index_length)
            self._heads = min(len(chunks), max(self._heads, number + HEADS_AHEAD))
        self._pieces = max(self._pieces, number)
        if self._pieces - number > PIECES_AHEAD // 2:
            return
        stop = min(self._heads, number + PIECES_AHEAD)
        while self._pieces < stop and (not self._asked or sum(self._asked.values()) < AHEAD_BYTES):
            asked = self._ask(reader, self._pieces)
            if asked is None:
                return  # its head or index is not at hand yet: next time
            self._asked[self._pieces] = asked
            self._pieces += 1

    def _inside(self, chunk: ChunkIndex) -> bool:
        """Whether the chunk and its message index lie inside the data (else: damage)."""
        end = chunk.offset + chunk.length + chunk.index_length
        return chunk.length >= PLAIN_CHUNK_HEAD and end <= self._data_end

    def _ask(self, reader: Hints, number: int) -> int | None:
        """Ask for the pieces of chunk ``number``, or its whole record; the bytes asked for
        (None: its head or index is not at hand)."""
        chunk = self._chunks[number]
        if not self._inside(chunk):
            return 0  # damage the reader reports when it comes to it; nothing to ask for
        head = reader.cached(chunk.offset, PLAIN_CHUNK_HEAD)
        if head is None:
            return None
        plan = None
        if len(head) == PLAIN_CHUNK_HEAD and chunk.index_length:
            index = reader.cached(chunk.offset + chunk.length, chunk.index_length)
            if index is None:
                return None
            plan = self._plan(chunk, head, index)
        if plan is None:  # read whole: its record after the opcode and length
            reader.will_need(chunk.offset + 9, chunk.length - 9)
            return chunk.length
        self.plans[number] = plan
        base = chunk.offset + PLAIN_CHUNK_HEAD
        for start, stop in plan.pieces:
            reader.will_need(base + start, stop - start)
        return sum(stop - start for start, stop in plan.pieces)
