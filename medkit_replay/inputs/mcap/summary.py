"""What an MCAP file declares before its messages: the header, the footer and the summary
(schemas, channels, statistics, chunk index), and which of its channels a read wants.
"""

from __future__ import annotations

from binascii import crc32
from typing import TYPE_CHECKING

from medkit_replay.inputs.mcap.plan import ChunkIndex
from medkit_replay.inputs.mcap.records import (
    FOOTER_SIZE,
    LOG_TIME_LIMIT,
    MAGIC,
    NO_FOOTER,
    OP_CHANNEL,
    OP_CHUNK_INDEX,
    OP_FOOTER,
    OP_HEADER,
    OP_SCHEMA,
    OP_STATISTICS,
    Cursor,
    DamageError,
    chunk_index_record,
)
from medkit_replay.inputs.ranges import LocalSource
from medkit_replay.inputs.storage import (
    RECORD_SIZE_LIMIT,
    Connection,
    NotABagError,
    StorageFields,
)
from medkit_replay.model import Loss
from medkit_replay.msgdefs import NO_DEFINITION, Definition, normalize_typename

if TYPE_CHECKING:
    from collections.abc import Callable
    from pathlib import Path

    from medkit_replay.inputs.ranges import ByteSource, RangeReader
    from medkit_replay.inputs.source import Warn


class McapSummary(StorageFields):
    """What one MCAP file declares, read before its messages; :class:`McapFile` reads them."""

    storage = "mcap"
    _accept: Callable[[Connection], bool]
    """Which connections the read under way wants (set by each read)."""

    def __init__(
        self,
        path: Path,
        file_no: int,
        warn: Warn,
        *,
        source: ByteSource | None = None,
    ) -> None:
        super().__init__(path, file_no, warn)
        self._source = source if source is not None else LocalSource(path)
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
        self._header_body(reader.read(len(head), length))
        self._data_end = self._size
        problem = self._read_footer_and_summary(reader)
        self.index_problem = problem
        if self._chunks is None:
            self.counts.clear()
            self.start_ns = self.end_ns = None
            if problem:
                self.summary_problem(problem)

    def _header_body(self, body: bytes) -> None:
        """Read the header record's profile; a profile other than ros2 is read anyway, said."""
        try:
            profile = Cursor(body).string()
        except DamageError:
            raise NotABagError("MCAP header record is damaged") from None
        if profile != "ros2":
            self.warn(f"{self.path}: MCAP profile {profile!r}, not 'ros2'; reading it anyway")

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
        cur = Cursor(footer[9:29])
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
        except DamageError as exc:
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
        cur = Cursor(summary)
        while cur.pos < len(summary):
            op = cur.uint(1)
            record = Cursor(cur.take(cur.uint(8)))
            if op == OP_SCHEMA:
                self._add_schema(record)
            elif op == OP_CHANNEL:
                self._add_channel(record)
            elif op == OP_CHUNK_INDEX and (fast := chunk_index_record(record.data)) is not None:
                indexes.append(fast)
            elif op == OP_CHUNK_INDEX:
                start_ns, end_ns, offset, length = (record.uint(8) for _ in range(4))
                offsets = Cursor(record.take(record.uint(4)))
                channels = []
                while offsets.pos < len(offsets.data):
                    channels.append(offsets.uint(2))
                    offsets.uint(8)
                try:
                    index_length = record.uint(8)
                except DamageError:
                    index_length = 0  # only an optimisation is lost
                indexes.append(
                    ChunkIndex(start_ns, offset, length, frozenset(channels), index_length, end_ns)
                )
            elif op == OP_STATISTICS:
                record.take(8 + 2 + 4 * 3)  # message, schema, channel, attachment, metadata counts
                chunk_count = record.uint(4)
                self.start_ns, self.end_ns = record.uint(8), record.uint(8)
                counts = Cursor(record.take(record.uint(4)))
                while counts.pos < len(counts.data):
                    cid = counts.uint(2)
                    self.counts[cid] = counts.uint(8)
                if not self.counts:
                    self.start_ns = self.end_ns = None
        return indexes, chunk_count

    def _add_schema(self, record: Cursor) -> None:
        sid = record.uint(2)
        name, encoding = record.string(), record.string()
        text = bytes(record.take(record.uint(4))).decode("utf-8", "replace")
        self._schemas[sid] = (name, Definition(encoding, text))

    def _add_channel(self, record: Cursor) -> None:
        cid, sid = record.uint(2), record.uint(2)
        topic, encoding = record.string(), record.string()
        if cid in self.connections:
            return
        name, definition = self._schemas.get(sid, ("", NO_DEFINITION))
        msgtype = normalize_typename(name) if name else ""
        self.connections[cid] = Connection(cid, topic, msgtype, encoding, definition)

    def close(self) -> None:
        """Nothing to release: the file is open only while it is read."""

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

    def _parse_records(self, body: bytes, op: int) -> None:
        if op == OP_SCHEMA:
            self._add_schema(Cursor(body))
        else:
            self._add_channel(Cursor(body))

    def _count(self, cid: int, t_ns: int) -> None:
        self.counts[cid] = self.counts.get(cid, 0) + 1
        self.start_ns = t_ns if self.start_ns is None else min(self.start_ns, t_ns)
        self.end_ns = t_ns if self.end_ns is None else max(self.end_ns, t_ns)
        if cid not in self.connections:
            self._unknown_channels += 1
