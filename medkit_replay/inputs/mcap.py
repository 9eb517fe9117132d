"""MCAP storage files: a streaming reader that uses the chunk index when intact, else scans.

Read-only and bounded: a length field is obeyed only within the file and RECORD_SIZE_LIMIT.
"""

from __future__ import annotations

import os
from binascii import crc32
from typing import TYPE_CHECKING, BinaryIO, NamedTuple

from rosbags.rosbag2.storage_mcap import decompress

from medkit_replay.inputs.merge import Bound, Timed
from medkit_replay.inputs.selection import normalize_typename
from medkit_replay.inputs.storage import RECORD_SIZE_LIMIT, Connection, NotABagError, Raw
from medkit_replay.inputs.typestore import NO_DEFINITION, Definition

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator
    from pathlib import Path

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


class _ChunkIndex(NamedTuple):
    start_ns: int
    offset: int
    length: int
    channels: frozenset[int]


class McapFile:
    """One MCAP file; see :class:`medkit_replay.inputs.storage.StorageFile`."""

    storage = "mcap"

    def __init__(self, path: Path, file_no: int, warn: Callable[[str], None]) -> None:
        self.path = path
        self.file_no = file_no
        self.warn = warn
        self.connections: dict[int, Connection] = {}
        self.counts: dict[int, int] = {}
        self.start_ns: int | None = None
        self.end_ns: int | None = None
        self._schemas: dict[int, tuple[str, Definition]] = {}
        self._chunks: list[_ChunkIndex] | None = None
        self._wanted: dict[int, bool] = {}
        self._unknown_channels = 0
        try:
            with path.open("rb") as bio:
                self._size = os.fstat(bio.fileno()).st_size
                self._probe(bio)
        except OSError as exc:
            raise NotABagError(f"cannot read: {exc.strerror or exc}") from None

    # -- probing -------------------------------------------------------------------------------

    def _probe(self, bio: BinaryIO) -> None:
        if self._size == 0:
            raise NotABagError("empty file, not an MCAP file")
        head = bio.read(len(MAGIC) + 9)
        if head[: len(MAGIC)] != MAGIC:
            raise NotABagError("not an MCAP file (bad magic)")
        if len(head) < len(MAGIC) + 9 or head[len(MAGIC)] != OP_HEADER:
            raise NotABagError("MCAP file cut off before its header record")
        length = int.from_bytes(head[len(MAGIC) + 1 :], "little")
        self._data_start = len(head) + length
        if self._data_start > self._size:
            raise NotABagError("MCAP file cut off inside its header record")
        try:
            profile = _Cursor(bio.read(length)).string()
        except _DamageError:
            raise NotABagError("MCAP header record is damaged") from None
        if profile != "ros2":
            self.warn(f"{self.path}: MCAP profile {profile!r}, not 'ros2'; reading it anyway")
        self._data_end = self._size
        problem = self._read_footer_and_summary(bio)
        if self._chunks is None:
            self.counts.clear()
            self.start_ns = self.end_ns = None
            if problem:
                self.warn(f"{self.path}: {problem}; scanning the file from the start")

    def _read_footer_and_summary(self, bio: BinaryIO) -> str | None:
        footer_pos = self._size - FOOTER_SIZE
        if footer_pos < self._data_start:
            return "no footer (the recorder did not close the file)"
        bio.seek(footer_pos)
        footer = bio.read(FOOTER_SIZE)
        if footer[-len(MAGIC) :] != MAGIC or footer[0] != OP_FOOTER:
            return "no footer (the recorder did not close the file)"
        cur = _Cursor(footer[9:29])
        summary_start, _, summary_crc = cur.uint(8), cur.uint(8), cur.uint(4)
        self._data_end = footer_pos
        if summary_start == 0:
            return None
        if not self._data_start <= summary_start <= footer_pos:
            return f"footer points to a summary at byte {summary_start}, outside the file"
        if footer_pos - summary_start > RECORD_SIZE_LIMIT:
            return f"summary section of {footer_pos - summary_start} bytes is implausible"
        bio.seek(summary_start)
        summary = bio.read(footer_pos - summary_start)
        if summary_crc and crc32(summary + footer[:25]) != summary_crc:
            return "summary section fails its checksum"
        try:
            indexes, chunk_count = self._parse_summary(summary)
        except _DamageError as exc:
            return f"summary section is damaged ({exc})"
        self._data_end = summary_start
        if chunk_count is not None and chunk_count != len(indexes):
            return f"summary indexes {len(indexes)} of {chunk_count} chunks"
        if indexes and chunk_count and self.connections:
            self._chunks = sorted(indexes)
        return None

    def _parse_summary(self, summary: bytes) -> tuple[list[_ChunkIndex], int | None]:
        """Schemas, channels and statistics into self; returns chunk indexes and chunk count."""
        indexes: list[_ChunkIndex] = []
        chunk_count = None
        cur = _Cursor(summary)
        while cur.pos < len(summary):
            op = cur.uint(1)
            record = _Cursor(cur.take(cur.uint(8)))
            if op == OP_SCHEMA:
                self._add_schema(record)
            elif op == OP_CHANNEL:
                self._add_channel(record)
            elif op == OP_CHUNK_INDEX:
                start_ns, _, offset, length = (record.uint(8) for _ in range(4))
                offsets = _Cursor(record.take(record.uint(4)))
                channels = []
                while offsets.pos < len(offsets.data):
                    channels.append(offsets.uint(2))
                    offsets.uint(8)
                indexes.append(_ChunkIndex(start_ns, offset, length, frozenset(channels)))
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
    ) -> Iterator[Bound | Timed[Raw]]:
        """Yield bounds and wanted messages (see ``StorageFile.read``)."""
        self._accept = wants
        cap = cap_ns if cap_ns is not None else 2**63
        for cid in sorted(self.connections):
            self._wants(cid)  # every declared topic is classified, read or not
        with self.path.open("rb") as bio:
            if self._chunks is not None:
                yield from self._read_indexed(bio, cap)
            else:
                yield from self._read_linear(bio, cap)
        if self._unknown_channels:
            self.warn(
                f"{self.path}: {self._unknown_channels} messages refer to channels the file never "
                "declares; skipped"
            )

    def _wants(self, cid: int) -> bool:
        if cid not in self._wanted:
            connection = self.connections.get(cid)
            self._wanted[cid] = connection is not None and self._accept(connection)
        return self._wanted[cid]

    def _read_indexed(self, bio: BinaryIO, cap: int) -> Iterator[Bound | Timed[Raw]]:
        for chunk in self._chunks or ():
            if chunk.channels and not any(self._wants(cid) for cid in chunk.channels):
                continue  # no wanted topic in it: its bytes are never read
            bio.seek(chunk.offset)
            head = bio.read(9)
            length = int.from_bytes(head[1:], "little") if len(head) == 9 else -1
            if (
                head[:1] != bytes([OP_CHUNK])
                or 9 + length != chunk.length
                or length > min(RECORD_SIZE_LIMIT, self._size - chunk.offset - 9)
            ):
                self.warn(
                    f"{self.path}: the chunk index points to no valid chunk at byte "
                    f"{chunk.offset}; messages from t={chunk.start_ns} in it are lost"
                )
                continue
            yield Bound(min(chunk.start_ns, cap))
            yield from self._chunk(memoryview(bio.read(length)), chunk.offset, cap, count=False)

    def _read_linear(self, bio: BinaryIO, cap: int) -> Iterator[Bound | Timed[Raw]]:
        pos, end = self._data_start, self._data_end
        bio.seek(pos)
        while pos < end:
            head = bio.read(9)
            if len(head) < 9:
                self._truncated(pos, "a record header")
                return
            op, length = head[0], int.from_bytes(head[1:], "little")
            if op in (OP_DATA_END, OP_FOOTER):
                return
            body_end = pos + 9 + length
            if op == OP_MESSAGE and length < MESSAGE_HEADER:
                self.warn(f"{self.path}: invalid message record at byte {pos}; the rest is lost")
                return
            if op == 0 or length > RECORD_SIZE_LIMIT:
                self.warn(
                    f"{self.path}: invalid record (opcode {op:#04x}, {length} bytes) at byte "
                    f"{pos}; the last {self._size - pos} bytes are lost"
                )
                return
            if body_end > end:
                if op == OP_CHUNK and end - pos - 9 > 0:
                    yield from self._chunk(
                        memoryview(bio.read(end - pos - 9)), pos, cap, count=True, partial=True
                    )
                self._truncated(pos, f"a record (opcode {op:#04x}) of {length} bytes")
                return
            if op == OP_MESSAGE:
                fixed = bio.read(MESSAGE_HEADER)
                cid, t_ns = (
                    int.from_bytes(fixed[:2], "little"),
                    int.from_bytes(fixed[6:14], "little"),
                )
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
                    self.warn(f"{self.path}: damaged schema or channel at byte {pos}: {exc}")
            pos = body_end
            bio.seek(pos)

    def _parse_records(self, body: bytes, op: int) -> None:
        if op == OP_SCHEMA:
            self._add_schema(_Cursor(body))
        else:
            self._add_channel(_Cursor(body))

    def _truncated(self, pos: int, what: str) -> None:
        self.warn(
            f"{self.path}: file ends inside {what} at byte {pos} of {self._size} (truncated: "
            f"recorder stopped mid-write?); the last {self._size - pos} bytes are lost"
        )

    def _count(self, cid: int, t_ns: int) -> None:
        self.counts[cid] = self.counts.get(cid, 0) + 1
        self.start_ns = t_ns if self.start_ns is None else min(self.start_ns, t_ns)
        self.end_ns = t_ns if self.end_ns is None else max(self.end_ns, t_ns)
        if cid not in self.connections:
            self._unknown_channels += 1

    def _chunk(
        self, body: memoryview, pos: int, cap: int, count: bool, partial: bool = False
    ) -> Iterator[Bound | Timed[Raw]]:
        """Decompress one chunk and yield its wanted messages sorted by (log time, offset)."""
        where = f"{self.path}: chunk at byte {pos}"
        try:
            cur = _Cursor(body)
            start_ns, end_ns, size, crc = cur.uint(8), cur.uint(8), cur.uint(8), cur.uint(4)
            compression, compressed = cur.string(), cur.uint(8)
            data = cur.rest() if partial else cur.take(compressed)
        except _DamageError as exc:
            self.warn(f"{where}: header damaged ({exc}); its messages are lost")
            return
        span = f"log times {start_ns}..{end_ns}"
        if partial and compression:
            self.warn(f"{where} ({span}) is cut off and {compression}-compressed; it is lost")
            return
        if size > RECORD_SIZE_LIMIT:
            self.warn(f"{where} ({span}) claims {size} bytes uncompressed; skipped as damaged")
            return
        try:
            records = (
                data if partial else memoryview(decompress(bytes(data), compression, size, crc))
            )
        except Exception as exc:  # rosbags' ReaderError, or the codec's own error
            self.warn(f"{where} ({span}) cannot be decompressed ({exc}); its messages are lost")
            return
        timed, problem = self._chunk_records(records, pos, count)
        if problem or partial:
            what = "cut off" if partial else problem
            self.warn(f"{where} ({span}): {what}; kept {len(timed)} messages")
        timed.sort(key=lambda item: (item.t_ns, item.position))
        if timed:
            yield Bound(min(timed[0].t_ns, cap))
            yield from timed

    def _chunk_records(
        self, records: memoryview, pos: int, count: bool
    ) -> tuple[list[Timed[Raw]], str | None]:
        timed: list[Timed[Raw]] = []
        cur = _Cursor(records)
        try:
            while cur.pos < len(records):
                inner = cur.pos
                op = cur.uint(1)
                record = _Cursor(cur.take(cur.uint(8)))
                if op == OP_MESSAGE:
                    cid, _, t_ns = record.uint(2), record.uint(4), record.uint(8)
                    record.uint(8)
                    if count:
                        self._count(cid, t_ns)
                    if self._wants(cid):
                        raw = Raw(self.connections[cid], record.rest())
                        timed.append(Timed(t_ns, (self.file_no, pos, inner), raw))
                elif op in (OP_SCHEMA, OP_CHANNEL):
                    self._parse_records(bytes(record.rest()), op)
        except _DamageError as exc:
            return timed, f"damaged record inside ({exc})"
        return timed, None
