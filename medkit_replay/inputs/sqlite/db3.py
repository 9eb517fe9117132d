"""rosbag2 sqlite3 storage files, opened immutable and read-only so nothing beside them changes.

An uncheckpointed ``-wal`` is read from a temporary copy; a damaged database keeps what it can.
"""

from __future__ import annotations

import sqlite3
from contextlib import closing
from typing import TYPE_CHECKING

from medkit_replay.files import open_regular
from medkit_replay.inputs.merge import Bound, Timed
from medkit_replay.inputs.sqlite.wal import checkpointed_copy
from medkit_replay.inputs.storage import (
    MESSAGE_SIZE_LIMIT,
    Connection,
    NotABagError,
    Raw,
    StorageFields,
)
from medkit_replay.model import Loss
from medkit_replay.msgdefs import NO_DEFINITION, Definition, normalize_typename

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator
    from pathlib import Path
    from tempfile import TemporaryDirectory

    from medkit_replay.inputs.source import Warn

SQLITE_MAGIC = b"SQLite format 3\x00"
MAX_TOPICS = 65_536
"""Most topics (and message definitions) read from one file; rosbag2 bags hold hundreds."""
SCHEMA_VALUE_LIMIT = 1024 * 1024
"""Longest topic name, type or message definition (bytes); real ones are a few KB."""
SCHEMA_BYTES_LIMIT = 64 * 1024 * 1024
"""Most bytes of topic names, types and definitions read from one file."""
MAX_TOO_LARGE = 1000
"""Most oversized rows skipped one by one before the rest of a file is given up."""
MAX_TOPIC_PARAMETERS = 500
"""Most topic ids named in a query (SQLite allows 32,766); beyond, rows are filtered here."""
_SHOWN_IDS = 5

# A row is read only with an integer id and an integer timestamp in [0, 2^63).
_GOOD = "typeof(id) = 'integer' AND typeof(timestamp) = 'integer' AND timestamp >= 0"
_TIME_RULE = "not an integer log time in [0, 2^63)"


def connect_read_only(path: Path, *, immutable: bool, limit: int) -> sqlite3.Connection:
    """An sqlite3 bag opened read-only (``immutable``: no lock, nothing written beside it), no
    string or blob longer than ``limit`` ever built."""
    flags = "mode=ro&immutable=1" if immutable else "mode=ro"
    connection = sqlite3.connect(f"{path.absolute().as_uri()}?{flags}", uri=True)
    # SQLite refuses to build a longer string or blob (a huge row, a generated column).
    connection.setlimit(sqlite3.SQLITE_LIMIT_LENGTH, limit)
    connection.execute("PRAGMA query_only = ON")
    # Lets SQLite read a file shorter than its header claims (a truncated copy) up to its end.
    connection.execute("PRAGMA writable_schema = ON")
    return connection


def _ids(ids: list[object], count: int) -> str:
    shown = ", ".join(str(i) for i in ids[:_SHOWN_IDS])
    return f"id {shown}" if count == 1 else f"ids {shown}{', ...' if count > len(ids) else ''}"


def _rows(count: int) -> str:
    return "1 message row" if count == 1 else f"{count:,} message rows"


class _Losses:
    """Rows skipped for one reason while reading: how many, and the first few ids."""

    def __init__(self) -> None:
        self.count = 0
        self.ids: list[object] = []

    def add(self, rowid: object) -> None:
        self.count += 1
        if len(self.ids) < _SHOWN_IDS and isinstance(rowid, int):
            self.ids.append(rowid)


class Db3File(StorageFields):
    """One ``.db3`` file; see :class:`medkit_replay.inputs.storage.StorageFile`."""

    storage = "sqlite3"

    def __init__(self, path: Path, file_no: int, warn: Warn) -> None:
        super().__init__(path, file_no, warn)
        self._counted = False
        self._emitted = 0  # wanted messages read: what damage leaves of the rows counted
        self._wanted_ids: set[int] = set()
        self._bad_times: dict[int, int] = {}
        self._copy: TemporaryDirectory[str] | None = None
        self._open(path)

    def _open(self, path: Path) -> None:
        """Check the magic and probe the database (a copy with its ``-wal`` applied, if any)."""
        try:
            with open_regular(path) as bio:
                magic = bio.read(len(SQLITE_MAGIC))
        except OSError as exc:
            raise NotABagError(f"cannot read: {exc.strerror or exc}") from None
        if magic != SQLITE_MAGIC:
            raise NotABagError("not an SQLite database")
        copied = checkpointed_copy(path, self.warn)
        self._source = path
        if copied is not None:
            self._copy, self._source = copied
        try:
            with closing(
                connect_read_only(self._source, immutable=True, limit=SCHEMA_VALUE_LIMIT)
            ) as db:
                self._probe(db)
        except sqlite3.Error as exc:
            self.close()
            raise NotABagError(f"SQLite database cannot be read ({exc})") from None

    def _probe(self, db: sqlite3.Connection) -> None:
        try:
            self._read_topics(db)
        except (sqlite3.Error, TypeError, ValueError) as exc:
            raise NotABagError(f"damaged database: its topics cannot be read ({exc})") from None
        orphans = 0
        try:
            query = (
                "SELECT topic_id, SUM(ok), MIN(CASE WHEN ok THEN timestamp END), "
                "MAX(CASE WHEN ok THEN timestamp END), SUM(NOT ok) "
                f"FROM (SELECT topic_id, timestamp, ({_GOOD}) AS ok FROM messages) "
                "GROUP BY topic_id"
            )
            for cid, count, first, last, bad in db.execute(query):
                if not isinstance(cid, int) or cid not in self.connections:
                    orphans += int(count) + int(bad)
                    continue
                if bad:
                    self._bad_times[cid] = int(bad)
                if not count:
                    continue
                self.counts[cid] = int(count)
                self.start_ns = first if self.start_ns is None else min(self.start_ns, first)
                self.end_ns = last if self.end_ns is None else max(self.end_ns, last)
            self._counted = True
        except (sqlite3.Error, TypeError, ValueError) as exc:
            self.counts.clear()
            self._bad_times.clear()
            self.start_ns = self.end_ns = None
            self.warn(f"{self.path}: damaged database, messages cannot be counted ({exc})", Loss())
            return
        if orphans:
            self.warn(
                f"{self.path}: {_rows(orphans)} name no declared topic; not read",
                Loss(messages=orphans),
            )

    def _read_topics(self, db: sqlite3.Connection) -> None:
        tables = {row[0] for row in db.execute("SELECT name FROM sqlite_master WHERE type='table'")}
        if not {"messages", "topics"} <= tables:
            raise NotABagError("SQLite database without rosbag2's messages and topics tables")
        budget = SCHEMA_BYTES_LIMIT
        definitions: dict[str, Definition] = {}
        if "message_definitions" in tables:
            query = (
                "SELECT topic_type, encoding, encoded_message_definition FROM message_definitions"
            )
            for name, encoding, text in db.execute(f"{query} LIMIT {MAX_TOPICS}"):
                values = (str(name), str(encoding), str(text))
                budget -= sum(len(value) for value in values)
                if budget < 0:
                    raise ValueError(f"topics and definitions exceed {SCHEMA_BYTES_LIMIT:,} bytes")
                definitions[normalize_typename(values[0])] = Definition(values[1], values[2])
        rows = self._topic_rows(db)
        if len(rows) > MAX_TOPICS:
            self.warn(f"{self.path}: more than {MAX_TOPICS:,} topics; the rest are not read")
            del rows[MAX_TOPICS:]
        for cid, topic, msgtype, fmt in rows:
            if not (isinstance(cid, int) and isinstance(topic, str) and isinstance(msgtype, str)):
                self.warn(f"{self.path}: topic row {cid!r}, {topic!r} is damaged; not read")
                continue
            budget -= len(topic) + len(msgtype) + len(str(fmt))
            if budget < 0:
                raise ValueError(f"topics and definitions exceed {SCHEMA_BYTES_LIMIT:,} bytes")
            name = normalize_typename(msgtype)
            if cid in self.connections:
                kept = self.connections[cid]
                if (kept.topic, kept.msgtype) != (topic, name):
                    self.warn(
                        f"{self.path}: topic id {cid} is declared twice ({kept.topic} of type "
                        f"{kept.msgtype}, then {topic} of type {name}); its messages cannot be "
                        f"told apart and are read as {kept.topic}, the first declared"
                    )
                continue
            definition = definitions.get(name) or NO_DEFINITION
            if name.endswith("_Event") and definition is NO_DEFINITION:
                # rosbag2 stores a service event topic's definition under the service's name.
                definition = definitions.get(name.removesuffix("_Event"), NO_DEFINITION)
            self.connections[cid] = Connection(cid, topic, name, str(fmt), definition)

    @staticmethod
    def _topic_rows(db: sqlite3.Connection) -> list[tuple[object, ...]]:
        """The topics table in id order, rows of one id in storage order (the first wins)."""
        columns = "SELECT id, name, type, serialization_format FROM topics"
        try:
            return db.execute(f"{columns} ORDER BY id, rowid LIMIT {MAX_TOPICS + 1}").fetchall()
        except sqlite3.OperationalError:  # a table without rowid: its key orders it
            return db.execute(f"{columns} ORDER BY id LIMIT {MAX_TOPICS + 1}").fetchall()

    def close(self) -> None:
        """Release the temporary copy, if one was made."""
        if self._copy is not None:
            self._copy.cleanup()
            self._copy = None

    def read(
        self, wants: Callable[[Connection], bool], cap_ns: int | None
    ) -> Iterator[Bound | Timed[Raw] | list[Timed[Raw]]]:
        """Yield bounds and wanted messages (see ``StorageFile.read``)."""
        wanted = {cid for cid, connection in self.connections.items() if wants(connection)}
        if not wanted:
            return
        losses = {"data": _Losses(), "large": _Losses()}
        self._wanted_ids = wanted
        try:
            with closing(
                connect_read_only(self._source, immutable=True, limit=MESSAGE_SIZE_LIMIT)
            ) as db:
                yield from self._messages(db, sorted(wanted), cap_ns, losses)
                self._report_bad_times(db, wanted)
        except sqlite3.Error as exc:
            self.warn(f"{self.path}: damaged database ({exc})", self._rest_lost(None, losses))
        self._report_losses(losses)

    def _rest_lost(self, after_ns: int | None, losses: dict[str, _Losses]) -> Loss:
        """What stopping here costs: the wanted rows counted but neither read nor skipped
        already (unknown when they could not be counted), after ``after_ns`` to the end."""
        messages = None
        if self._counted:
            counted = sum(self.counts.get(cid, 0) for cid in self._wanted_ids)
            messages = max(0, counted - self._emitted - sum(x.count for x in losses.values()))
        start = after_ns if after_ns is not None and self.end_ns is not None else None
        return Loss(messages=messages, start_ns=start, end_ns=self.end_ns if start else None)

    def _report_losses(self, losses: dict[str, _Losses]) -> None:
        """Warn about wanted rows skipped for their payload."""
        data, large = losses["data"], losses["large"]
        if data.count:
            self.warn(
                f"{self.path}: {_rows(data.count)} without a binary payload "
                f"({_ids(data.ids, data.count)})",
                Loss(messages=data.count),
            )
        if large.count:
            shown = _ids(large.ids, large.count)
            self.warn(
                f"{self.path}: {_rows(large.count)} with a payload that cannot be loaded "
                f"within the {MESSAGE_SIZE_LIMIT:,}-byte limit ({shown})",
                Loss(messages=large.count),
            )

    def _messages(
        self,
        db: sqlite3.Connection,
        ids: list[int],
        cap_ns: int | None,
        losses: dict[str, _Losses],
    ) -> Iterator[Bound | Timed[Raw]]:
        """Rows in time order; past damage to the time index, the rest in storage order."""
        cap = cap_ns if cap_ns is not None else 2**63
        if len(ids) <= MAX_TOPIC_PARAMETERS:
            where, params = f"topic_id IN ({','.join('?' * len(ids))}) AND {_GOOD}", ids
        else:
            where, params = _GOOD, []
        wanted = set(ids)
        # Resume points: the last row read in time order, then the last id in storage order.
        last: tuple[int, int] | None = None
        last_id: int | None = None
        indexed = True
        skips = 0
        while True:
            after, args = _after(last, last_id)
            source = "messages" if indexed else "messages NOT INDEXED"
            order = "timestamp, id" if indexed else "id"
            rows = f"FROM {source} WHERE {where}{after} ORDER BY {order}"
            try:
                for row in db.execute(
                    f"SELECT id, topic_id, timestamp, data {rows}", params + args
                ):
                    if indexed:
                        last = (row[2], row[0])
                    else:
                        last_id = row[0]
                    yield from self._emit(row, wanted, cap, losses)
                return
            except sqlite3.DataError:
                # A row's payload is over the length limit. sqlite3 fetches one row ahead, so
                # it is the next row or the one after: load the next alone to find out.
                skips += 1
                try:
                    found = db.execute(
                        f"SELECT id, topic_id, timestamp {rows} LIMIT 1", params + args
                    ).fetchone()
                except sqlite3.DatabaseError:
                    found = None
                if found is None or skips > MAX_TOO_LARGE:
                    self.warn(
                        f"{self.path}: rows past the limit cannot be skipped; the rest is lost",
                        self._rest_lost(last[0] if last else None, losses),
                    )
                    return
                if indexed:
                    last = (found[2], found[0])
                else:
                    last_id = found[0]
                try:
                    alone = db.execute("SELECT data FROM messages WHERE id = ?", found[:1])
                    yield from self._emit(
                        (*found, *(alone.fetchone() or (None,))), wanted, cap, losses
                    )
                except sqlite3.DataError:
                    losses["large"].add(found[0])
            except sqlite3.DatabaseError as exc:
                if not indexed:
                    self.warn(
                        f"{self.path}: damaged database ({exc}); the rest is lost",
                        self._rest_lost(None, losses),
                    )
                    return
                after_text = f"after t={last[0]}" if last else "from the start"
                self.warn(
                    f"{self.path}: damaged database ({exc}) {after_text}; "
                    "reading on in storage order"
                )
                # The time index may be what is damaged: walk the table itself.
                indexed = False

    def _emit(
        self,
        row: tuple[object, ...],
        wanted: set[int],
        cap: int,
        losses: dict[str, _Losses],
    ) -> Iterator[Bound | Timed[Raw]]:
        rowid, cid, t_ns, data = row
        if not (isinstance(cid, int) and isinstance(rowid, int) and isinstance(t_ns, int)):
            return  # not selected (the query reads integer ids and times only)
        if cid not in wanted:
            return
        if not isinstance(data, bytes):
            losses["data"].add(rowid)
            return
        self._emitted += 1
        if not self._counted:
            self.counts[cid] = self.counts.get(cid, 0) + 1
            self.start_ns = t_ns if self.start_ns is None else min(self.start_ns, t_ns)
            self.end_ns = t_ns if self.end_ns is None else max(self.end_ns, t_ns)
        yield Bound(min(t_ns, cap))
        yield Timed(t_ns, (self.file_no, rowid, 0), Raw(self.connections[cid], data))

    def _report_bad_times(self, db: sqlite3.Connection, wanted: set[int]) -> None:
        """Warn about wanted rows skipped because their log time is unusable."""
        count = sum(self._bad_times.get(cid, 0) for cid in wanted)
        if self._counted and not count:
            return
        ids: list[object] = []
        found = 0
        try:
            query = f"SELECT id, topic_id FROM messages WHERE NOT ({_GOOD}) ORDER BY id"
            for rowid, cid in db.execute(query):
                if cid not in wanted:
                    continue
                found += 1
                if len(ids) < _SHOWN_IDS:
                    ids.append(rowid)
                elif self._counted:
                    break
        except sqlite3.Error:
            pass  # the count from the probe still stands
        if not self._counted:
            count = found
        if count:
            self.warn(
                f"{self.path}: {_rows(count)}: {_TIME_RULE} ({_ids(ids, count)})",
                Loss(messages=count),
            )


def _after(last: tuple[int, int] | None, last_id: int | None) -> tuple[str, list[int]]:
    """The condition (and its arguments) for the rows after the resume points."""
    text, args = "", []
    if last is not None:
        text += " AND (timestamp > ? OR (timestamp = ? AND id > ?))"
        args += [last[0], last[0], last[1]]
    if last_id is not None:
        text += " AND id > ?"
        args.append(last_id)
    return text, args
