"""An MCAP chunk record's messages: decompressed within bounds, walked fast when intact and
record by record when not, and what losing a chunk costs.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

from medkit_replay.inputs.decompress import ChunkDamageError, decompress_chunk
from medkit_replay.inputs.mcap.plan import PAYLOAD_AT, ChunkIndex, indexed_count
from medkit_replay.inputs.mcap.records import (
    LOG_TIME_LIMIT,
    MESSAGE_HEAD,
    MESSAGE_HEADER,
    OP_CHANNEL,
    OP_MESSAGE,
    OP_SCHEMA,
    ORDER,
    SEEN_T_NS,
    T_NS,
    Cursor,
    DamageError,
    chunk_span,
    new_tuple,
)
from medkit_replay.inputs.mcap.summary import McapSummary
from medkit_replay.inputs.merge import Bound, Timed
from medkit_replay.inputs.storage import RECORD_SIZE_LIMIT, Raw
from medkit_replay.model import Loss

if TYPE_CHECKING:
    from collections.abc import Iterator

    from medkit_replay.inputs.ranges import RangeReader


class McapChunks(McapSummary):
    """The chunk records of an MCAP file turned into its wanted messages; :class:`McapFile`
    chooses which chunks and how their bytes are read."""

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

    def _late_message(self, where: str, count: int, t_ns: int) -> None:
        what = "a log time" if count == 1 else f"{count} messages with log times"
        self.warn(
            f"{where}: {what} at or after 2^63 ns ({t_ns}), which ROS 2 cannot record; damaged",
            Loss(messages=count),
        )

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
            cur = Cursor(body)
            start_ns, end_ns, size, crc = cur.uint(8), cur.uint(8), cur.uint(8), cur.uint(4)
            compression, compressed = cur.string(), cur.uint(8)
            data = cur.rest() if partial else cur.take(compressed)
        except DamageError as exc:
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
        timed.sort(key=ORDER)
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
        unpack = MESSAGE_HEAD.unpack_from
        wants, connections, file_no = self._wants, self.connections, self.file_no
        at = self._declarations(records)
        if at is None:
            return None
        while at < size:
            if at + MESSAGE_HEAD.size > size:
                return None
            op, length, cid, _, t_ns = unpack(records, at)
            end = at + 9 + length
            if op != OP_MESSAGE or length < MESSAGE_HEADER or end > size:
                return None
            if count:
                seen.append((cid, t_ns))
            if wants(cid):
                payload = records[at + PAYLOAD_AT : end].tobytes()
                raw = new_tuple(Raw, (connections[cid], payload))
                timed.append(new_tuple(Timed, (t_ns, (file_no, pos, at), raw)))
            at = end
        if (timed and max(map(T_NS, timed)) >= LOG_TIME_LIMIT) or (
            seen and max(map(SEEN_T_NS, seen)) >= LOG_TIME_LIMIT
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
            except DamageError:
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
        cur = Cursor(records)
        walked = inner = 0
        try:
            while cur.pos < len(records):
                inner = cur.pos
                op = cur.uint(1)
                if op == 0:  # reserved opcode: zero-filled or overwritten bytes, not records
                    lost = len(records) - inner
                    problem = f"invalid opcode 0x00 at byte {inner} of its records ({lost} bytes)"
                    return timed, (problem, inner, walked), late
                record = Cursor(cur.take(cur.uint(8)))
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
        except DamageError as exc:
            return timed, (f"damaged record inside ({exc})", inner, walked), late
        return timed, None, late

    def _lost_chunk(
        self, body: memoryview, indexed: tuple[RangeReader, ChunkIndex] | None, kept: int = 0
    ) -> Loss:
        """What losing a chunk (but ``kept`` of its messages) costs: as its chunk index and
        message index say, or (found by scanning) its bytes and the span its header gives."""
        if indexed is not None:
            return self._chunk_loss(*indexed, kept)
        start_ns, end_ns = chunk_span(body) or (None, None)
        return Loss(bytes=9 + len(body), start_ns=start_ns, end_ns=end_ns)
