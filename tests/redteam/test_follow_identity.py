"""Red team: files that are not what they were, or not files at all, under analyze and follow.

A storage file or recording that is a FIFO is refused at once (never opened blocking); a
followed file that is cut, renamed over or swapped behind a symlink is said in one line and
replayed from its start, so the report is the new file's, with a warning.
"""

from __future__ import annotations

import json
import os
import queue
import shutil
import subprocess
import sys
import threading
from pathlib import Path
from typing import IO, TYPE_CHECKING

import pytest

import medkit_replay
from medkit_replay.files import FileRefusedError
from medkit_replay.inputs.follow import Follow
from medkit_replay.inputs.watch import FollowRestart, Watched
from medkit_replay.model import POLL_MIN_S
from medkit_replay.pipeline import replay
from tests.inputs.builders import (
    as_wal,
    diag,
    write_bag,
    write_bare,
)
from tests.redteam.support import assert_one_line_error, run_limited

if TYPE_CHECKING:
    from collections.abc import Callable

SECOND = 1_000_000_000
PACKAGE_ROOT = Path(medkit_replay.__file__).resolve().parents[1]
ENV = {**os.environ, "PYTHONPATH": str(PACKAGE_ROOT)}
TIMEOUT = 60


def device(path: Path) -> None:
    """/dev/zero under a recording's name: a device that would be read forever."""
    path.symlink_to("/dev/zero")


@pytest.mark.parametrize("command", ["analyze", "follow"])
@pytest.mark.parametrize(
    ("name", "make", "kind"),
    [("run.mcap", os.mkfifo, "a FIFO"), ("run.db3", os.mkfifo, "a FIFO"),
     ("run.mcap", device, "a character device")],
    ids=["fifo-mcap", "fifo-db3", "dev-zero"],
)  # fmt: skip
def test_a_recording_that_is_not_a_regular_file_is_refused_not_read(
    tmp_path: Path, command: str, name: str, make: Callable[[Path], None], kind: str
) -> None:
    path = tmp_path / name
    make(path)
    outcome = run_limited([command, path, "--quiet"], timeout=TIMEOUT)
    assert_one_line_error(outcome, str(path), f"{kind}, not a regular file")


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_following_a_folder_whose_storage_file_is_a_fifo_is_refused(
    tmp_path: Path, storage: str
) -> None:
    bag = tmp_path / "bag"
    bag.mkdir()
    fifo = bag / ("bag_0.mcap" if storage == "mcap" else "bag_0.db3")
    os.mkfifo(fifo)
    outcome = run_limited(["follow", bag, "--quiet"], timeout=TIMEOUT)
    assert_one_line_error(outcome, str(fifo), "a FIFO, not a regular file")


# --- the rule, in process ---------------------------------------------------------------


def test_a_watched_file_cut_or_replaced_restarts_and_a_removed_one_keeps_its_size(
    tmp_path: Path,
) -> None:
    path = tmp_path / "run.mcap"
    path.write_bytes(b"x" * 100)
    watched = Watched(path)
    with path.open("ab") as grow:
        grow.write(b"y" * 20)
    assert watched.look() == 120
    with path.open("r+b") as cut:
        cut.truncate(50)
    with pytest.raises(FollowRestart, match=r"run.mcap was cut from 120 to 50 bytes"):
        watched.look()
    watched = Watched(path)
    other = tmp_path / "other.mcap"
    other.write_bytes(b"z" * 500)
    with (
        other.open("rb") as stream,
        pytest.raises(FollowRestart, match="replaced by another file"),
    ):
        watched.check_open(stream.fileno())
    other.replace(path)
    with pytest.raises(FollowRestart, match=r"run.mcap was replaced by another file"):
        watched.look()
    watched = Watched(path)
    path.unlink()
    assert watched.look() == 500  # gone (compressed by rosbag2): what was read stands


def test_a_watched_symlink_swapped_to_another_file_restarts(tmp_path: Path) -> None:
    (tmp_path / "a.mcap").write_bytes(b"a" * 10)
    (tmp_path / "b.mcap").write_bytes(b"b" * 10)
    link = tmp_path / "run.mcap"
    link.symlink_to("a.mcap")
    watched = Watched(link)
    assert watched.look() == 10
    swap = tmp_path / "swap.mcap"
    swap.symlink_to("b.mcap")
    swap.replace(link)
    with pytest.raises(FollowRestart, match="replaced by another file"):
        watched.look()


def test_a_fifo_is_never_watched(tmp_path: Path) -> None:
    fifo = tmp_path / "run.mcap"
    os.mkfifo(fifo)
    with pytest.raises(FileRefusedError, match="a FIFO, not a regular file"):
        Watched(fifo)


class ReplacedAtFirstWait(Follow):
    """A Follow whose first wait renames ``new`` over ``path`` (then waits as usual)."""

    def __init__(self, path: Path, new: Path) -> None:
        super().__init__(poll_s=POLL_MIN_S, idle_timeout_s=3)
        self.path, self.new = path, new

    def wait(self) -> None:
        if self.new.exists():
            self.new.replace(self.path)
        super().wait()


def test_a_db3_renamed_over_while_followed_restarts_the_replay(tmp_path: Path) -> None:
    # A WAL-mode database with its -wal beside it is read while written; renamed over, it is
    # never read at the old row ids: the replay ends with FollowRestart (follow starts again).
    run = write_bare(tmp_path / "run.db3", [diag(k * SECOND) for k in (1, 2, 3)])
    new = write_bare(tmp_path / "new.db3", [diag(k * SECOND, name="lidar") for k in (1, 2)])
    for db in (run, new):
        as_wal(db)
    (tmp_path / "run.db3-wal").touch()
    follow = ReplacedAtFirstWait(run, new)
    with pytest.raises(FollowRestart, match=r"run.db3 was replaced by another file"):
        replay([run], follow=follow)
    assert not new.exists()  # replaced after the first look, as the test means


# --- follow, against files changed under it ------------------------------------------------


class Lines:
    """A child's output stream read line by line in a thread, waited for with a timeout."""

    def __init__(self, stream: IO[str] | None) -> None:
        assert stream is not None
        self.lines: list[str] = []
        self._queue: queue.Queue[str] = queue.Queue()
        self._stream = stream
        self._pumping = threading.Thread(target=self._pump, args=(stream,), daemon=True)
        self._pumping.start()

    def _pump(self, stream: IO[str]) -> None:
        for line in stream:
            self._queue.put(line)

    def wait_for(self, needle: str) -> str:
        """The first line (from now on) holding ``needle``."""
        while True:
            line = self._queue.get(timeout=TIMEOUT)
            self.lines.append(line)
            if needle in line:
                return line

    def rest(self) -> str:
        """Every line not taken yet (call once the child ended); closes the stream."""
        self._pumping.join(TIMEOUT)
        self._stream.close()
        while not self._queue.empty():
            self.lines.append(self._queue.get())
        return "".join(self.lines)


def mission(path: Path, name: str, count: int = 20) -> Path:
    """A bare MCAP of ``count`` diagnostics, one chunk each (so a prefix holds messages)."""
    records = [diag(k * SECOND, name=name) for k in range(1, count + 1)]
    return write_bare(path, records, chunk_every=1)


def start_follow(recording: Path, report: Path) -> tuple[subprocess.Popen[str], Lines, Lines]:
    follower = subprocess.Popen(
        [sys.executable, "-m", "medkit_replay.cli", "follow", str(recording),
         "--json", str(report), "--poll", "0.05"],
        env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    return follower, Lines(follower.stdout), Lines(follower.stderr)


def finish(follower: subprocess.Popen[str], out: Lines, err: Lines) -> str:
    """Wait for the follower to end (status 0); its standard error."""
    status = follower.wait(timeout=TIMEOUT)
    out.rest()
    text = err.rest()
    assert status == 0, text
    return text


def analyzed(recording: Path, target: Path) -> dict[str, object]:
    outcome = run_limited(["analyze", recording, "--json", target, "--quiet"], timeout=TIMEOUT)
    assert outcome.status == 0, outcome.stderr
    report: dict[str, object] = json.loads(target.read_text())
    return report


def assert_report_of_the_new_file(
    tmp_path: Path, followed: Path, recording: Path, reason: str
) -> None:
    """The followed report is analyze's of what the path holds now, plus one warning."""
    data = json.loads(followed.read_text())
    warning = (
        f"{reason} while it was followed; this report is a replay of what the path held then, "
        "from its start"
    )
    assert warning in data["warnings"]
    data["warnings"].remove(warning)
    assert data == analyzed(recording, tmp_path / "analyzed.json")


def half_of(source: Path, target: Path) -> int:
    """Write the first half of ``source`` to ``target`` (a recording still being written)."""
    data = source.read_bytes()
    target.write_bytes(data[: len(data) // 2])
    return len(data) // 2


def test_a_bare_mcap_renamed_over_is_replayed_anew(tmp_path: Path) -> None:
    old = mission(tmp_path / "old.mcap", "motor")
    new = mission(tmp_path / "new.mcap", "lidar", count=7)
    run, report = tmp_path / "run.mcap", tmp_path / "followed.json"
    half_of(old, run)
    follower, out, err = start_follow(run, report)
    assert "MOTOR" in out.wait_for(" -> ")  # the old file is being read
    new.replace(run)
    line = err.wait_for("replaced")
    assert (
        line == f"medkit-replay: {run} was replaced by another file; replaying it from its start\n"
    )
    assert "LIDAR" in out.wait_for(" -> ")
    finish(follower, out, err)
    assert_report_of_the_new_file(tmp_path, report, run, f"{run} was replaced by another file")


def test_a_symlink_swapped_to_another_recording_is_replayed_anew(tmp_path: Path) -> None:
    old = mission(tmp_path / "old.mcap", "motor")
    new = mission(tmp_path / "new.mcap", "lidar", count=7)
    growing, report = tmp_path / "growing.mcap", tmp_path / "followed.json"
    half_of(old, growing)
    link = tmp_path / "latest.mcap"
    link.symlink_to(growing.name)
    follower, out, err = start_follow(link, report)
    out.wait_for(" -> ")
    swap = tmp_path / "swap.mcap"
    swap.symlink_to(new.name)
    swap.replace(link)
    err.wait_for("replaced")
    finish(follower, out, err)
    assert_report_of_the_new_file(tmp_path, report, link, f"{link} was replaced by another file")
    assert growing.stat().st_size < old.stat().st_size  # the old file was left as it was


def test_a_bare_mcap_cut_is_replayed_from_its_start(tmp_path: Path) -> None:
    whole = mission(tmp_path / "whole.mcap", "motor")
    run, report = tmp_path / "run.mcap", tmp_path / "followed.json"
    half = half_of(whole, run)
    follower, out, err = start_follow(run, report)
    out.wait_for(" -> ")
    with run.open("r+b") as cut:
        cut.truncate(half // 2)
    line = err.wait_for("was cut")
    assert f"{run} was cut from {half:,} to {half // 2:,} bytes; replaying it" in line
    with run.open("ab") as rest:  # the writer goes on: the recording ends as ``whole``
        rest.write(whole.read_bytes()[half // 2 :])
    finish(follower, out, err)
    reason = f"{run} was cut from {half:,} to {half // 2:,} bytes"
    assert_report_of_the_new_file(tmp_path, report, run, reason)


def test_a_split_file_renamed_over_in_a_bag_folder_is_replayed_anew(tmp_path: Path) -> None:
    old = write_bag(tmp_path / "old" / "bag", [diag(k * SECOND) for k in range(1, 21)],
                    chunk_every=1)  # fmt: skip
    new = write_bag(tmp_path / "new" / "bag", [diag(k * SECOND, name="lidar") for k in (1, 2)])
    bag, report = tmp_path / "bag", tmp_path / "followed.json"
    bag.mkdir()
    half_of(old / "bag.mcap", bag / "bag.mcap")
    follower, out, err = start_follow(bag, report)
    out.wait_for(" -> ")
    shutil.copy(new / "bag.mcap", tmp_path / "staged.mcap")
    (tmp_path / "staged.mcap").replace(bag / "bag.mcap")
    err.wait_for("replaced")
    shutil.copy(new / "metadata.yaml", bag / "metadata.yaml")
    finish(follower, out, err)
    reason = f"{bag / 'bag.mcap'} was replaced by another file"
    assert_report_of_the_new_file(tmp_path, report, bag, reason)
