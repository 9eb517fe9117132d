"""Red team: what hostile recordings make us write to the temporary folder, and its cleanup.

zstd bombs and wrong magic in file-compressed bags, a sparse multi-gigabyte ``-wal``, SIGTERM
in the middle of decompression: bounded with RLIMIT_FSIZE, and the private TMPDIR left empty.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.inputs.mcap.records import MAGIC as MCAP_MAGIC
from tests.inputs.builders import as_wal, diag, storage_file, write_bag
from tests.redteam.support import assert_one_line_error, run_limited, tree_listing

if sys.version_info >= (3, 14):
    from compression import zstd
else:
    from backports import zstd

if TYPE_CHECKING:
    from tests.redteam.support import Outcome

MIB = 1024 * 1024


def compressed(target: Path, head: bytes, zeros: int) -> Path:
    """A zstd file of ``head`` then ``zeros`` zero bytes, written without holding them."""
    compressor = zstd.ZstdCompressor()
    with target.open("wb") as sink:
        sink.write(compressor.compress(head))
        block = bytes(MIB)
        for _ in range(zeros // MIB):
            sink.write(compressor.compress(block))
        sink.write(compressor.flush())
    return target


def analyze(tmp_path: Path, bag: Path, file_size: int | None = None) -> tuple[Outcome, Path]:
    """Run analyze with a private, initially empty TMPDIR; return the outcome and the TMPDIR."""
    temp = tmp_path / "tmpdir"
    temp.mkdir(exist_ok=True)
    report = tmp_path / "report.json"
    outcome = run_limited(
        ["analyze", bag, "--json", report, "--quiet"],
        env={"TMPDIR": str(temp)},
        cpu_seconds=30,
        file_size=file_size,
    )
    assert "Traceback" not in outcome.stderr, outcome.stderr[-2000:]
    return outcome, temp


def report_warnings(tmp_path: Path) -> list[str]:
    return list(json.loads((tmp_path / "report.json").read_text())["warnings"])


# --- item 6: file compression --------------------------------------------------------


def test_zstd_file_with_wrong_magic_stops_at_once(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    bag.mkdir()
    compressed(bag / "x.mcap.zstd", b"", zeros=512 * MIB)
    outcome, temp = analyze(tmp_path, bag, file_size=8 * MIB)
    assert_one_line_error(outcome, str(bag), "x.mcap", "decompressed data is not an MCAP file")
    assert list(temp.iterdir()) == []
    assert sorted(p.name for p in bag.iterdir()) == ["x.mcap.zstd"]


def test_zstd_bomb_with_the_right_magic_is_cut_at_the_expansion_bound(tmp_path: Path) -> None:
    recorded = storage_file(write_bag(tmp_path / "real", [diag(1), diag(2)]))
    bag = tmp_path / "bag"
    bag.mkdir()
    source = compressed(bag / "x.mcap.zstd", recorded.read_bytes(), zeros=512 * MIB)
    assert source.stat().st_size < 64 * 1024
    # Writing past 80 MiB would kill the child (SIGXFSZ): the bound is 64 MiB for this file.
    outcome, temp = analyze(tmp_path, bag, file_size=80 * MIB)
    assert outcome.status == 0, outcome.stderr[-2000:]
    assert json.loads((tmp_path / "report.json").read_text())["summary"]["messages_read"] == 2
    assert (
        f"{source}: decompresses to more than 67,108,864 bytes (at most 1000x its compressed "
        "size, and the temporary folder's free space less 256 MiB); only the first 67,108,864 "
        "are read; how much was lost is unknown"
    ) in report_warnings(tmp_path)
    assert list(temp.iterdir()) == []


def test_zstd_sqlite_file_is_checked_for_the_sqlite_header(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "bag", [diag(1), diag(2)], storage="sqlite3", compression="file")
    packed = next(bag.glob("*.zstd"))
    mcap_inside = compressed(tmp_path / "other.zstd", MCAP_MAGIC, zeros=MIB)
    packed.write_bytes(mcap_inside.read_bytes())
    outcome, temp = analyze(tmp_path, bag)
    assert_one_line_error(outcome, "decompressed data is not an SQLite database")
    assert list(temp.iterdir()) == []


# --- item 7: a sparse -wal -----------------------------------------------------------

KILL_WRITER = """
import os, sqlite3, sys
db = sqlite3.connect(sys.argv[1])
db.execute("PRAGMA wal_autocheckpoint=0")
row = db.execute("SELECT topic_id, data FROM messages ORDER BY id DESC LIMIT 1").fetchone()
db.execute("INSERT INTO messages (topic_id, timestamp, data) VALUES (?, 99000000000, ?)", row)
db.commit()
os._exit(0)  # the recorder dies: the -wal keeps the committed row, nothing checkpoints it
"""


def test_sparse_three_gigabyte_wal_is_copied_only_as_far_as_its_frames(tmp_path: Path) -> None:
    bag = write_bag(
        tmp_path / "bag", [diag(k * 1_000_000_000) for k in range(1, 4)], storage="sqlite3"
    )
    db = storage_file(bag)
    as_wal(db)
    subprocess.run([sys.executable, "-c", KILL_WRITER, str(db)], check=True)
    wal = db.with_name(db.name + "-wal")
    with wal.open("r+b") as stream:
        stream.truncate(3 * 1024 * MIB)  # a hole: no disk used, 3 GB to a naive copy
    before = tree_listing(bag)
    outcome, temp = analyze(tmp_path, bag, file_size=16 * MIB)
    assert outcome.status == 0, outcome.stderr[-2000:]
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["summary"]["messages_read"] == 4  # the row in the -wal too
    assert (
        f"{db}: {wal.name} holds data not yet checkpointed; read from a copy" in report["warnings"]
    )
    assert list(temp.iterdir()) == []
    assert tree_listing(bag) == before  # no -shm, nothing changed beside the recording


def test_wal_that_is_not_a_wal_is_ignored_without_a_copy(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "bag", [diag(1), diag(2)], storage="sqlite3")
    db = storage_file(bag)
    wal = db.with_name(db.name + "-wal")
    with wal.open("wb") as stream:
        stream.truncate(3 * 1024 * MIB)
    before = tree_listing(bag)
    outcome, temp = analyze(tmp_path, bag, file_size=MIB)
    assert outcome.status == 0, outcome.stderr[-2000:]
    assert list(temp.iterdir()) == []
    assert tree_listing(bag) == before


# --- item 8: SIGTERM in the middle of decompression ----------------------------------

# Loaded by the child (PYTHONPATH): each decompressed block takes 50 ms, so the test can
# signal it mid-way; the code under test is unchanged.
SLOW_ZSTD = """
import sys, time
if sys.version_info >= (3, 14):
    from compression import zstd
else:
    from backports import zstd
_Real = zstd.ZstdDecompressor
class _Slow:
    def __init__(self, *args, **kwargs):
        self._real = _Real(*args, **kwargs)
    def __getattr__(self, name):
        return getattr(self._real, name)
    def decompress(self, *args, **kwargs):
        time.sleep(0.05)
        return self._real.decompress(*args, **kwargs)
zstd.ZstdDecompressor = _Slow
"""


def test_sigterm_during_decompression_leaves_the_temporary_folder_empty(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    bag.mkdir()
    compressed(bag / "x.mcap.zstd", MCAP_MAGIC, zeros=60 * MIB)
    hook = tmp_path / "hook"
    hook.mkdir()
    (hook / "sitecustomize.py").write_text(SLOW_ZSTD)
    temp = tmp_path / "tmpdir"
    temp.mkdir()
    env = dict(os.environ, TMPDIR=str(temp), PYTHONPATH=f"{hook}{os.pathsep}{Path.cwd()}")
    child = subprocess.Popen(
        [sys.executable, "-m", "medkit_replay.cli", "analyze", bag, "--quiet"],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    try:
        deadline = time.monotonic() + 60
        while not any(p.is_file() and p.stat().st_size for p in temp.rglob("*")):
            assert child.poll() is None, child.stderr.read() if child.stderr else ""
            assert time.monotonic() < deadline, "no temporary file appeared"
            time.sleep(0.01)
        child.send_signal(signal.SIGTERM)
        _, stderr = child.communicate(timeout=60)
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    assert child.returncode == 2, stderr
    assert b"SIGTERM" in stderr and b"nothing partial was left behind" in stderr, stderr
    assert b"Traceback" not in stderr, stderr
    assert list(temp.iterdir()) == []
