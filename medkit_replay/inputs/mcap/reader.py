"""MCAP storage files: a streaming reader that uses the chunk index when intact, else scans.

Read-only and bounded: a length field is obeyed only within the file and RECORD_SIZE_LIMIT.
Bytes come through a RangeReader (inputs.ranges): a local file or a remote object alike.
Uncompressed chunks without a checksum are read through their message indexes when that skips
most of their bytes (only the wanted records are read, and the first header of each run of other
records skipped: inputs.mcap.plan); anything irregular in what is read falls back to reading the
whole chunk, so what is delivered never depends on the route taken. The records inside a skipped
run are taken to be what the message index (checked against the summary) says they are, as a
chunk without a wanted topic is never read: damage there goes unseen on both counts.
"""

from __future__ import annotations

from binascii import crc32
from bisect import bisect_left
from dataclasses import replace
from operator import itemgetter
from struct import Struct
from typing import TYPE_CHECKING, BinaryIO

from medkit_replay.inputs.decompress import ChunkDamageError, decompress_chunk
from medkit_replay.inputs.mcap.plan import (
    PAYLOAD_AT,
    PLAIN_CHUNK_HEAD,
    RECORD_HEAD,
    ChunkIndex,
    Plan,
    ReadAhead,
    indexed_count,
    plan_chunk,
)
from medkit_replay.inputs.mcap.window import merge_window, window_chunks
from medkit_replay.inputs.merge import Bound, Timed
from medkit_replay.inputs.ranges import LocalSource
from medkit_replay.inputs.storage import RECORD_SIZE_LIMIT, Connection, NotABagError, Raw
from medkit_replay.model import Loss
from medkit_replay.msgdefs import NO_DEFINITION, Definition, normalize_typename

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator
    from pathlib import Path

    from medkit_replay.inputs.ranges import ByteSource, RangeReader
    from medkit_replay.inputs.source import Warn

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
_CHUNK_HEAD = Struct("<BQQQQII")  # opcode, length, start, end, size, crc, compression length
_U64 = Struct("<Q")
_MESSAGE_HEAD = Struct("<BQHIQ")  # opcode, length, channel id, sequence, log time
_ORDER = itemgetter(0, 1)  # (log time, position) of a Timed
_T_NS = itemgetter(0)  # log time of a Timed
_SEEN_T_NS = itemgetter(1)  # log time of a (channel id, log time) pair
LOG_TIME_LIMIT = 2**63
"""Log times at or above it cannot come from ROS 2 (int64 nanoseconds): such a message is damage."""
NO_FOOTER = "no footer (the recorder did not close the file)"
_new = tuple.__new__  # builds a Timed or Raw from a tuple without its Python-level __new__


class _DamageError(Exception):
    """A record's content does not fit its declared length."""


class _Cursor:
    """Little-endian reader over one record's bytes that refuses to run past its end."""

    __slots__ = ("data", "pos")

    def __init__(self, data: bytes | memoryview) -> None:
        self.data = memoryview(data)
        self.pos = 0

    def take(self, size: int) -> memoryview:
        if size < 0 or self.pos + size > len(self.data):
            raise _DamageError(f"field of {size} bytes overruns its record")
        self.pos += size
        return self.data[self.pos - size : self.pos]

    def uint(self, size: int) -> int:
        return int.from_bytes(self.take(size), "little")

    def string(self) -> str:
        return bytes(self.take(self.uint(4))).decode("utf-8", "replace")

    def rest(self) -> memoryview:
        return self.take(len(self.data) - self.pos)


def _plain(head: bytes) -> bool:
    """Whether a chunk's head declares it uncompressed, without checksum, its size plausible."""
    _, length, _, _, size, crc, compression = _CHUNK_HEAD.unpack_from(head)
    if compression or crc or size > RECORD_SIZE_LIMIT:
        return False
    declared = int(_U64.unpack_from(head, PLAIN_CHUNK_HEAD - 8)[0])
    return bool(declared == size and 40 + size <= length)


_CHUNK_INDEX_HEAD = Struct("<QQQQI")  # start, end, chunk offset, chunk length, map length
_CHUNK_INDEX_ENTRY = Struct("<HQ")  # channel id, message index offset


def _chunk_index(body: memoryview) -> ChunkIndex | None:
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
    index_length = _U64.unpack_from(body, end)[0] if end + 8 <= len(body) else 0
    return ChunkIndex(start_ns, offset, length, channels, index_length, end_ns)


class McapFile:
    """One MCAP file; see :class:`medkit_replay.inputs.storage.StorageFile`."""

    storage = "mcap"

    def __init__(
        self,
        path: Path,
        file_no: int,
        warn: Warn,
        *,
        indexed: bool = True,
        source: ByteSource | None = None,
    ) -> None:
        self.path = path
        self._source = source if source is not None else LocalSource(path)
        self.file_no = file_no
        self.warn = warn
        self.indexed = indexed  # False: always read whole chunks
        self._buffer = bytearray()
        self._cold = True  # the chunk being read is not at hand (not in the page cache)
        self.connections: dict[int, Connection] = {}
        self.counts: dict[int, int] = {}
        self.start_ns: int | None = None
        self.end_ns: int | None = None
        self._schemas: dict[int, tuple[str, Definition]] = {}
        self._chunks: list[ChunkIndex] | None = None
        self._wanted: dict[int, bool] = {}
        self._unknown_channels = 0
        self.index_problem: str | None = None  # why the summary is unusable (None: no summary)
        try:
            with self._source.ranges() as reader:
                self._size = reader.size
                self._probe(reader)
        except OSError as exc:
            raise NotABagError(f"cannot read: {exc.strerror or exc}") from None

    # -- probing -------------------------------------------------------------------------------

    def _probe(self, reader: RangeReader) -> None:
        if self._size == 0:
            raise NotABagError("empty file, not an MCAP file")
        head = reader.read(0, len(MAGIC) + 9)
        if head[: len(MAGIC)] != MAGIC:
            raise NotABagError("not an MCAP file (bad magic)")
        if len(head) < len(MAGIC) + 9 or head[len(MAGIC)] != OP_HEADER:
            raise NotABagError("MCAP file cut off before its header record")
        length = int.from_bytes(head[len(MAGIC) + 1 :], "little")
        self._data_start = len(head) + length
        if self._data_start > self._size:
            raise NotABagError("MCAP file cut off inside its header record")
        try:
            profile = _Cursor(reader.read(len(head), length)).string()
        except _DamageError:
            raise NotABagError("MCAP header record is damaged") from None
        if profile != "ros2":
            self.warn(f"{self.path}: MCAP profile {profile!r}, not 'ros2'; reading it anyway")
        self._data_end = self._size
        problem = self._read_footer_and_summary(reader)
        self.index_problem = problem
        if self._chunks is None:
            self.counts.clear()
            self.start_ns = self.end_ns = None
            if problem:
                self.summary_problem(problem)

    def summary_problem(self, problem: str) -> None:
        """Say why the summary cannot be used: the messages are still scanned, so a damaged
        summary costs none; a missing footer means a file cut short, which costs unknown."""
        loss = Loss() if problem == NO_FOOTER else Loss(messages=0)
        self.warn(f"{self.path}: {problem}; scanning the file from the start", loss)

    def _read_footer_and_summary(self, reader: RangeReader) -> str | None:
        footer_pos = self._size - FOOTER_SIZE
        if footer_pos < self._data_start:
            return NO_FOOTER
        footer = reader.read(footer_pos, FOOTER_SIZE)
        if footer[-len(MAGIC) :] != MAGIC or footer[0] != OP_FOOTER:
            return NO_FOOTER
        cur = _Cursor(footer[9:29])
        summary_start, _, summary_crc = cur.uint(8), cur.uint(8), cur.uint(4)
        self._data_end = footer_pos
        if summary_start == 0:
            return None
        if not self._data_start <= summary_start <= footer_pos:
            return f"footer points to a summary at byte {summary_start}, outside the file"
        if footer_pos - summary_start > RECORD_SIZE_LIMIT:
            return f"summary section of {footer_pos - summary_start} bytes is implausible"
        summary = reader.read(summary_start, footer_pos - summary_start)
        if summary_crc and crc32(summary + footer[:25]) != summary_crc:
            return "summary section fails its checksum"
        try:
            indexes, chunk_count = self._parse_summary(summary)
        except _DamageError as exc:
            return f"summary section is damaged ({exc})"
        self._data_end = summary_start
        if any(index.start_ns >= LOG_TIME_LIMIT for index in indexes) or (
            self.end_ns is not None and self.end_ns >= LOG_TIME_LIMIT
        ):
            return "summary section holds log times at or after 2^63 ns"
        if chunk_count is not None and chunk_count != len(indexes):
            return f"summary indexes {len(indexes)} of {chunk_count} chunks"
        if indexes and chunk_count and self.connections:
            self._chunks = sorted(indexes)
        return None

    def _parse_summary(self, summary: bytes) -> tuple[list[ChunkIndex], int | None]:
        """Schemas, channels and statistics into self; returns chunk indexes and chunk count."""
        indexes: list[ChunkIndex] = []
        chunk_count = None
        cur = _Cursor(summary)
        while cur.pos < len(summary):
            op = cur.uint(1)
            record = _Cursor(cur.take(cur.uint(8)))
            if op == OP_SCHEMA:
                self._add_schema(record)
            elif op == OP_CHANNEL:
                self._add_channel(record)
            elif op == OP_CHUNK_INDEX and (fast := _chunk_index(record.data)) is not None:
                indexes.append(fast)
            elif op == OP_CHUNK_INDEX:
                start_ns, end_ns, offset, length = (record.uint(8) for _ in range(4))
                offsets = _Cursor(record.take(record.uint(4)))
                channels = []
                while offsets.pos < len(offsets.data):
                    channels.append(offsets.uint(2))
                    offsets.uint(8)
                try:
                    index_length = record.uint(8)
                except _DamageError:
                    index_length = 0  # only an optimisation is lost
                indexes.append(
                    ChunkIndex(start_ns, offset, length, frozenset(channels), index_length, end_ns)
                )
            elif op == OP_STATISTICS:
                record.take(8 + 2 + 4 * 3)  # message, schema, channel, attachment, metadata counts
                chunk_count = record.uint(4)
                self.start_ns, self.end_ns = record.uint(8), record.uint(8)
                counts = _Cursor(record.take(record.uint(4)))
                while counts.pos < len(counts.data):
                    cid = counts.uint(2)
                    self.counts[cid] = counts.uint(8)
                if not self.counts:
                    self.start_ns = self.end_ns = None
        return indexes, chunk_count

    def _add_schema(self, record: _Cursor) -> None:
        sid = record.uint(2)
        name, encoding = record.string(), record.string()
        text = bytes(record.take(record.uint(4))).decode("utf-8", "replace")
        self._schemas[sid] = (name, Definition(encoding, text))

    def _add_channel(self, record: _Cursor) -> None:
        cid, sid = record.uint(2), record.uint(2)
        topic, encoding = record.string(), record.string()
        if cid in self.connections:
            return
        name, definition = self._schemas.get(sid, ("", NO_DEFINITION))
        msgtype = normalize_typename(name) if name else ""
        self.connections[cid] = Connection(cid, topic, msgtype, encoding, definition)

    def close(self) -> None:
        """Nothing to release: the file is open only while it is read."""

    # -- reading -------------------------------------------------------------------------------

    def read(
        self, wants: Callable[[Connection], bool], cap_ns: int | None
    ) -> Iterator[Bound | Timed[Raw] | list[Timed[Raw]]]:
        """Yield bounds and wanted messages (see ``StorageFile.read``)."""
        self._accept = wants
        cap = cap_ns if cap_ns is not None else 2**63
        for cid in sorted(self.connections):
            self._wants(cid)  # every declared topic is classified, read or not
        if self._chunks is not None:
            with self._source.ranges() as reader:
                yield from self._read_indexed(reader, cap)
        else:
            with self._source.stream() as bio:
                yield from self._read_linear(bio, cap)
        if self._unknown_channels:
            self.warn(
                f"{self.path}: messages refer to channels the file never declares",
                Loss(messages=self._unknown_channels),
            )

    def _wants(self, cid: int) -> bool:
        if cid not in self._wanted:
            connection = self.connections.get(cid)
            self._wanted[cid] = connection is not None and self._accept(connection)
        return self._wanted[cid]

    def _has_wanted(self, chunk: ChunkIndex) -> bool:
        """Whether a chunk may hold a wanted message (an index listing no channel: maybe)."""
        return not chunk.channels or any(self._wants(cid) for cid in chunk.channels)

    def _may_want(self, chunk: ChunkIndex) -> bool:
        """:meth:`_has_wanted` before the chunks are read (a channel not declared yet: maybe)."""
        return not chunk.channels or any(self._wanted.get(cid, True) for cid in chunk.channels)

    def _read_indexed(
        self, reader: RangeReader, cap: int
    ) -> Iterator[Bound | Timed[Raw] | list[Timed[Raw]]]:
        # Chunks without a wanted topic are never read. Reading by index is many small
        # reads; from a cold disk or over the network each would wait its turn, so the next
        # chunks' heads, indexes and pieces are asked for ahead while this one is decoded.
        chunks = [chunk for chunk in self._chunks or [] if self._may_want(chunk)]
        ahead = ReadAhead(chunks, self._plan_ahead, self._data_end) if self.indexed else None
        for number, chunk in enumerate(chunks):
            if not self._has_wanted(chunk):
                continue  # no wanted topic in it, now that it is known: never read
            reader.forget(chunk.offset)
            if ahead is not None and (reader.always_ahead or self._cold):
                ahead.advance(reader, number)
            head = self._chunk_head(reader, chunk)
            if head is None:
                continue
            yield Bound(min(chunk.start_ns, cap))
            plan = ahead.plans.pop(number, None) if ahead is not None else None
            timed = self._chunk_messages(reader, chunk, head, plan)
            if timed:
                yield Bound(min(timed[0].t_ns, cap))
                yield timed

    def _chunk_head(self, reader: RangeReader, chunk: ChunkIndex) -> bytes | None:
        """The first bytes of the chunk record the index points to; None (warned): none there."""
        head = reader.read(chunk.offset, PLAIN_CHUNK_HEAD)
        length = int.from_bytes(head[1:9], "little") if len(head) >= 9 else -1
        if (
            head[:1] != bytes([OP_CHUNK])
            or 9 + length != chunk.length
            or length > min(RECORD_SIZE_LIMIT, self._size - chunk.offset - 9)
        ):
            self.warn(
                f"{self.path}: the chunk index points to no valid chunk at byte {chunk.offset}",
                self._chunk_loss(reader, chunk),
            )
            return None
        return head

    def _chunk_loss(
        self, reader: RangeReader, chunk: ChunkIndex, kept: int = 0, size: int | None = None
    ) -> Loss:
        """What losing an indexed chunk (but ``kept`` of its messages) costs: the messages its
        message index lists, its bytes (or ``size``), the span the chunk index gives it."""
        listed = None
        if chunk.index_length and chunk.offset + chunk.length + chunk.index_length <= self._size:
            index = reader.read(chunk.offset + chunk.length, chunk.index_length)
            listed = indexed_count(chunk, index)
        return Loss(
            messages=listed - kept if listed is not None and listed >= kept else None,
            bytes=chunk.length if size is None else size,
            start_ns=chunk.start_ns,
            end_ns=chunk.end_ns if chunk.end_ns < LOG_TIME_LIMIT else None,
        )

    def _chunk_messages(
        self, reader: RangeReader, chunk: ChunkIndex, head: bytes, plan: Plan | None
    ) -> list[Timed[Raw]]:
        """The wanted messages of an indexed chunk whose ``head`` is valid, sorted by (log time,
        position): by its message index when that pays, else the whole chunk decompressed."""
        timed = None
        if self.indexed and chunk.index_length and len(head) == PLAIN_CHUNK_HEAD:
            timed = self._by_index(reader, chunk, head, plan)
        if timed is None:
            body = self._read_into_buffer(reader, chunk.offset + 9, chunk.length - 9)
            indexed = (reader, chunk)
            for batch in self._chunk(body, chunk.offset, LOG_TIME_LIMIT, False, indexed=indexed):
                if isinstance(batch, list):
                    return batch
            return []
        timed.sort(key=_ORDER)
        return timed

    # -- reading a time window ------------------------------------------------------------------

    @property
    def chunk_indexed(self) -> bool:
        """Whether the summary's chunk index is intact (time windows can be read)."""
        return self._chunks is not None

    def read_window(
        self,
        wants: Callable[[Connection], bool],
        start_ns: int,
        end_ns: int,
        *,
        reverse: bool = False,
    ) -> Iterator[Timed[Raw]]:
        """The wanted messages with log time in [start_ns, end_ns], in (log time, position)
        order or, with ``reverse``, the opposite; only for a :attr:`chunk_indexed` file.

        Chunks outside the window or without a wanted channel are never read; a chunk is read
        only when the order needs it, so a reverse read taking the latest message reads the
        chunks at the window's end only. Damage is warned and skipped as in :meth:`read`.
        Several windows may be read at once (interleaved): each keeps its own wanted channels.
        """
        wanted: dict[int, bool] = {}
        chunks = window_chunks(self._chunks or [], start_ns, end_ns, reverse=reverse)
        with self._source.ranges() as reader:

            def decode(chunk: ChunkIndex) -> list[Timed[Raw]]:
                self._accept, self._wanted = wants, wanted  # this window's, while it decodes
                if not self._has_wanted(chunk):
                    return []
                head = self._chunk_head(reader, chunk)
                return [] if head is None else self._chunk_messages(reader, chunk, head, None)

            yield from merge_window(chunks, decode, start_ns, end_ns, reverse=reverse)

    def _read_into_buffer(self, reader: RangeReader, offset: int, length: int) -> memoryview:
        """``length`` bytes at ``offset`` (fewer at the end of the file) in the reused buffer.

        The view is valid until the next call; whatever must outlive it is copied out.
        """
        if len(self._buffer) < length:
            self._buffer = bytearray(length)  # a new one: views of the old stay valid
        view = memoryview(self._buffer)[:length]
        return view[: reader.read_into(offset, view)]

    def _by_index(
        self,
        reader: RangeReader,
        chunk: ChunkIndex,
        head: bytes,
        plan: Plan | None = None,
    ) -> list[Timed[Raw]] | None:
        """The wanted messages of an uncompressed chunk, read through its message indexes.

        Only the wanted records and the first header of each run of other records skipped
        are read (:func:`~medkit_replay.inputs.mcap.plan.plan_chunk`; ``plan``: made while
        asking ahead). None when that does not pay (most of the chunk is wanted) or anything
        read is irregular: a compressed or checksummed chunk, an index that does not tile the
        chunk's records with message records or names other channels than the summary, a
        record read that is not where and what the index says. The whole chunk is then read,
        so both routes deliver the same messages (the records inside a skipped run are taken
        to be what the index says, as chunks without a wanted topic are never read).
        """
        index_at = chunk.offset + chunk.length
        if not _plain(head) or index_at + chunk.index_length > self._data_end:
            return None
        if plan is not None and plan.wanted != {c for c in chunk.channels if self._wants(c)}:
            plan = None  # made ahead, before a channel was declared (inside an earlier chunk)
        if plan is None:
            plan = self._plan(chunk, head, reader.read(index_at, chunk.index_length))
        if plan is None:
            return None
        starts, ends, channels, flags, pieces, _ = plan
        base = chunk.offset + PLAIN_CHUNK_HEAD
        first = reader.cached(base + pieces[0][0], pieces[0][1] - pieces[0][0])
        self._cold = first is None
        if self._cold and len(pieces) > 1:  # not at hand: all pieces in flight at once
            for start, stop in pieces:
                reader.will_need(base + start, stop - start)
        timed: list[Timed[Raw]] = []
        unpack_message, unpack_head = _MESSAGE_HEAD.unpack_from, RECORD_HEAD.unpack_from
        connections, file_no, pos = self.connections, self.file_no, chunk.offset
        k, count = 0, len(starts)
        for start, stop in pieces:
            if first is not None:
                data, first = first, None
            else:
                data = reader.read(base + start, stop - start)
            if len(data) != stop - start:
                return None
            prefix = starts[0] if not start else 0  # schema and channel records only
            if prefix and self._declarations(memoryview(data)[:prefix]) != prefix:
                return None
            k = bisect_left(starts, start, k)  # past the rest of a skipped run
            while k < count and starts[k] < stop:
                inner, end = starts[k], ends[k]
                at = inner - start
                if end <= stop:
                    op, record_length, cid, _, t_ns = unpack_message(data, at)
                    if op != OP_MESSAGE or record_length != end - inner - 9:
                        return None
                    if flags[k] if cid == channels[k] else self._wants(cid):
                        payload = data[at + PAYLOAD_AT : at + 9 + record_length]
                        timed.append(
                            _new(
                                Timed,
                                (
                                    t_ns,
                                    (file_no, pos, inner),
                                    _new(Raw, (connections[cid], payload)),
                                ),
                            )
                        )
                else:
                    op, record_length, cid = unpack_head(data, at)
                    if op != OP_MESSAGE or record_length != end - inner - 9 or self._wants(cid):
                        return None
                k += 1
        if timed and max(map(_T_NS, timed)) >= LOG_TIME_LIMIT:
            return None  # the careful parser skips and reports it
        return timed

    def _plan(
        self, chunk: ChunkIndex, head: bytes, index: bytes, ahead: bool = False
    ) -> Plan | None:
        """How to read a chunk by its message index (None: read it whole); ``ahead``: before
        the chunks between are read, so no channel's classification is settled by it."""
        if len(head) != PLAIN_CHUNK_HEAD or not _plain(head):
            return None
        if not chunk.channels <= self.connections.keys():
            return None  # declared inside the chunk: read it whole (its wanted flags unknown)
        size = _CHUNK_HEAD.unpack_from(head)[4]
        return plan_chunk(chunk, size, index, self._peek if ahead else self._wants)

    def _plan_ahead(self, chunk: ChunkIndex, head: bytes, index: bytes) -> Plan | None:
        return self._plan(chunk, head, index, ahead=True)

    def _peek(self, cid: int) -> bool:
        """:meth:`_wants` without keeping the answer (a channel may yet be declared)."""
        return self._wanted.get(cid, False)

    def _read_linear(
        self, bio: BinaryIO, cap: int
    ) -> Iterator[Bound | Timed[Raw] | list[Timed[Raw]]]:
        pos = self._data_start
        bio.seek(pos)
        while pos < self._data_end or self._grow(pos + 1):
            if pos + 9 > self._data_end:
                self._grow(pos + 9)
                bio.seek(pos)
            end = self._data_end
            head = bio.read(9)
            if len(head) < 9:
                self._truncated(pos, "a record header")
                return
            op, length = head[0], int.from_bytes(head[1:], "little")
            if op in (OP_DATA_END, OP_FOOTER):
                return
            body_end = pos + 9 + length
            if op == OP_MESSAGE and length < MESSAGE_HEADER:
                self.warn(
                    f"{self.path}: invalid message record at byte {pos}; the rest is lost",
                    Loss(bytes=self._size - pos),
                )
                return
            if op == 0 or length > RECORD_SIZE_LIMIT:
                self.warn(
                    f"{self.path}: invalid record (opcode {op:#04x}, {length} bytes) at byte "
                    f"{pos}; the last {self._size - pos} bytes are lost",
                    Loss(bytes=self._size - pos),
                )
                return
            if body_end > end:
                self._grow(body_end)
                end = self._data_end
                bio.seek(pos + 9)
            if body_end > end:
                span = None
                if op == OP_CHUNK and end - pos - 9 > 0:
                    body = memoryview(bio.read(end - pos - 9))
                    yield from self._chunk(body, pos, cap, count=True, partial=True)
                    span = _chunk_span(body)
                self._truncated(pos, f"a record (opcode {op:#04x}) of {length} bytes", span)
                return
            if op == OP_MESSAGE:
                fixed = bio.read(MESSAGE_HEADER)
                cid, t_ns = (
                    int.from_bytes(fixed[:2], "little"),
                    int.from_bytes(fixed[6:14], "little"),
                )
                if t_ns >= LOG_TIME_LIMIT:
                    self._late_message(f"{self.path}: message at byte {pos}", 1, t_ns)
                    pos = body_end
                    bio.seek(pos)
                    continue
                self._count(cid, t_ns)
                if self._wants(cid):
                    raw = Raw(self.connections[cid], bio.read(length - MESSAGE_HEADER))
                    yield Bound(min(t_ns, cap))
                    yield Timed(t_ns, (self.file_no, pos, 0), raw)
            elif op == OP_CHUNK:
                yield from self._chunk(memoryview(bio.read(length)), pos, cap, count=True)
            elif op in (OP_SCHEMA, OP_CHANNEL):
                try:
                    self._parse_records(bio.read(length), op)
                except _DamageError as exc:
                    self.warn(
                        f"{self.path}: damaged schema or channel at byte {pos}: {exc}",
                        Loss(messages=0, bytes=9 + length),  # its messages: unknown channels
                    )
            pos = body_end
            bio.seek(pos)

    def _grow(self, need: int) -> bool:
        """Whether the data now reaches byte ``need``; a followed file waits for its writer
        here (:mod:`medkit_replay.inputs.mcap.tail`), a file read as it stands never grows."""
        return need <= self._data_end

    def _parse_records(self, body: bytes, op: int) -> None:
        if op == OP_SCHEMA:
            self._add_schema(_Cursor(body))
        else:
            self._add_channel(_Cursor(body))

    def _truncated(self, pos: int, what: str, span: tuple[int, int] | None = None) -> None:
        """Say the file ends inside a record: its bytes from ``pos`` are lost (a chunk cut off
        gives the ``span`` of its messages; how many of them are lost is unknown)."""
        start_ns, end_ns = span if span is not None else (None, None)
        self.warn(
            f"{self.path}: file ends inside {what} at byte {pos} of {self._size} (truncated: "
            f"recorder stopped mid-write?); the last {self._size - pos} bytes are lost",
            Loss(bytes=self._size - pos, start_ns=start_ns, end_ns=end_ns),
        )

    def _late_message(self, where: str, count: int, t_ns: int) -> None:
        what = "a log time" if count == 1 else f"{count} messages with log times"
        self.warn(
            f"{where}: {what} at or after 2^63 ns ({t_ns}), which ROS 2 cannot record; damaged",
            Loss(messages=count),
        )

    def _count(self, cid: int, t_ns: int) -> None:
        self.counts[cid] = self.counts.get(cid, 0) + 1
        self.start_ns = t_ns if self.start_ns is None else min(self.start_ns, t_ns)
        self.end_ns = t_ns if self.end_ns is None else max(self.end_ns, t_ns)
        if cid not in self.connections:
            self._unknown_channels += 1

    def _chunk(
        self,
        body: memoryview,
        pos: int,
        cap: int,
        count: bool,
        partial: bool = False,
        indexed: tuple[RangeReader, ChunkIndex] | None = None,
    ) -> Iterator[Bound | Timed[Raw] | list[Timed[Raw]]]:
        """Decompress one chunk and yield its wanted messages sorted by (log time, offset);
        ``indexed``: read through the chunk index, which says what a damaged chunk lost."""
        where = f"{self.path}: chunk at byte {pos}"
        try:
            cur = _Cursor(body)
            start_ns, end_ns, size, crc = cur.uint(8), cur.uint(8), cur.uint(8), cur.uint(4)
            compression, compressed = cur.string(), cur.uint(8)
            data = cur.rest() if partial else cur.take(compressed)
        except _DamageError as exc:
            self.warn(f"{where}: header damaged ({exc})", self._lost_chunk(body, indexed))
            return
        span = f"log times {start_ns}..{end_ns}"
        if partial and compression:  # what it cost is said with the cut
            self.warn(f"{where} ({span}) is cut off and {compression}-compressed; it is lost")
            return
        if size > RECORD_SIZE_LIMIT:
            self.warn(
                f"{where} ({span}) claims {size} bytes uncompressed: damaged",
                self._lost_chunk(body, indexed),
            )
            return
        if partial or (not compression and len(data) == size and not crc):
            records = data  # what decompressing would give, without copying it
        else:
            try:
                records = memoryview(decompress_chunk(bytes(data), compression, size, crc))
            except ChunkDamageError as exc:
                self.warn(
                    f"{where} ({span}) cannot be decompressed: {exc}",
                    self._lost_chunk(body, indexed),
                )
                return
        fast = None if partial else self._plain_records(records, pos, count)
        timed, problem, late = (
            (fast, None, None) if fast is not None else self._chunk_records(records, pos, count)
        )
        if late is not None:
            late_count, late_at, late_t_ns = late
            self._late_message(
                f"{where} ({span}), record at byte {late_at} of its records",
                late_count,
                late_t_ns,
            )
        if partial:  # what it cost is said with the cut
            self.warn(f"{where} ({span}): cut off; kept {len(timed)} messages")
        elif problem is not None:
            text, stop, walked = problem
            loss = self._lost_chunk(body, indexed, walked)
            rest = len(records) - stop if not compression else None  # of the file's bytes
            self.warn(
                f"{where} ({span}): {text}; kept {len(timed)} messages", replace(loss, bytes=rest)
            )
        timed.sort(key=_ORDER)
        if timed:
            yield Bound(min(timed[0].t_ns, cap))
            yield timed

    def _plain_records(self, records: memoryview, pos: int, count: bool) -> list[Timed[Raw]] | None:
        """:meth:`_chunk_records` for the common case: message records only, all intact.

        Schema and channel records before the first message are taken in. None at the first
        record that is not (damage, a schema or channel between messages): the careful parser
        then reads the chunk from its start.
        """
        timed: list[Timed[Raw]] = []
        seen: list[tuple[int, int]] = []
        size = len(records)
        unpack = _MESSAGE_HEAD.unpack_from
        wants, connections, file_no = self._wants, self.connections, self.file_no
        at = self._declarations(records)
        if at is None:
            return None
        while at < size:
            if at + _MESSAGE_HEAD.size > size:
                return None
            op, length, cid, _, t_ns = unpack(records, at)
            end = at + 9 + length
            if op != OP_MESSAGE or length < MESSAGE_HEADER or end > size:
                return None
            if count:
                seen.append((cid, t_ns))
            if wants(cid):
                payload = records[at + PAYLOAD_AT : end].tobytes()
                raw = _new(Raw, (connections[cid], payload))
                timed.append(_new(Timed, (t_ns, (file_no, pos, at), raw)))
            at = end
        if (timed and max(map(_T_NS, timed)) >= LOG_TIME_LIMIT) or (
            seen and max(map(_SEEN_T_NS, seen)) >= LOG_TIME_LIMIT
        ):
            return None  # the careful parser skips and reports them
        for cid, t_ns in seen:
            self._count(cid, t_ns)
        return timed

    def _declarations(self, records: memoryview) -> int | None:
        """Take in the schema and channel records a chunk's records start with; where the
        first other record starts (None: one of them is damaged)."""
        at, size = 0, len(records)
        while at + 9 <= size and records[at] in (OP_SCHEMA, OP_CHANNEL):
            end = at + 9 + int.from_bytes(records[at + 1 : at + 9], "little")
            if end > size:
                return None
            try:
                self._parse_records(bytes(records[at + 9 : end]), records[at])
            except _DamageError:
                return None
            at = end
        return at

    def _chunk_records(
        self, records: memoryview, pos: int, count: bool
    ) -> tuple[list[Timed[Raw]], tuple[str, int, int] | None, tuple[int, int, int] | None]:
        """Every record of a chunk, carefully: its wanted messages, the damage that ended the
        walk (if any: what, where in the records, how many messages were walked before it),
        and messages skipped for log times past int64 (count, first offset, time).
        """
        timed: list[Timed[Raw]] = []
        late: tuple[int, int, int] | None = None
        cur = _Cursor(records)
        walked = inner = 0
        try:
            while cur.pos < len(records):
                inner = cur.pos
                op = cur.uint(1)
                if op == 0:  # reserved opcode: zero-filled or overwritten bytes, not records
                    lost = len(records) - inner
                    problem = f"invalid opcode 0x00 at byte {inner} of its records ({lost} bytes)"
                    return timed, (problem, inner, walked), late
                record = _Cursor(cur.take(cur.uint(8)))
                if op == OP_MESSAGE:
                    cid, _, t_ns = record.uint(2), record.uint(4), record.uint(8)
                    record.uint(8)
                    walked += 1
                    if t_ns >= LOG_TIME_LIMIT:
                        late = (1, inner, t_ns) if late is None else (late[0] + 1, late[1], late[2])
                        continue
                    if count:
                        self._count(cid, t_ns)
                    if self._wants(cid):
                        raw = Raw(self.connections[cid], record.rest().tobytes())
                        timed.append(Timed(t_ns, (self.file_no, pos, inner), raw))
                elif op in (OP_SCHEMA, OP_CHANNEL):
                    self._parse_records(bytes(record.rest()), op)
        except _DamageError as exc:
            return timed, (f"damaged record inside ({exc})", inner, walked), late
        return timed, None, late

    def _lost_chunk(
        self, body: memoryview, indexed: tuple[RangeReader, ChunkIndex] | None, kept: int = 0
    ) -> Loss:
        """What losing a chunk (but ``kept`` of its messages) costs: as its chunk index and
        message index say, or (found by scanning) its bytes and the span its header gives."""
        if indexed is not None:
            return self._chunk_loss(*indexed, kept)
        start_ns, end_ns = _chunk_span(body) or (None, None)
        return Loss(bytes=9 + len(body), start_ns=start_ns, end_ns=end_ns)


def _chunk_span(body: memoryview) -> tuple[int, int] | None:
    """The log time span a chunk record's header gives (None: cut before it, or past int64)."""
    if len(body) < 16:
        return None
    start_ns, end_ns = int.from_bytes(body[:8], "little"), int.from_bytes(body[8:16], "little")
    return (start_ns, end_ns) if start_ns <= end_ns < LOG_TIME_LIMIT else None
