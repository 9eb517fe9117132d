"""ROS 1 bag inputs (``.bag``, format 2.0): a streaming chunk scanner and rosbags' ROS 1 decoder.

Reads the chunks in file order (the index, when intact, only skips chunks and bounds time), so
unindexed, truncated and damaged bags give what they hold; never writes, allocates within bounds.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, NamedTuple

from medkit_replay.errors import InputError
from medkit_replay.files import open_regular
from medkit_replay.inputs import rosbag1_records as rec
from medkit_replay.inputs.decompress import ChunkDamageError, decompress_chunk
from medkit_replay.inputs.merge import Bound, Timed, reorder_batches
from medkit_replay.inputs.ros1_diagnostics import DECODERS
from medkit_replay.inputs.ros1_messages import TRANSLATIONS, ros1_typestore, standard_md5
from medkit_replay.inputs.rosbag1_records import RecordDamageError
from medkit_replay.inputs.source import Message
from medkit_replay.inputs.storage import RECORD_SIZE_LIMIT
from medkit_replay.model import InputSummary, TopicSummary
from medkit_replay.msgdefs import normalize_typename

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator
    from pathlib import Path
    from typing import IO

    from medkit_replay.inputs.selection import Role
    from medkit_replay.inputs.source import InputContext

STORAGE = "rosbag1"
MAX_HELD = 100_000
"""Most messages held to restore time order; beyond it the oldest leaves, later ones may be late."""
INDEX_SIZE_LIMIT = 256 * 1024 * 1024
"""Largest index section (connections and chunk infos) read into memory; larger is damage."""
_CODECS = {"none": "", "bz2": "bz2", "lz4": "lz4"}
ROS1_ROLES: frozenset[Role] = frozenset({"diagnostics", "action_status", "rosout", "extra"})
"""The roles a ROS 1 bag's topics can have (ROS 1 has no ros2_medkit service events)."""


class _Reader(NamedTuple):
    """How one connection's messages are replayed."""

    role: Role
    topic: str
    msgtype: str
    decode: Callable[[bytes], object]


class _Raw(NamedTuple):
    connection: int
    data: bytes


class _NotABagError(Exception):
    """Nothing at all can be read from the file."""


def open_bag1(path: Path, ctx: InputContext) -> Rosbag1Input:
    """Open a ROS 1 bag.

    Raises:
        InputError: the file is not a ROS 1 bag (format 2.0) or its bag header is unreadable.
        OSError: the file cannot be opened.
    """
    return Rosbag1Input(path, ctx)


class Rosbag1Input:
    """One ROS 1 bag read as a stream sorted by (log time, position); see ``Input``."""

    def __init__(self, path: Path, ctx: InputContext) -> None:
        self.path = path
        self.ctx = ctx
        self._file: IO[bytes] | None = open_regular(path)
        self._size = os.fstat(self._file.fileno()).st_size
        self._connections: dict[int, rec.Ros1Connection] = {}
        self._readers: dict[int, _Reader | None] = {}
        self._chunks: dict[int, rec.ChunkInfo] = {}  # by position; empty without a usable index
        self._counts: dict[int, int] = {}
        self._start: int | None = None
        self._end: int | None = None
        self._warned: set[str] = set()
        self._failures: dict[str, tuple[int, int, str]] = {}
        self._orphans = 0  # messages of connections no record declares
        self._late: tuple[int, int] = (0, 0)
        self._used = False
        try:
            self._probe()
        except _NotABagError as exc:
            self.close()
            raise InputError(str(exc), path=str(path)) from None
        except BaseException:
            self.close()
            raise

    # -- probing -------------------------------------------------------------------------------

    def _read_at(self, pos: int, size: int) -> bytes:
        assert self._file is not None
        self._file.seek(pos)
        return self._file.read(size)

    def _probe(self) -> None:
        if self._size == 0:
            raise _NotABagError("empty file, not a ROS 1 bag")
        magic = self._read_at(0, len(rec.MAGIC))
        if magic != rec.MAGIC:
            if magic.startswith(b"#ROSBAG V"):
                shown = magic.decode("ascii", "replace").strip()
                raise _NotABagError(f"ROS 1 bag of format {shown[9:]!r}; only 2.0 is read")
            raise _NotABagError("not a ROS 1 bag (bad magic)")
        try:
            fields, data_start, data_end = self._record_at(len(rec.MAGIC))
            header = rec.bag_header(fields)
        except (RecordDamageError, EOFError) as exc:
            raise _NotABagError(f"ROS 1 bag header record is damaged ({exc})") from None
        encryptor = rec.string(fields, "encryptor", "")
        if encryptor:
            raise _NotABagError(f"ROS 1 bag encrypted with {encryptor!r}; cannot be read")
        self._data_start = data_end
        self._data_end = self._size
        del data_start
        if header.index_pos == 0:
            self._warn(
                "not indexed (the recorder stopped before writing its index?); "
                "its chunks are scanned"
            )
        elif not data_end <= header.index_pos < self._size:
            self._warn(
                f"index at byte {header.index_pos} is beyond the end of the file "
                f"({self._size} bytes: truncated?); its chunks are scanned"
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
            self._warn(f"index of {length} bytes is implausible; its chunks are scanned")
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
            self._warn(f"index is damaged ({exc}); its chunks are scanned")
            return
        if (connections, len(chunks)) != (header.conn_count, header.chunk_count):
            self._warn(
                f"index holds {connections} connections and {len(chunks)} chunks, the bag "
                f"header declares {header.conn_count} and {header.chunk_count}; "
                "its chunks are scanned"
            )
            return
        if any(not self._data_start <= c.chunk_pos < self._data_end for c in chunks):
            self._warn("index points outside the bag's data; its chunks are scanned")
            return
        self._chunks = {c.chunk_pos: c for c in chunks}
        for chunk in chunks:
            for cid, count in chunk.counts.items():
                self._counts[cid] = self._counts.get(cid, 0) + count
            if chunk.counts:
                self._span(chunk.start_ns)
                self._span(chunk.end_ns)

    def _span(self, t_ns: int) -> None:
        self._start = t_ns if self._start is None else min(self._start, t_ns)
        self._end = t_ns if self._end is None else max(self._end, t_ns)

    def _warn(self, text: str) -> None:
        text = f"{self.path}: {text}"
        if text not in self._warned:
            self._warned.add(text)
            self.ctx.warn(text)

    # -- connections ---------------------------------------------------------------------------

    def _add_connection(self, connection: rec.Ros1Connection) -> None:
        if connection.id not in self._connections:
            self._connections[connection.id] = connection

    def _reader(self, cid: int) -> _Reader | None:
        """How a connection is replayed, decided when its first message is met (None: not read)."""
        if cid in self._readers:
            return self._readers[cid]
        connection = self._connections[cid]
        reader = self._readers[cid] = self._make_reader(connection)
        return reader

    def _make_reader(self, connection: rec.Ros1Connection) -> _Reader | None:
        ros1_type = normalize_typename(connection.msgtype)
        translation = TRANSLATIONS.get(ros1_type)
        topic, msgtype = connection.topic, ros1_type
        if translation is not None:
            topic, msgtype = translation.topic(connection.topic), translation.ros2_type
        selection = self.ctx.selection
        role, reason = selection.classify(topic, msgtype)
        if role is None and connection.topic in selection.extra_topics:
            role, reason, topic = "extra", None, connection.topic
        if role is None:
            if reason:
                self._warn(reason)
            return None
        store = ros1_typestore()
        if ros1_type not in store.fielddefs:
            self._warn(f"topic {connection.topic} has type {ros1_type}, unknown to ROS 1 Noetic")
            return None
        if translation is not None and connection.md5sum not in ("*", standard_md5(ros1_type)):
            self._warn(
                f"topic {connection.topic}: type {connection.msgtype} recorded with md5sum "
                f"{connection.md5sum!r}, not the standard one; decoded with the standard definition"
            )
        fast = DECODERS.get(ros1_type)
        if fast is not None:
            return _Reader(role, topic, msgtype, fast)
        deserialize = store.deserialize_ros1
        if translation is None:
            return _Reader(role, topic, msgtype, lambda raw: deserialize(raw, ros1_type))
        convert = translation.convert
        return _Reader(role, topic, msgtype, lambda raw: convert(deserialize(raw, ros1_type)))

    # -- reading -------------------------------------------------------------------------------

    def _scan(self) -> Iterator[Bound | list[Timed[_Raw]]]:
        """Every chunk in file order: bounds and the wanted messages of each, sorted."""
        only = self.ctx.selection.only_roles
        if only is not None and not only & ROS1_ROLES:
            return  # e.g. the pre-pass over recorded service calls, which ROS 1 has none of
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
                self._warn(
                    f"file ends inside a record at byte {pos} of {self._size} (truncated: "
                    f"recorder stopped mid-write?); the last {self._size - pos} bytes are lost"
                )
                yield from self._cut_chunk(pos)
                return
            except RecordDamageError as exc:
                later = [p for p in positions if p > pos]
                if later:
                    self._warn(f"damaged record at byte {pos} ({exc}); resumed at byte {later[0]}")
                    pos = later[0]
                    continue
                self._warn(
                    f"damaged record at byte {pos} ({exc}); the last {self._data_end - pos} "
                    "bytes are not read"
                )
                return
            if op == rec.OP_CHUNK:
                if pos in floors:
                    yield Bound(floors[pos])
                if self._needed(pos):
                    batch = self._chunk(pos, compression, size, start, end)
                    if batch:
                        if pos not in floors:
                            yield Bound(batch[0].t_ns)
                        yield batch
            pos = end

    def _needed(self, pos: int) -> bool:
        """Whether a chunk may hold a wanted message (all do, without an index)."""
        info = self._chunks.get(pos)
        if info is None:
            return True
        return any(
            cid not in self._connections or self._reader(cid) is not None for cid in info.counts
        )

    def _cut_chunk(self, pos: int) -> Iterator[Bound | list[Timed[_Raw]]]:
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
    ) -> list[Timed[_Raw]]:
        """One chunk's wanted messages, sorted by (log time, position)."""
        where = f"chunk at byte {pos}"
        codec = _CODECS.get(compression)
        if codec is None:
            self._warn(f"{where}: compression {compression!r} is not supported; it is lost")
            return []
        if size > RECORD_SIZE_LIMIT:
            self._warn(f"{where} claims {size} bytes uncompressed; skipped as damaged")
            return []
        try:
            compressed = self._read_at(start, end - start)
            records = memoryview(decompress_chunk(compressed, codec, size, 0))
        except ChunkDamageError as exc:
            self._warn(f"{where} cannot be decompressed: {exc}; its messages are lost")
            return []
        return self._messages_of(where, pos, records)

    def _messages_of(self, where: str, pos: int, records: memoryview) -> list[Timed[_Raw]]:
        """The wanted messages of a chunk's records, sorted; connection records are learnt."""
        counted = pos in self._chunks
        batch: list[Timed[_Raw]] = []
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
                        self._counts[cid] = self._counts.get(cid, 0) + 1
                        self._span(t_ns)
                    if cid not in self._connections:
                        self._orphans += 1
                        continue
                    if self._reader(cid) is not None:
                        payload = bytes(records[record.data_start : record.data_end])
                        batch.append(Timed(t_ns, (pos, record.data_start), _Raw(cid, payload)))
        except RecordDamageError as exc:
            self._warn(f"{where}: {exc}; kept the {kept} messages before it")
        batch.sort(key=lambda timed: (timed.t_ns, timed.position))
        return batch

    def messages(self) -> Iterator[Timed[Message]]:
        """Yield the selected, decoded messages once, sorted by (log time, position).

        Raises:
            RuntimeError: called a second time.
        """
        self._claim()
        return self._stream(timed=True)  # type: ignore[return-value]  # Timed items

    def message_tuples(self) -> Iterator[tuple[int, int, str, str, Role, object]]:
        """:meth:`messages` as plain tuples laid out as Message, without their positions (a
        recording of one input needs none; cheaper to build)."""
        self._claim()
        return self._stream(timed=False)  # type: ignore[return-value]  # tuples

    def _claim(self) -> None:
        if self._used:
            raise RuntimeError(f"{self.path}: messages() can be read only once")
        self._used = True

    def _stream(
        self, *, timed: bool
    ) -> Iterator[Timed[Message] | tuple[int, int, str, str, Role, object]]:
        input_index, readers = self.ctx.input_index, self._readers
        try:
            for batch in reorder_batches(self._guarded_scan(), self._on_late, MAX_HELD):
                for t_ns, position, raw in batch:
                    reader = readers[raw.connection]
                    assert reader is not None
                    try:
                        msg = reader.decode(raw.data)
                    except ImportError:
                        raise  # the environment, not the bag
                    except Exception as exc:  # rosbags raises struct.error, IndexError, ...
                        self._failed(reader.topic, t_ns, exc)
                        continue
                    topic, msgtype, role = reader.topic, reader.msgtype, reader.role
                    if timed:
                        message = Message(t_ns, input_index, topic, msgtype, role, msg)
                        yield Timed(t_ns, position, message)
                    else:
                        yield (t_ns, input_index, topic, msgtype, role, msg)
        finally:
            self._report_losses()

    def _guarded_scan(self) -> Iterator[Bound | list[Timed[_Raw]]]:
        try:
            yield from self._scan()
        except Exception as exc:  # last resort: no reader failure may end the replay
            self._warn(f"reading stopped ({type(exc).__name__}: {exc})")

    def _on_late(self, item: Timed[_Raw]) -> None:
        count, first = self._late
        self._late = (count + 1, first if count else item.t_ns)

    def _failed(self, topic: str, t_ns: int, exc: Exception) -> None:
        reason = " ".join(str(exc).split()) or type(exc).__name__
        count, first, why = self._failures.get(topic, (0, t_ns, reason))
        self._failures[topic] = (count + 1, first, why)

    def _report_losses(self) -> None:
        for topic, (count, first, reason) in sorted(self._failures.items()):
            self._warn(
                f"{count} messages on {topic} cannot be decoded and were skipped "
                f"(first at t={first}: {reason})"
            )
        if self._orphans:
            self._warn(
                f"{self._orphans} messages belong to connections whose records are lost "
                "(kept only in the missing index?); they cannot be decoded"
            )
        if self._late[0]:
            self._warn(
                f"{self._late[0]} messages are stored too far out of time order to be "
                f"replayed in order and were skipped (first at t={self._late[1]})"
            )

    # -- summary -------------------------------------------------------------------------------

    def summary(self) -> InputSummary:
        """Topics (as recorded, with the role of those read), counts and time span."""
        counts: dict[tuple[str, str], int] = {}
        roles: dict[tuple[str, str], Role] = {}
        for cid, connection in self._connections.items():
            key = (connection.topic, normalize_typename(connection.msgtype))
            counts[key] = counts.get(key, 0) + self._counts.get(cid, 0)
            reader = self._readers.get(cid)
            if reader is not None:
                roles[key] = reader.role
        return InputSummary(
            path=str(self.path),
            storage=STORAGE,
            start_ns=self._start,
            end_ns=self._end,
            message_count=sum(self._counts.values()),
            topics=tuple(
                TopicSummary(topic=topic, type=msgtype, role=roles.get(key), messages=count)
                for key, count in sorted(counts.items())
                for topic, msgtype in (key,)
            ),
        )

    def close(self) -> None:
        """Close the file; safe to call twice."""
        if self._file is not None:
            self._file.close()
            self._file = None
