"""Raw messages of a recording by topic and time range, for the captures' second pass.

MCAP files are read by the replay's reader (inputs.mcap) through their chunk and message indexes,
sqlite3 files by ranged queries on the timestamp index; nothing is decoded here and nothing of
the recording is held in memory.
"""

from __future__ import annotations

import heapq
import sqlite3
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

from medkit_replay.files import open_regular
from medkit_replay.inputs.mcap.reader import McapFile
from medkit_replay.inputs.mcap.records import NO_FOOTER
from medkit_replay.inputs.sqlite.db3 import connect_read_only
from medkit_replay.inputs.storage import MESSAGE_SIZE_LIMIT, NotABagError
from medkit_replay.msgdefs import Definition, normalize_typename

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Iterator
    from pathlib import Path

    from medkit_replay.model import Loss

_INT64_MAX = 2**63 - 1


class RawMessage(NamedTuple):
    """One recorded message as stored: topic, log time, serialized bytes."""

    t_ns: int
    topic: str
    data: bytes


@dataclass(frozen=True, slots=True)
class TopicInfo:
    """What a clip needs to re-create a topic: its type and the definition as recorded."""

    type: str
    definition: Definition
    serialization_format: str


class _File:
    """One storage file: its topics and ranged reads."""

    path: Path
    topics: dict[str, TopicInfo]

    def read(
        self, topics: Iterable[str], start_ns: int, end_ns: int, *, reverse: bool = False
    ) -> Iterator[RawMessage]:
        raise NotImplementedError

    def close(self) -> None:
        raise NotImplementedError


def _silent(text: str, loss: Loss | None = None, /) -> None:
    """Says nothing: what opening a file finds, the replay has reported already."""


class _McapFile(_File):
    """Read through the replay's MCAP reader (inputs.mcap): its bounds, its damage handling."""

    def __init__(self, path: Path, note: Callable[[str], None]) -> None:
        self.path = path
        open_regular(path).close()  # a FIFO or device is refused, never waited on
        # What opening finds (a profile, a missing footer) the replay has reported already.
        self.file = McapFile(path, 0, _silent)

        def noted(text: str, loss: Loss | None = None, /) -> None:
            note(text)  # damage met in a window: a note of the evidence (the replay counted it)

        self.file.warn = noted
        if not self.file.chunk_indexed:
            # Time windows are read through the chunk index only: a file without one would
            # be scanned whole for every capture.
            problem = self.file.index_problem
            if problem == NO_FOOTER:
                raise ValueError("no summary section (a truncated file?)")
            raise ValueError(problem or "no chunk index in its summary section")
        self.topics = {}
        for connection in self.file.connections.values():
            if not connection.msgtype or connection.serialization != "cdr":
                continue
            self.topics.setdefault(
                connection.topic,
                TopicInfo(connection.msgtype, connection.definition, connection.serialization),
            )

    def read(
        self, topics: Iterable[str], start_ns: int, end_ns: int, *, reverse: bool = False
    ) -> Iterator[RawMessage]:
        wanted = {t for t in topics if t in self.topics}
        if not wanted:
            return
        window = self.file.read_window(
            lambda connection: connection.topic in wanted,
            max(start_ns, 0),
            min(end_ns, _INT64_MAX),
            reverse=reverse,
        )
        for message in window:
            connection, data = message.item
            yield RawMessage(
                message.t_ns, connection.topic, data if isinstance(data, bytes) else bytes(data)
            )

    def close(self) -> None:
        self.file.close()


class _Db3File(_File):
    def __init__(self, path: Path) -> None:
        wal = path.with_name(path.name + "-wal")
        if wal.exists() and wal.stat().st_size > 0:
            raise ValueError("in WAL mode (frames not checkpointed)")
        self.path = path
        # As the replay opens it: immutable, and no row's blob past the message bound (a hostile
        # row inside a clip's window stops the file's evidence, noted, instead of being held).
        self.db = connect_read_only(path.resolve(), immutable=True, limit=MESSAGE_SIZE_LIMIT)
        self.ids: dict[str, int] = {}
        self.topics = {}
        try:
            self._index()
        except BaseException:
            self.db.close()
            raise

    def _index(self) -> None:
        definitions: dict[str, Definition] = {}
        tables = {r[0] for r in self.db.execute("SELECT name FROM sqlite_master")}
        if "message_definitions" in tables:
            for name, encoding, text in self.db.execute(
                "SELECT topic_type, encoding, encoded_message_definition FROM message_definitions"
            ):
                definitions[str(name)] = Definition(str(encoding), str(text))
        for topic_id, name, type_name, fmt in self.db.execute(
            "SELECT id, name, type, serialization_format FROM topics"
        ):
            if fmt != "cdr":
                continue
            self.ids[str(name)] = int(topic_id)
            self.topics[str(name)] = TopicInfo(
                normalize_typename(str(type_name)),
                definitions.get(str(type_name), Definition("", "")),
                str(fmt),
            )

    def read(
        self, topics: Iterable[str], start_ns: int, end_ns: int, *, reverse: bool = False
    ) -> Iterator[RawMessage]:
        by_id = {self.ids[t]: t for t in topics if t in self.ids}
        if not by_id:
            return
        marks = ",".join("?" * len(by_id))
        order = "DESC" if reverse else "ASC"
        rows = self.db.execute(
            f"SELECT timestamp, topic_id, data FROM messages WHERE topic_id IN ({marks}) "
            f"AND timestamp BETWEEN ? AND ? ORDER BY timestamp {order}, id {order}",
            (*by_id, start_ns, end_ns),
        )
        for t_ns, topic_id, data in rows:
            yield RawMessage(int(t_ns), by_id[topic_id], bytes(data))

    def close(self) -> None:
        self.db.close()


def storage_files(path: Path) -> list[Path]:
    """The storage files of one input (a rosbag2 folder or a bare file); a compressed one
    (``.zstd``) and a ROS 1 bag are listed too, and refused when opened."""
    wanted = (".mcap", ".db3", ".zstd", ".bag")
    if path.is_dir():
        found = [p for p in path.iterdir() if p.suffix.lower() in wanted and p.is_file()]
        return sorted(found, key=lambda p: p.name)
    return [path] if path.suffix.lower() in wanted else []


class EvidenceSource:
    """Every readable storage file of a recording's inputs, read by topic and time range.

    Attributes:
        topics: every topic with its type and recorded definition (first file wins).
        skipped: files that could not be opened for evidence, with why.
    """

    def __init__(self, inputs: Iterable[Path | str]) -> None:
        self.files: list[_File] = []
        self.skipped: list[str] = []
        self.topics: dict[str, TopicInfo] = {}
        for path in inputs:
            if isinstance(path, str):
                self.skipped.append(
                    f"{path}: not read for evidence: a remote recording (download it to "
                    "capture its freeze frames and recordings)"
                )
                continue
            for file in storage_files(path):
                try:
                    if file.suffix.lower() == ".zstd":
                        raise ValueError("file-compressed storage")
                    if file.suffix.lower() == ".bag":
                        # Its payloads are ROS 1 serialized: no rosbag2 clip or serializer
                        # rendering the live (ROS 2) manager would make can be taken from it.
                        raise ValueError("a ROS 1 bag holds no ROS 2 messages to capture")
                    opened: _File = (
                        _McapFile(file, self._note)
                        if file.suffix.lower() == ".mcap"
                        else _Db3File(file)
                    )
                except (OSError, NotABagError, sqlite3.Error, ValueError, KeyError) as err:
                    self.skipped.append(f"{file}: not read for evidence: {err}")
                    continue
                self.files.append(opened)
                for topic, info in opened.topics.items():
                    self.topics.setdefault(topic, info)

    def _note(self, note: str) -> None:
        """Note a problem once (damage met again by a later read is not repeated)."""
        if note not in self.skipped:
            self.skipped.append(note)

    def _guarded(self, file: _File, stream: Iterator[RawMessage]) -> Iterator[RawMessage]:
        """A file's messages until it turns out damaged; the damage is noted once.

        The MCAP reader notes damage it can read past (a chunk lost) and goes on; sqlite3
        raises on damaged pages, and stops the read.
        """
        try:
            yield from stream
        except ImportError:
            raise
        except Exception as err:  # sqlite3 raises many kinds on damaged bytes
            self._note(f"{file.path}: stopped reading evidence at damage ({err})")

    def read(self, topics: Iterable[str], start_ns: int, end_ns: int) -> Iterator[RawMessage]:
        """Messages on ``topics`` with log time in [start_ns, end_ns], in time order."""
        wanted = sorted(set(topics))
        streams = [self._guarded(f, f.read(wanted, start_ns, end_ns)) for f in self.files]
        if len(streams) == 1:
            return streams[0]
        return (m for _, m in heapq.merge(*(_keyed(s, n) for n, s in enumerate(streams))))

    def first(self, topic: str, after_ns: int, until_ns: int) -> RawMessage | None:
        """The first message on ``topic`` in (after_ns, until_ns]."""
        return next(iter(self.read((topic,), after_ns + 1, until_ns)), None)

    def last(self, topic: str, at_ns: int, max_size: int) -> RawMessage | None:
        """The last message on ``topic`` at or before ``at_ns`` no larger than ``max_size``."""
        best: RawMessage | None = None
        for file in self.files:
            stream = file.read((topic,), -(2**63), at_ns, reverse=True)
            for message in self._guarded(file, stream):
                if len(message.data) <= max_size:
                    if best is None or message.t_ns > best.t_ns:
                        best = message
                    break
        return best

    def any_between(self, topics: Iterable[str], start_ns: int, end_ns: int) -> bool:
        """Whether any message on ``topics`` lies in [start_ns, end_ns]."""
        return next(iter(self.read(topics, start_ns, end_ns)), None) is not None

    def close(self) -> None:
        """Close every file."""
        for file in self.files:
            file.close()


def _keyed(
    stream: Iterator[RawMessage], number: int
) -> Iterator[tuple[tuple[int, int], RawMessage]]:
    for message in stream:
        yield (message.t_ns, number), message
