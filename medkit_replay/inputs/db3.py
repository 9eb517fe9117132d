"""rosbag2 sqlite3 storage files, opened immutable and read-only so nothing beside them changes.

An uncheckpointed ``-wal`` is read from a temporary copy; a damaged database keeps what it can.
"""

from __future__ import annotations

import shutil
import sqlite3
from contextlib import closing
from tempfile import TemporaryDirectory
from typing import TYPE_CHECKING

from medkit_replay.inputs.merge import Bound, Timed
from medkit_replay.inputs.selection import normalize_typename
from medkit_replay.inputs.storage import Connection, NotABagError, Raw
from medkit_replay.inputs.typestore import NO_DEFINITION, Definition

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator
    from pathlib import Path

SQLITE_MAGIC = b"SQLite format 3\x00"
_COLUMNS = "SELECT id, topic_id, timestamp, data FROM messages"


def _connect(path: Path, *, immutable: bool) -> sqlite3.Connection:
    flags = "mode=ro&immutable=1" if immutable else "mode=ro"
    connection = sqlite3.connect(f"{path.absolute().as_uri()}?{flags}", uri=True)
    connection.execute("PRAGMA query_only = ON")
    # Lets SQLite read a file shorter than its header claims (a truncated copy) up to its end.
    connection.execute("PRAGMA writable_schema = ON")
    return connection


class Db3File:
    """One ``.db3`` file; see :class:`medkit_replay.inputs.storage.StorageFile`."""

    storage = "sqlite3"

    def __init__(self, path: Path, file_no: int, warn: Callable[[str], None]) -> None:
        self.path = path
        self.file_no = file_no
        self.warn = warn
        self.connections: dict[int, Connection] = {}
        self.counts: dict[int, int] = {}
        self.start_ns: int | None = None
        self.end_ns: int | None = None
        self._counted = False
        self._bad_rows = 0
        self._copy: TemporaryDirectory[str] | None = None
        try:
            with path.open("rb") as bio:
                magic = bio.read(len(SQLITE_MAGIC))
        except OSError as exc:
            raise NotABagError(f"cannot read: {exc.strerror or exc}") from None
        if magic != SQLITE_MAGIC:
            raise NotABagError("not an SQLite database")
        self._source = self._pending_wal() or path
        try:
            with closing(_connect(self._source, immutable=True)) as db:
                self._probe(db)
        except sqlite3.Error as exc:
            self.close()
            raise NotABagError(f"SQLite database cannot be read ({exc})") from None

    def _pending_wal(self) -> Path | None:
        """A checkpointed temporary copy when a ``-wal`` holds data ``immutable`` would ignore."""
        wal = self.path.with_name(self.path.name + "-wal")
        journal = self.path.with_name(self.path.name + "-journal")
        if journal.is_file() and journal.stat().st_size:
            self.warn(f"{self.path}: an unfinished transaction in {journal.name} is not read")
        if not wal.is_file() or not wal.stat().st_size:
            return None
        self._copy = TemporaryDirectory(prefix="medkit-replay-")
        copy = shutil.copy(self.path, self._copy.name)
        shutil.copy(wal, self._copy.name)
        try:
            with closing(sqlite3.connect(copy)) as db:
                db.execute("PRAGMA wal_checkpoint(TRUNCATE)")
        except sqlite3.Error as exc:
            self.warn(f"{self.path}: {wal.name} cannot be applied ({exc}); its data is not read")
            return None
        self.warn(f"{self.path}: {wal.name} holds data not yet checkpointed; read from a copy")
        return type(self.path)(copy)

    def _probe(self, db: sqlite3.Connection) -> None:
        try:
            self._read_topics(db)
        except (sqlite3.Error, TypeError, ValueError) as exc:
            raise NotABagError(f"damaged database: its topics cannot be read ({exc})") from None
        try:
            query = "SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp) FROM messages"
            for cid, count, first, last in db.execute(f"{query} GROUP BY topic_id"):
                self.counts[int(cid)] = int(count)
                self.start_ns = first if self.start_ns is None else min(self.start_ns, int(first))
                self.end_ns = last if self.end_ns is None else max(self.end_ns, int(last))
            self._counted = True
        except (sqlite3.Error, TypeError, ValueError) as exc:
            self.counts.clear()
            self.start_ns = self.end_ns = None
            self.warn(f"{self.path}: damaged database, messages cannot be counted ({exc})")

    def _read_topics(self, db: sqlite3.Connection) -> None:
        tables = {row[0] for row in db.execute("SELECT name FROM sqlite_master WHERE type='table'")}
        if not {"messages", "topics"} <= tables:
            raise NotABagError("SQLite database without rosbag2's messages and topics tables")
        definitions: dict[str, Definition] = {}
        if "message_definitions" in tables:
            query = (
                "SELECT topic_type, encoding, encoded_message_definition FROM message_definitions"
            )
            for name, encoding, text in db.execute(query):
                definitions[normalize_typename(str(name))] = Definition(str(encoding), str(text))
        for cid, topic, msgtype, fmt in db.execute(
            "SELECT id, name, type, serialization_format FROM topics ORDER BY id"
        ):
            name = normalize_typename(str(msgtype))
            definition = definitions.get(name) or NO_DEFINITION
            if name.endswith("_Event") and definition is NO_DEFINITION:
                # rosbag2 stores a service event topic's definition under the service's name.
                definition = definitions.get(name.removesuffix("_Event"), NO_DEFINITION)
            self.connections[int(cid)] = Connection(
                int(cid), str(topic), name, str(fmt), definition
            )

    def close(self) -> None:
        """Delete the temporary copy, if one was made."""
        if self._copy is not None:
            self._copy.cleanup()
            self._copy = None

    def read(
        self, wants: Callable[[Connection], bool], cap_ns: int | None
    ) -> Iterator[Bound | Timed[Raw] | list[Timed[Raw]]]:
        """Yield bounds and wanted messages (see ``StorageFile.read``)."""
        ids = [cid for cid, connection in self.connections.items() if wants(connection)]
        if not ids:
            return
        cap = cap_ns if cap_ns is not None else 2**63
        where = f"WHERE topic_id IN ({','.join('?' * len(ids))})"
        last: tuple[int, int] | None = None
        with closing(_connect(self._source, immutable=True)) as db:
            try:
                for row in db.execute(f"{_COLUMNS} {where} ORDER BY timestamp, id", ids):
                    yield from self._row(row, cap)
                    last = (row[2], row[0])
                return
            except sqlite3.DatabaseError as exc:
                after = f"after t={last[0]}" if last else "from the start"
                self.warn(
                    f"{self.path}: damaged database ({exc}) {after}; reading on in storage order"
                )
            # The time index may be what is damaged: walk the table itself from the last row read.
            resume = "AND (timestamp > ? OR (timestamp = ? AND id > ?))" if last else ""
            args = [*ids, last[0], last[0], last[1]] if last else ids
            query = f"{_COLUMNS} NOT INDEXED {where} {resume} ORDER BY id"
            try:
                for row in db.execute(query, args):
                    yield from self._row(row, cap)
            except sqlite3.DatabaseError as exc:
                self.warn(f"{self.path}: damaged database ({exc}); the rest is lost")
        if self._bad_rows:
            self.warn(f"{self.path}: {self._bad_rows} damaged message rows skipped")

    def _row(self, row: tuple[object, ...], cap: int) -> Iterator[Bound | Timed[Raw]]:
        rowid, cid, t_ns, data = row
        if not (
            isinstance(rowid, int)
            and isinstance(cid, int)
            and isinstance(t_ns, int)
            and isinstance(data, bytes)
            and cid in self.connections
        ):
            self._bad_rows += 1
            return
        if not self._counted:
            self.counts[cid] = self.counts.get(cid, 0) + 1
            self.start_ns = t_ns if self.start_ns is None else min(self.start_ns, t_ns)
            self.end_ns = t_ns if self.end_ns is None else max(self.end_ns, t_ns)
        yield Bound(min(t_ns, cap))
        yield Timed(t_ns, (self.file_no, rowid, 0), Raw(self.connections[cid], data))
