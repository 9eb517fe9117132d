"""A ROS 1 bag file (format 2.0) read record by record: its bag header, index and chunks.

Reads chunks in file order (an intact index skips chunks, bounds time and points into plain
chunks), so unindexed, truncated and damaged bags give what they hold; never writes; bounded.
"""

from __future__ import annotations

import os
import struct
from typing import TYPE_CHECKING, NamedTuple

from medkit_replay.files import open_regular
from medkit_replay.inputs.decompress import ChunkDamageError, decompress_chunk
from medkit_replay.inputs.merge import Bound, Timed
from medkit_replay.inputs.ros1 import records as rec
from medkit_replay.inputs.ros1.records import RecordDamageError
from medkit_replay.inputs.storage import RECORD_SIZE_LIMIT, NotABagError
from medkit_replay.model import Loss

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator
    from pathlib import Path
    from typing import IO

    from medkit_replay.inputs.source import Warn

_SCANNED = Loss(messages=0)
"""What an unusable index costs: nothing, its chunks are scanned instead."""
INDEX_SIZE_LIMIT = 256 * 1024 * 1024
"""Largest index section (connections and chunk infos) read into memory; larger is damage."""
_CODECS = {"none": "", "bz2": "bz2", "lz4": "lz4"}
_INDEX_ENTRY = struct.Struct("<III").unpack_from  # time (sec, nsec), offset in the chunk


class Raw1(NamedTuple):
    """One stored message, not decoded: its connection id and payload."""

    connection: int
    data: bytes


class Bag1File:
    """One ROS 1 bag, probed when constructed (magic, bag header, index), scanned on demand.

    After construction ``connections``, ``counts``, ``start_ns`` and ``end_ns`` hold what the
    index declares (nothing without one); scanning completes them. ``orphans`` counts messages
    whose connection record is lost.
    """

    def __init__(
        self,
        path: Path,
        warn: Warn,
        wants: Callable[[int], bool],
        *,
        indexed: bool = True,
    ) -> None:
        """Open and probe the bag.

        Args:
            path: the ``.bag`` file.
            warn: told each loss or oddity (without the path).
            wants: whether a connection's messages are read; asked when first needed.
            indexed: read the wanted records of an uncompressed chunk through the index data
                records after it (False: every chunk is read whole, the route the index must
                agree with).

        Raises:
            NotABagError: the file is not a ROS 1 bag of format 2.0, or its bag header is
                unreadable.
            OSError: the file cannot be opened.
        """
        self.path = path
        self.warn = warn
        self._wants = wants
        self._indexed = indexed
        self._file: IO[bytes] | None = open_regular(path)
        self._size = os.fstat(self._file.fileno()).st_size
        self.connections: dict[int, rec.Ros1Connection] = {}
        self.counts: dict[int, int] = {}
        self.start_ns: int | None = None
        self.end_ns: int | None = None
        self.orphans = 0
        self._chunks: dict[int, rec.ChunkInfo] = {}  # by position; empty without a usable index
        try:
            self._probe()
        except BaseException:
            self.close()
            raise

    def _read_at(self, pos: int, size: int) -> bytes:
        assert self._file is not None
        self._file.seek(pos)
        return self._file.read(size)

    def _probe(self) -> None:
        if self._size == 0:
            raise NotABagError("empty file, not a ROS 1 bag")
        magic = self._read_at(0, len(rec.MAGIC))
        if magic != rec.MAGIC:
            if magic.startswith(b"#ROSBAG V"):
                shown = magic.decode("ascii", "replace").strip()
                raise NotABagError(f"ROS 1 bag of format {shown[9:]!r}; only 2.0 is read")
            raise NotABagError("not a ROS 1 bag (bad magic)")
        try:
            fields, data_start, data_end = self._record_at(len(rec.MAGIC))
            header = rec.bag_header(fields)
        except (RecordDamageError, EOFError) as exc:
            raise NotABagError(f"ROS 1 bag header record is damaged ({exc})") from None
        encryptor = rec.string(fields, "encryptor", "")
        if encryptor:
            raise NotABagError(f"ROS 1 bag encrypted with {encryptor!r}; cannot be read")
        self._data_start = data_end
        self._data_end = self._size
        del data_start
        if header.index_pos == 0:
            self.warn(
                "not indexed (the recorder stopped before writing its index?); "
                "its chunks are scanned",
                Loss(),  # a recording cut short: how much is unknown
            )
        elif not data_end <= header.index_pos < self._size:
            self.warn(
                f"index at byte {header.index_pos} is beyond the end of the file "
                f"({self._size} bytes: truncated?); its chunks are scanned",
                Loss(),
            )
        else:
            self._data_end = header.index_pos
            self._read_index(header)

    def _record_at(self, pos: int) -> tuple[dict[str, bytes], int, int]:
        """A top-level record's fields and where its data lies.

        Raises:
            EOFError: the file ends inside the record.
            RecordDamageError: a length field beyond every bound, or a damaged header.
        """
        head = self._read_at(pos, 4)
        if len(head) < 4:
            raise EOFError("the file ends inside it")
        header_len = int.from_bytes(head, "little")
        if header_len > rec.HEADER_SIZE_LIMIT:
            raise RecordDamageError(f"record header of {header_len} bytes")
        if pos + 8 + header_len > self._size:
            raise EOFError("the file ends inside it")
        block = self._read_at(pos + 4, header_len + 4)
        fields = rec.parse_fields(block[:header_len])
        data_len = int.from_bytes(block[header_len:], "little")
        start = pos + 8 + header_len
        if data_len > RECORD_SIZE_LIMIT:
            raise RecordDamageError(f"record data of {data_len} bytes")
        if start + data_len > self._size:
            raise EOFError("the file ends inside it")
        return fields, start, start + data_len

    def _read_index(self, header: rec.BagHeader) -> None:
        """Connections and chunk infos from the index; a damaged index is set aside with a note."""
        length = self._size - header.index_pos
        if length > INDEX_SIZE_LIMIT:
            self.warn(f"index of {length} bytes is implausible; its chunks are scanned", _SCANNED)
            return
        chunks: list[rec.ChunkInfo] = []
        connections = 0
        try:
            for op, fields, data in rec.index_records(self._read_at(header.index_pos, length)):
                if op == rec.OP_CONNECTION:
                    self._add_connection(rec.connection(fields, data))
                    connections += 1
                elif op == rec.OP_CHUNK_INFO:
                    chunks.append(rec.chunk_info(fields, data))
        except RecordDamageError as exc:
            self.warn(f"index is damaged ({exc}); its chunks are scanned", _SCANNED)
            return
        if (connections, len(chunks)) != (header.conn_count, header.chunk_count):
            self.warn(
                f"index holds {connections} connections and {len(chunks)} chunks, the bag "
                f"header declares {header.conn_count} and {header.chunk_count}; "
                "its chunks are scanned",
                _SCANNED,
            )
            return
        if any(not self._data_start <= c.chunk_pos < self._data_end for c in chunks):
            self.warn("index points outside the bag's data; its chunks are scanned", _SCANNED)
            return
        self._chunks = {c.chunk_pos: c for c in chunks}
        for chunk in chunks:
            for cid, count in chunk.counts.items():
                self.counts[cid] = self.counts.get(cid, 0) + count
            if chunk.counts:
                self._span(chunk.start_ns)
                self._span(chunk.end_ns)

    def _span(self, t_ns: int) -> None:
        self.start_ns = t_ns if self.start_ns is None else min(self.start_ns, t_ns)
        self.end_ns = t_ns if self.end_ns is None else max(self.end_ns, t_ns)

    def _add_connection(self, connection: rec.Ros1Connection) -> None:
        if connection.id not in self.connections:
            self.connections[connection.id] = connection

    def scan(self) -> Iterator[Bound | list[Timed[Raw1]]]:
        """Every chunk in file order: bounds and the wanted messages of each, sorted by
        (log time, position); a position is (chunk's byte offset, record's offset in it)."""
        positions = sorted(self._chunks)
        floors: dict[int, int] = {}  # earliest start of this chunk and every later one
        floor: int | None = None
        for pos in reversed(positions):
            info = self._chunks[pos]
            if info.counts:
                floor = info.start_ns if floor is None else min(floor, info.start_ns)
            if floor is not None:
                floors[pos] = floor
        pos = self._data_start
        while pos < self._data_end:
            try:
                fields, start, end = self._record_at(pos)
                op = rec.op_of(fields)
                if op == rec.OP_CHUNK:
                    compression = rec.string(fields, "compression")
                    size = rec.uint32(fields, "size")
                elif op == rec.OP_CONNECTION:
                    self._add_connection(rec.connection(fields, self._read_at(start, end - start)))
            except EOFError:
                self.warn(
                    f"file ends inside a record at byte {pos} of {self._size} (truncated: "
                    f"recorder stopped mid-write?); the last {self._size - pos} bytes are lost",
                    self._lost(pos, self._size - pos, chunks=False),
                )
                yield from self._cut_chunk(pos)
                return
            except RecordDamageError as exc:
                later = [p for p in positions if p > pos]
                if later:
                    self.warn(
                        f"damaged record at byte {pos} ({exc}); resumed at byte {later[0]}",
                        self._lost(pos, later[0] - pos),
                    )
                    pos = later[0]
                    continue
                self.warn(
                    f"damaged record at byte {pos} ({exc}); the last {self._data_end - pos} "
                    "bytes are not read",
                    self._lost(pos, self._data_end - pos),
                )
                return
            if op == rec.OP_CHUNK:
                if pos in floors:
                    yield Bound(floors[pos])
                if self._needed(pos):
                    batch = None
                    if self._indexed and compression == "none" and pos in self._chunks:
                        batch = self._by_index(pos, size, start, end)
                    if batch is None:
                        batch = self._chunk(pos, compression, size, start, end)
                    if batch:
                        if pos not in floors:
                            yield Bound(batch[0].t_ns)
                        yield batch
            pos = end

    def _by_index(self, pos: int, size: int, start: int, end: int) -> list[Timed[Raw1]] | None:
        """An uncompressed chunk's wanted messages read through its index data records, or None
        when anything disagrees (the chunk is then read whole, and any damage said there).

        A record runs to the next indexed offset; runs of wanted records are read in one piece,
        the records between them (camera frames) never.
        """
        offsets = self._index_data(pos, end, size) if size == end - start else None
        if offsets is None:
            return None
        starts = sorted(offsets)
        following = dict(zip(starts, [*starts[1:], size], strict=True))
        wanted = [o for o in starts if self._wants(offsets[o][0])]
        batch: list[Timed[Raw1]] = []
        k = 0
        while k < len(wanted):
            first = last = wanted[k]
            k += 1
            while k < len(wanted) and wanted[k] == following[last]:
                last = wanted[k]
                k += 1
            stop = following[last]
            block = memoryview(self._read_at(start + first, stop - first))
            at = 0
            try:
                for record in rec.chunk_records(block):
                    offset, at = first + at, record.data_end
                    if record.op != rec.OP_MSG_DATA:
                        continue
                    cid = rec.uint32(record.fields, "conn")
                    t_ns = rec.time_ns(record.fields, "time")
                    if offsets.get(offset) != (cid, t_ns) or not self._wants(cid):
                        return None
                    payload = bytes(block[record.data_start : record.data_end])
                    batch.append(Timed(t_ns, (pos, first + record.data_start), Raw1(cid, payload)))
            except RecordDamageError:
                return None
        if len(batch) != len(wanted):
            return None
        batch.sort(key=lambda timed: (timed.t_ns, timed.position))
        return batch

    def _index_data(self, pos: int, end: int, size: int) -> dict[int, tuple[int, int]] | None:
        """The index data records after a chunk: each message's offset in the chunk, with its
        connection and log time; None unless they agree with the chunk info and each other."""
        expected = self._chunks[pos].counts
        found: dict[int, tuple[int, int]] = {}
        seen: dict[int, int] = {}
        at = end
        try:
            while len(seen) < len(expected):
                fields, data_start, data_end = self._record_at(at)
                if rec.op_of(fields) != rec.OP_INDEX_DATA or rec.uint32(fields, "ver") != 1:
                    return None
                cid, count = rec.uint32(fields, "conn"), rec.uint32(fields, "count")
                known = cid in self.connections and cid not in seen
                if not known or data_end - data_start != 12 * count:
                    return None
                seen[cid] = count
                data = self._read_at(data_start, data_end - data_start)
                for k in range(count):
                    sec, nsec, offset = _INDEX_ENTRY(data, 12 * k)
                    if offset >= size or offset in found:
                        return None
                    found[offset] = (cid, sec * 1_000_000_000 + nsec)
                at = data_end
        except (RecordDamageError, EOFError):
            return None
        return found if seen == expected else None

    def _needed(self, pos: int) -> bool:
        """Whether a chunk may hold a wanted message (all do, without an index)."""
        info = self._chunks.get(pos)
        if info is None:
            return True
        return any(cid not in self.connections or self._wants(cid) for cid in info.counts)

    def _cut_chunk(self, pos: int) -> Iterator[Bound | list[Timed[Raw1]]]:
        """The intact messages of an uncompressed chunk the end of the file cuts off."""
        head = self._read_at(pos, 4)
        header_len = int.from_bytes(head, "little") if len(head) == 4 else 0
        if not 0 < header_len <= min(rec.HEADER_SIZE_LIMIT, self._size - pos - 8):
            return
        try:
            fields = rec.parse_fields(self._read_at(pos + 4, header_len))
            if rec.op_of(fields) != rec.OP_CHUNK or rec.string(fields, "compression") != "none":
                return
        except RecordDamageError:
            return
        start = pos + 8 + header_len
        records = memoryview(self._read_at(start, self._size - start))
        batch = self._messages_of(f"chunk at byte {pos} (cut off)", pos, records)
        if batch:
            yield Bound(batch[0].t_ns)
            yield batch

    def _chunk(
        self, pos: int, compression: str, size: int, start: int, end: int
    ) -> list[Timed[Raw1]]:
        """One chunk's wanted messages, sorted by (log time, position)."""
        where = f"chunk at byte {pos}"
        codec = _CODECS.get(compression)
        lost = self._lost(pos, end - pos)
        if codec is None:
            self.warn(f"{where}: compression {compression!r} is not supported; it is lost", lost)
            return []
        if size > RECORD_SIZE_LIMIT:
            self.warn(f"{where} claims {size} bytes uncompressed: damaged", lost)
            return []
        try:
            compressed = self._read_at(start, end - start)
            records = memoryview(decompress_chunk(compressed, codec, size, 0))
        except ChunkDamageError as exc:
            self.warn(f"{where} cannot be decompressed: {exc}", lost)
            return []
        return self._messages_of(where, pos, records)

    def _messages_of(self, where: str, pos: int, records: memoryview) -> list[Timed[Raw1]]:
        """The wanted messages of a chunk's records, sorted; connection records are learnt."""
        counted = pos in self._chunks
        batch: list[Timed[Raw1]] = []
        kept = 0
        try:
            for record in rec.chunk_records(records):
                if record.op == rec.OP_CONNECTION:
                    data = records[record.data_start : record.data_end]
                    self._add_connection(rec.connection(record.fields, data))
                elif record.op == rec.OP_MSG_DATA:
                    cid = rec.uint32(record.fields, "conn")
                    t_ns = rec.time_ns(record.fields, "time")
                    kept += 1
                    if not counted:
                        self.counts[cid] = self.counts.get(cid, 0) + 1
                        self._span(t_ns)
                    if cid not in self.connections:
                        self.orphans += 1
                        continue
                    if self._wants(cid):
                        payload = bytes(records[record.data_start : record.data_end])
                        batch.append(Timed(t_ns, (pos, record.data_start), Raw1(cid, payload)))
        except RecordDamageError as exc:
            lost = self._lost(pos, None, kept)
            self.warn(f"{where}: {exc}; the {kept} messages before it are kept", lost)
        batch.sort(key=lambda timed: (timed.t_ns, timed.position))
        return batch

    def _lost(self, pos: int, size: int | None, kept: int = 0, *, chunks: bool = True) -> Loss:
        """What losing ``size`` bytes from ``pos`` costs (but ``kept`` messages): the messages
        and span the index gives the chunks starting in them (unknown without an index)."""
        end = pos + (size or 1)
        lost = [c for p, c in self._chunks.items() if pos <= p < end] if chunks else []
        if not lost:
            return Loss(bytes=size)
        count = sum(sum(c.counts.values()) for c in lost)
        spans = [c for c in lost if c.counts]
        return Loss(
            messages=max(0, count - kept),
            bytes=size,
            start_ns=min((c.start_ns for c in spans), default=None),
            end_ns=max((c.end_ns for c in spans), default=None),
        )

    def close(self) -> None:
        """Close the file; safe to call twice."""
        if self._file is not None:
            self._file.close()
            self._file = None
