"""The private copy of a live WAL-mode database: committed data only, checkpoints followed,
torn frames refused, nothing created beside the writer's files."""

from __future__ import annotations

import shutil
import sqlite3
from contextlib import closing
from typing import TYPE_CHECKING

import pytest

from medkit_replay.inputs.sqlite.wal import WalMirror, is_wal_mode

if TYPE_CHECKING:
    from collections.abc import Iterator
    from pathlib import Path


@pytest.fixture
def writer(tmp_path: Path) -> Iterator[sqlite3.Connection]:
    (tmp_path / "live").mkdir()
    db = sqlite3.connect(tmp_path / "live" / "bag.db3", isolation_level=None)
    db.execute("PRAGMA journal_mode=WAL")
    db.execute("PRAGMA wal_autocheckpoint=0")  # checkpoints only when a test asks
    db.execute("CREATE TABLE messages (id INTEGER PRIMARY KEY, data BLOB)")
    yield db
    db.close()


def commit(db: sqlite3.Connection, first: int, count: int) -> None:
    db.execute("BEGIN")
    db.executemany(
        "INSERT INTO messages VALUES (?, ?)",
        [(i, bytes([i % 256]) * 700) for i in range(first, first + count)],
    )
    db.execute("COMMIT")


def ids(path: Path) -> list[int]:
    uri = f"{path.absolute().as_uri()}?mode=ro&immutable=1"
    with closing(sqlite3.connect(uri, uri=True)) as db:
        return [row[0] for row in db.execute("SELECT id FROM messages ORDER BY id")]


def mirror_of(tmp_path: Path, live: Path) -> WalMirror:
    folder = tmp_path / "copy"
    folder.mkdir(exist_ok=True)
    return WalMirror(live, folder)


def test_commits_are_applied_as_they_come(tmp_path: Path, writer: sqlite3.Connection) -> None:
    live = tmp_path / "live" / "bag.db3"
    assert is_wal_mode(live)
    beside = sorted(p.name for p in live.parent.iterdir())
    mirror = mirror_of(tmp_path, live)
    commit(writer, 1, 5)
    assert mirror.refresh()
    assert ids(mirror.copy) == list(range(1, 6))
    assert not mirror.refresh()  # nothing new
    commit(writer, 6, 20)  # spans several pages: several frames, one commit
    assert mirror.refresh()
    assert ids(mirror.copy) == list(range(1, 26))
    assert sorted(p.name for p in live.parent.iterdir()) == beside  # nothing of ours there


def test_a_checkpoint_restarting_the_wal_is_followed(
    tmp_path: Path, writer: sqlite3.Connection
) -> None:
    live = tmp_path / "live" / "bag.db3"
    mirror = mirror_of(tmp_path, live)
    commit(writer, 1, 10)
    assert mirror.refresh()
    commit(writer, 11, 10)  # never seen by the copy before the checkpoint moves it
    writer.execute("PRAGMA wal_checkpoint(RESTART)")
    commit(writer, 21, 10)  # written from the start of the WAL again, with new salts
    assert mirror.refresh()
    assert ids(mirror.copy) == list(range(1, 31))
    writer.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    assert mirror.refresh()
    assert ids(mirror.copy) == list(range(1, 31))


def test_an_open_transaction_is_not_read(tmp_path: Path, writer: sqlite3.Connection) -> None:
    live = tmp_path / "live" / "bag.db3"
    mirror = mirror_of(tmp_path, live)
    commit(writer, 1, 3)
    writer.execute("PRAGMA cache_size=1")  # pages spill to the WAL before the commit
    writer.execute("BEGIN")
    writer.executemany(
        "INSERT INTO messages VALUES (?, ?)", [(i, b"x" * 3000) for i in range(4, 60)]
    )
    assert mirror.refresh()
    assert ids(mirror.copy) == [1, 2, 3]
    writer.execute("COMMIT")
    assert mirror.refresh()
    assert ids(mirror.copy) == list(range(1, 60))


def test_a_torn_last_frame_keeps_the_commits_before_it(
    tmp_path: Path, writer: sqlite3.Connection
) -> None:
    live = tmp_path / "live" / "bag.db3"
    for first in (1, 11, 21):
        commit(writer, first, 10)
    torn = tmp_path / "torn"
    torn.mkdir()
    shutil.copyfile(live, torn / "bag.db3")
    wal = bytearray((live.parent / "bag.db3-wal").read_bytes())
    wal[-1] ^= 0xFF  # the last frame's page: its checksum no longer holds
    (torn / "bag.db3-wal").write_bytes(bytes(wal))
    mirror = mirror_of(tmp_path, torn / "bag.db3")
    assert mirror.refresh()
    assert ids(mirror.copy) == list(range(1, 21))


def test_a_database_without_wal(tmp_path: Path) -> None:
    path = tmp_path / "plain.db3"
    with closing(sqlite3.connect(path)) as db:
        db.execute("CREATE TABLE messages (id INTEGER PRIMARY KEY, data BLOB)")
        db.execute("INSERT INTO messages VALUES (1, x'00')")
        db.commit()
    assert not is_wal_mode(path)
    mirror = mirror_of(tmp_path, path)
    assert mirror.refresh()
    assert ids(mirror.copy) == [1]
