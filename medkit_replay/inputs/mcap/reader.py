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

from bisect import bisect_left
from typing import TYPE_CHECKING, BinaryIO

from medkit_replay.inputs.mcap.chunks import McapChunks
from medkit_replay.inputs.mcap.plan import (
    PAYLOAD_AT,
    PLAIN_CHUNK_HEAD,
    RECORD_HEAD,
    ChunkIndex,
    Plan,
    ReadAhead,
    plan_chunk,
)
from medkit_replay.inputs.mcap.records import (
    CHUNK_HEAD,
    LOG_TIME_LIMIT,
    MESSAGE_HEAD,
    MESSAGE_HEADER,
    OP_CHANNEL,
    OP_CHUNK,
    OP_DATA_END,
    OP_FOOTER,
    OP_MESSAGE,
    OP_SCHEMA,
    ORDER,
    T_NS,
    DamageError,
    chunk_span,
    new_tuple,
    plain_chunk,
)
from medkit_replay.inputs.mcap.window import merge_window, window_chunks
from medkit_replay.inputs.merge import Bound, Timed
from medkit_replay.inputs.storage import RECORD_SIZE_LIMIT, Raw
from medkit_replay.model import Loss

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator
    from pathlib import Path

    from medkit_replay.inputs.ranges import ByteSource, RangeReader
    from medkit_replay.inputs.source import Warn
    from medkit_replay.inputs.storage import Connection


class McapFile(McapChunks):
    """One MCAP file; see :class:`medkit_replay.inputs.storage.StorageFile`."""

    def __init__(
        self,
        path: Path,
        file_no: int,
        warn: Warn,
        *,
        indexed: bool = True,
        source: ByteSource | None = None,
    ) -> None:
        self.indexed = indexed  # False: always read whole chunks
        self._buffer = bytearray()
        self._cold = True  # the chunk being read is not at hand (not in the page cache)
        super().__init__(path, file_no, warn, source=source)

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
        timed.sort(key=ORDER)
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
        if not plain_chunk(head) or index_at + chunk.index_length > self._data_end:
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
        unpack_message, unpack_head = MESSAGE_HEAD.unpack_from, RECORD_HEAD.unpack_from
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
                            new_tuple(
                                Timed,
                                (
                                    t_ns,
                                    (file_no, pos, inner),
                                    new_tuple(Raw, (connections[cid], payload)),
                                ),
                            )
                        )
                else:
                    op, record_length, cid = unpack_head(data, at)
                    if op != OP_MESSAGE or record_length != end - inner - 9 or self._wants(cid):
                        return None
                k += 1
        if timed and max(map(T_NS, timed)) >= LOG_TIME_LIMIT:
            return None  # the careful parser skips and reports it
        return timed

    def _plan(
        self, chunk: ChunkIndex, head: bytes, index: bytes, ahead: bool = False
    ) -> Plan | None:
        """How to read a chunk by its message index (None: read it whole); ``ahead``: before
        the chunks between are read, so no channel's classification is settled by it."""
        if len(head) != PLAIN_CHUNK_HEAD or not plain_chunk(head):
            return None
        if not chunk.channels <= self.connections.keys():
            return None  # declared inside the chunk: read it whole (its wanted flags unknown)
        size = CHUNK_HEAD.unpack_from(head)[4]
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
                    span = chunk_span(body)
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
                except DamageError as exc:
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

    def _truncated(self, pos: int, what: str, span: tuple[int, int] | None = None) -> None:
        """Say the file ends inside a record: its bytes from ``pos`` are lost (a chunk cut off
        gives the ``span`` of its messages; how many of them are lost is unknown)."""
        start_ns, end_ns = span if span is not None else (None, None)
        self.warn(
            f"{self.path}: file ends inside {what} at byte {pos} of {self._size} (truncated: "
            f"recorder stopped mid-write?); the last {self._size - pos} bytes are lost",
            Loss(bytes=self._size - pos, start_ns=start_ns, end_ns=end_ns),
        )
