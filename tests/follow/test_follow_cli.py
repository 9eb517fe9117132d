"""``medkit-replay follow`` against a writer process appending a recording in real time.

The final report must be analyze's on the finished recording, byte for byte; lines print while
the writer still writes; the writer's files are left as it leaves them (no -wal/-shm of ours).
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import IO

import pytest

import medkit_replay
from medkit_replay.cli import main
from medkit_replay.outputs.times import start_text
from medkit_replay.pipeline import replay

PACKAGE_ROOT = Path(medkit_replay.__file__).resolve().parents[1]
WRITER = Path(__file__).with_name("live_writer.py")
ENV = {**os.environ, "PYTHONPATH": str(PACKAGE_ROOT)}
TIMEOUT = 120


def start_writer(out: Path, *args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, str(WRITER), str(out), *args],
        env=ENV,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def start_follow(recording: Path, *args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "medkit_replay.cli", "follow", str(recording), *args],
        env=ENV,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def first_line(stream: IO[str] | None) -> str:
    assert stream is not None
    return stream.readline()


def finish(process: subprocess.Popen[str]) -> tuple[str, str]:
    out, err = process.communicate(timeout=TIMEOUT)
    assert process.returncode == 0, err
    return out, err


def analyze_json(recording: Path, target: Path) -> bytes:
    assert main(["analyze", str(recording), "--json", str(target), "--quiet"]) == 0
    return target.read_bytes()


def follow_and_compare(tmp_path: Path, recording: Path, writer_args: list[str]) -> str:
    """Follow while the writer writes; returns the live lines. Checks the bytes and the files."""
    followed = tmp_path / "followed.json"
    follower = start_follow(recording, "--json", str(followed), "--poll", "0.05")
    assert first_line(follower.stderr).startswith(f"waiting for {recording} to appear")
    writer = start_writer(recording, *writer_args)
    header = first_line(follower.stdout)
    line = first_line(follower.stdout)
    assert writer.poll() is None, "the first line came only after the writer had finished"
    assert " -> " in line or " event " in line
    assert re.match(r"\d+\.\d{3} s \d\d:\d\d:\d\d\.\d{3}  ", line), line  # s from start, UTC
    rest, err = finish(follower)
    _, writer_err = finish(writer)
    assert "locked" not in writer_err.lower()
    assert "the recording is finished" in err
    analyzed = analyze_json(recording, tmp_path / "analyzed.json")
    assert followed.read_bytes() == analyzed
    start_ns = json.loads(analyzed)["summary"]["start_ns"]
    assert header == f"recording starts {start_text(start_ns)}: times are s from the start; " + (
        "then the time of day, UTC\n"
    )
    return line + rest


def test_growing_mcap_from_rosbags_writer(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    lines = follow_and_compare(
        tmp_path, bag, ["--storage", "mcap", "--batches", "15", "--delay", "0.15"]
    )
    assert "LOCALIZATION_POSE_CONFIDENCE  - -> CONFIRMED  (report, source /diagnostic_bridge)" in (
        lines
    )
    assert sorted(p.name for p in bag.iterdir()) == ["bag.mcap", "metadata.yaml"]


def test_sqlite3_in_wal_mode_while_written(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    # A WAL restarted every few pages: the copy must follow the writer's checkpoints too.
    follow_and_compare(
        tmp_path,
        bag,
        ["--storage", "sqlite3", "--batches", "15", "--delay", "0.15", "--wal-pages", "8"],
    )
    # The writer could checkpoint and remove its -wal and -shm: we held nothing open on them.
    assert sorted(p.name for p in bag.iterdir()) == ["bag.db3", "metadata.yaml"]


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_metadata_written_before_the_file_is_closed(tmp_path: Path, storage: str) -> None:
    # rosbag2 writes metadata.yaml, then closes the storage (last chunk, footer, last commit).
    bag = tmp_path / "bag"
    follow_and_compare(
        tmp_path,
        bag,
        ["--storage", storage, "--batches", "8", "--delay", "0.2", "--metadata-first"],
    )


def test_split_sqlite3_files_in_wal_mode(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    args = ["--mode", "split-sqlite", "--parts", "2", "--batches", "8", "--delay", "0.15"]
    follow_and_compare(tmp_path, bag, args)
    assert sorted(p.name for p in bag.iterdir()) == ["bag_0.db3", "bag_1.db3", "metadata.yaml"]


def test_split_files_appearing_with_torn_tails(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    follow_and_compare(
        tmp_path, bag, ["--mode", "relay", "--parts", "3", "--step", "4099", "--delay", "0.03"]
    )
    assert sorted(p.name for p in bag.iterdir()) == [
        "bag_0.mcap",
        "bag_1.mcap",
        "bag_2.mcap",
        "metadata.yaml",
    ]


@pytest.mark.parametrize(("cut", "torn"), [(3000, False), (30011, True)])
def test_a_finished_recording_with_a_torn_tail_is_damaged_as_for_analyze(
    tmp_path: Path, cut: int, torn: bool
) -> None:
    # The recorder died: the last file lacks its footer and summary (3000 bytes), or also the
    # end of its data (a record cut off). Once metadata.yaml is there, that is damage.
    bag = tmp_path / "bag"
    args = ["--mode", "relay", "--parts", "2", "--step", "4099", "--delay", "0.04"]
    follow_and_compare(tmp_path, bag, [*args, "--cut", str(cut)])
    report = json.loads((tmp_path / "followed.json").read_text())
    assert any("bag_1.mcap: no footer" in w for w in report["warnings"])
    assert any("file ends inside" in w for w in report["warnings"]) is torn


def test_bare_mcap_ends_at_its_footer(tmp_path: Path) -> None:
    target = tmp_path / "run.mcap"
    follow_and_compare(
        tmp_path,
        target,
        ["--mode", "relay", "--parts", "1", "--step", "2053", "--delay", "0.02"],
    )


def test_recorded_report_fault_calls_are_learnt_live(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    follow_and_compare(
        tmp_path,
        bag,
        ["--mode", "relay", "--records", "services", "--parts", "1", "--step", "509",
         "--delay", "0.08"],
    )  # fmt: skip


def test_ctrl_c_writes_what_was_read(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    writer = start_writer(
        bag, "--mode", "relay", "--parts", "1", "--step", "997", "--delay", "0.05", "--unfinished"
    )
    report = tmp_path / "partial.json"
    follower = start_follow(bag, "--json", str(report), "--poll", "0.05")
    first_line(follower.stdout)
    follower.send_signal(signal.SIGINT)
    _, err = finish(follower)
    writer.kill()
    writer.communicate()
    assert "following stopped (interrupted by SIGINT)" in err
    data = json.loads(report.read_text())
    assert any("following stopped (interrupted by SIGINT)" in w for w in data["warnings"])
    assert data["summary"]["transitions"] >= 1
    whole = replay([PACKAGE_ROOT / "sample_bags" / "nav2_mission_mcap"]).summary.messages_read
    assert 0 < data["summary"]["messages_read"] < whole


def test_sigterm_and_a_recording_that_never_finishes(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    writer = start_writer(
        bag, "--mode", "relay", "--parts", "1", "--step", "65536", "--delay", "0", "--unfinished"
    )
    finish(writer)
    report = tmp_path / "report.json"
    follower = start_follow(bag, "--json", str(report), "--quiet")
    assert first_line(follower.stderr).startswith("following ")
    time.sleep(1.5)
    assert follower.poll() is None, "a recording without metadata.yaml is followed on"
    follower.send_signal(signal.SIGTERM)
    _, err = finish(follower)
    assert "interrupted by SIGTERM" in err
    data = json.loads(report.read_text())
    full = json.loads(analyze_json(bag, tmp_path / "analyzed.json"))
    assert data["summary"]["messages_read"] == full["summary"]["messages_read"]
    assert data["faults"] == full["faults"]


def test_idle_timeout_ends_the_following(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    writer = start_writer(
        bag, "--mode", "relay", "--parts", "1", "--step", "65536", "--delay", "0", "--unfinished"
    )
    finish(writer)
    report = tmp_path / "report.json"
    started = time.monotonic()
    follower = start_follow(bag, "--json", str(report), "--quiet", "--idle-timeout", "1")
    _, err = finish(follower)
    assert time.monotonic() - started < 30
    assert "nothing new for 1 s" in err
    assert any("nothing new for 1 s" in w for w in json.loads(report.read_text())["warnings"])


@pytest.mark.parametrize("poll", ["0.01", "6"])
def test_poll_interval_is_bounded(tmp_path: Path, poll: str) -> None:
    bag = tmp_path / "bag"
    bag.mkdir()
    assert main(["follow", str(bag), "--poll", poll]) == 2
