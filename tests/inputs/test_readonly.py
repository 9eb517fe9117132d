"""Inputs are never written: WAL-mode sqlite3 bags in read-only folders, MCAP bags, the fixtures.

Tests may run as root, for whom chmod stops nothing: listings and hashes are compared instead.
"""

from __future__ import annotations

import hashlib
import stat
import subprocess
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from medkit_replay.inputs import open_recording
from tests.inputs.builders import as_wal, diag, storage_file, write_bag

if TYPE_CHECKING:
    from collections.abc import Iterator

FIXTURES = Path(__file__).parents[1] / "fixtures" / "rosbag2"


def snapshot(root: Path) -> dict[str, tuple[int, str]]:
    """Every file under root with its mode and content hash."""
    return {
        str(p.relative_to(root)): (p.stat().st_mode, hashlib.sha256(p.read_bytes()).hexdigest())
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


@contextmanager
def read_only(root: Path) -> Iterator[None]:
    for path in [*root.rglob("*"), root]:
        mode = stat.S_IRUSR | stat.S_IRGRP | stat.S_IROTH
        if path.is_dir():
            mode |= stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH
        path.chmod(mode)
    try:
        yield
    finally:
        for path in [root, *root.rglob("*")]:
            path.chmod(path.stat().st_mode | stat.S_IWUSR)


@pytest.fixture
def wal_bag(tmp_path: Path) -> Iterator[Path]:
    bag = write_bag(tmp_path / "bag", [diag(t) for t in range(1, 6)], storage="sqlite3")
    as_wal(storage_file(bag))
    yield bag


def test_wal_sqlite_bag_in_read_only_folder_is_left_untouched(wal_bag: Path) -> None:
    db = storage_file(wal_bag)
    assert db.read_bytes()[18:20] == b"\x02\x02"  # WAL mode in the header
    before = snapshot(wal_bag)
    with read_only(wal_bag):
        with open_recording([wal_bag]) as recording:
            assert [m.t_ns for m in recording.messages()] == [1, 2, 3, 4, 5]
            assert recording.warnings == []
        with open_recording([db]) as recording:
            assert len(list(recording.messages())) == 5
    assert snapshot(wal_bag) == before
    assert sorted(p.name for p in wal_bag.iterdir()) == ["bag.db3", "metadata.yaml"]


KILL_WRITER = """
import os, sqlite3, sys
db = sqlite3.connect(sys.argv[1])
db.execute("PRAGMA wal_autocheckpoint=0")
row = db.execute("SELECT topic_id, data FROM messages ORDER BY id DESC LIMIT 1").fetchone()
db.execute("INSERT INTO messages (topic_id, timestamp, data) VALUES (?, 99, ?)", row)
db.commit()
os._exit(0)  # the recorder dies: the -wal keeps the committed row, nothing checkpoints it
"""


def test_uncheckpointed_wal_is_read_from_a_copy(wal_bag: Path) -> None:
    db = storage_file(wal_bag)
    subprocess.run([sys.executable, "-c", KILL_WRITER, str(db)], check=True)
    wal = db.with_name(db.name + "-wal")
    assert wal.stat().st_size > 0
    before = snapshot(wal_bag)
    with read_only(wal_bag), open_recording([wal_bag]) as recording:
        assert [m.t_ns for m in recording.messages()] == [1, 2, 3, 4, 5, 99]
        assert recording.warnings == [
            f"{db}: {wal.name} holds data not yet checkpointed; read from a copy"
        ]
    assert snapshot(wal_bag) == before


def test_mcap_bag_in_read_only_folder_is_left_untouched(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "bag", [diag(t) for t in range(1, 4)], compression="file")
    before = snapshot(bag)
    with read_only(bag), open_recording([bag]) as recording:
        assert len(list(recording.messages())) == 3
    assert snapshot(bag) == before


def test_reading_every_fixture_changes_nothing() -> None:
    before = snapshot(FIXTURES)
    paths = [p for p in FIXTURES.iterdir() if p.is_dir()]
    paths += sorted((FIXTURES / "bare_files").iterdir())
    for path in paths:
        with open_recording([path], rosout=True) as recording:
            for _ in recording.messages():
                pass
    assert snapshot(FIXTURES) == before
    assert not [p for p in FIXTURES.rglob("*") if p.name.endswith(("-wal", "-shm", "-journal"))]


def test_temporary_copies_are_removed_on_close(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "bag", [diag(1)], compression="file")
    temp_root = Path(tempfile.gettempdir())
    before = {p.name for p in temp_root.glob("medkit-replay-*")}
    with open_recording([bag]) as recording:
        assert {p.name for p in temp_root.glob("medkit-replay-*")} - before
        list(recording.messages())
    assert {p.name for p in temp_root.glob("medkit-replay-*")} == before
