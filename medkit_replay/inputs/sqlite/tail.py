"""An sqlite3 storage file being written (WAL mode), read commit by commit from a private copy.

Never opens the writer's database for anything but plain reads of its bytes; see sqlite/wal.py.
"""

from __future__ import annotations

import sqlite3
from contextlib import closing
from operator import itemgetter
from pathlib import Path
from tempfile import TemporaryDirectory
from typing import TYPE_CHECKING

from medkit_replay.files import open_regular
from medkit_replay.inputs.follow import FollowStopped
from medkit_replay.inputs.merge import Bound, Timed
from medkit_replay.inputs.sqlite.db3 import (
    _GOOD,
    SCHEMA_VALUE_LIMIT,
    SQLITE_MAGIC,
    Db3File,
    _Losses,
    connect_read_only,
)
from medkit_replay.inputs.sqlite.wal import WalMirror, is_wal_mode
from medkit_replay.inputs.storage import MESSAGE_SIZE_LIMIT, NotABagError, Raw, temp_room
from medkit_replay.model import Loss

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator

    from medkit_replay.inputs.follow import Growing
    from medkit_replay.inputs.source import Warn
    from medkit_replay.inputs.storage import Connection

_ORDER = itemgetter(0, 1)
_HEADER_BYTES = 100  # an SQLite database header


class Db3Tail(Db3File):
    """A growing ``.db3``: each poll reads the rows committed since the last one.

    In WAL mode the writer's commits are applied to a private copy (:class:`WalMirror`) and the
    new rows read from it. In another journal mode a database cannot be read while it is
    written without locking it, so it is read once the recording moved on (``done``). Each
    poll's rows form one batch, sorted by (log time, id), released once later rows show that
    nothing earlier follows. Counts and the span come from the final database, as for a
    finished file. Every poll checks, before and after reading, that it is still the file
    first seen (``watched``).
    """

    def __init__(self, path: Path, file_no: int, warn: Warn, *, growing: Growing) -> None:
        self._follow, self._done, self._watched = growing
        self._waited: tuple[int, int] | None = None  # the file when first not readable live
        self._live = False  # read while written
        self._too_large = False  # for a copy in the temporary folder
        self._topics_seen = 0  # rows of the topics table read so far
        super().__init__(path, file_no, warn)

    def _open(self, path: Path) -> None:
        """Wait for the database header; what the file holds is learnt while reading."""
        while True:
            moved_on = self._done()
            try:
                with open_regular(path) as bio:
                    self._watched.check_open(bio.fileno())
                    magic = bio.read(_HEADER_BYTES)
            except OSError as exc:
                raise NotABagError(f"cannot read: {exc.strerror or exc}") from None
            if len(magic) == _HEADER_BYTES:
                if magic[: len(SQLITE_MAGIC)] != SQLITE_MAGIC:
                    raise NotABagError("not an SQLite database")
                break
            if moved_on:
                raise NotABagError("not an SQLite database (cut off before its header)")
            self._follow.wait()
        self._copy = TemporaryDirectory(prefix="medkit-replay-")

    def read(
        self, wants: Callable[[Connection], bool], cap_ns: int | None
    ) -> Iterator[Bound | Timed[Raw] | list[Timed[Raw]]]:
        """Yield each poll's new rows as a batch until the file is finished (see StorageFile)."""
        assert self._copy is not None
        mirror = WalMirror(self.path, Path(self._copy.name))
        cap = cap_ns if cap_ns is not None else 2**63
        wanted: set[int] = set()
        self._wanted_ids = wanted  # as it grows: what damage costs is counted over it
        classified: set[int] = set()
        losses = {"data": _Losses(), "large": _Losses()}
        last_id = 0
        source: Path | None = None
        try:
            while True:
                done = self._done()
                self._watched.look()
                fresh = self._snapshot(mirror, done)
                if fresh is not None:
                    source = fresh
                    with closing(
                        connect_read_only(source, immutable=True, limit=MESSAGE_SIZE_LIMIT)
                    ) as db:
                        self._new_topics(db, wants, wanted, classified)
                        batch, last_id = self._new_rows(db, wanted, last_id, losses)
                    self._watched.look()  # what was copied or read is of the file read so far
                    if batch:
                        batch.sort(key=_ORDER)
                        yield Bound(min(batch[0].t_ns, cap))
                        yield batch
                if done:
                    break
                self._follow.wait()
        except FollowStopped:
            self._finish(source, wanted, losses)
            raise
        except sqlite3.Error as exc:
            self.warn(f"{self.path}: damaged database ({exc})", self._rest_lost(None, losses))
        self._finish(source, wanted, losses)

    def _snapshot(self, mirror: WalMirror, done: bool) -> Path | None:
        """The database to read now, if it changed: the file itself once finished and without
        a WAL (as a finished file is read), else the private copy; None when not readable yet."""
        if done and not mirror.wal.exists():
            return self.path
        if not done and not is_wal_mode(self.path):
            if self._waited is None:
                self._waited = self._stat()
            return None
        if not done:
            if self._watched.size > temp_room():
                if not self._too_large:
                    self._too_large = True
                    self._follow.notes.append(
                        f"{self.path}: too large for a copy in the temporary folder; it is "
                        "read when the recording is finished"
                    )
                return None
            self._live = True
        if not mirror.needs_copy():
            return mirror.copy if mirror.refresh() else None
        if not done and not self._follow.may_spend(self.path):
            self._follow.saw_data()  # the WAL restarted since the last copy: the writer is busy
            return None  # copied again a moment ago: the writer's commits wait for the next
        with self._follow.spending(self.path):
            changed = mirror.refresh()
        return mirror.copy if changed else None

    def _stat(self) -> tuple[int, int]:
        try:
            info = self.path.stat()
        except OSError:
            return (-1, -1)
        return (info.st_size, info.st_mtime_ns)

    def _new_topics(
        self,
        db: sqlite3.Connection,
        wants: Callable[[Connection], bool],
        wanted: set[int],
        classified: set[int],
    ) -> None:
        try:
            count = db.execute("SELECT count(*) FROM topics").fetchone()[0]
        except sqlite3.OperationalError:
            return  # the tables are not created yet
        if count == self._topics_seen:
            return
        self._topics_seen = count
        try:
            self._read_topics(db)
        except NotABagError:
            return  # the tables are not created yet
        except ValueError as exc:
            raise sqlite3.DatabaseError(str(exc)) from None
        for cid in sorted(set(self.connections) - classified):
            classified.add(cid)
            if wants(self.connections[cid]):
                wanted.add(cid)

    def _new_rows(
        self,
        db: sqlite3.Connection,
        wanted: set[int],
        last_id: int,
        losses: dict[str, _Losses],
    ) -> tuple[list[Timed[Raw]], int]:
        """The wanted rows after ``last_id`` (in id order) and the id read up to."""
        top = db.execute("SELECT max(id) FROM messages").fetchone()[0]
        if not isinstance(top, int) or top <= last_id:
            return [], last_id
        self._follow.saw_data()
        batch: list[Timed[Raw]] = []
        if not wanted:
            return batch, top
        query = (
            f"SELECT id, topic_id, timestamp, CASE WHEN length(data) <= {MESSAGE_SIZE_LIMIT} "
            "THEN data END, typeof(data) FROM messages "
            f"WHERE id > ? AND id <= ? AND {_GOOD} ORDER BY id"
        )
        connections, file_no = self.connections, self.file_no
        for rowid, cid, t_ns, data, kind in db.execute(query, (last_id, top)):
            if cid not in wanted:
                continue
            if isinstance(data, bytes):
                batch.append(Timed(t_ns, (file_no, rowid, 0), Raw(connections[cid], data)))
            else:
                losses["large" if kind == "blob" else "data"].add(rowid)
        return batch, top

    def _finish(self, source: Path | None, wanted: set[int], losses: dict[str, _Losses]) -> None:
        """Counts, span and the rows skipped, from the last database read (as a finished file)."""
        if self._waited is not None and not self._live and self._waited != self._stat():
            self._follow.notes.append(
                f"{self.path}: not in WAL mode; it cannot be read while written without "
                "locking it, so it was read once the writer was done with it"
            )
        if source is not None:
            try:
                with closing(
                    connect_read_only(source, immutable=True, limit=SCHEMA_VALUE_LIMIT)
                ) as db:
                    self._probe(db)
                    self._report_bad_times(db, wanted)
            except (sqlite3.Error, NotABagError) as exc:
                self.warn(
                    f"{self.path}: damaged database ({exc}); its messages cannot be counted", Loss()
                )
        self._report_losses(losses)
