"""Red team, ``analyze --evidence DIR``: the folder never overlaps what the run reads, nothing
there is replaced but a clip carrying this tool's marker, a failed write leaves nothing behind, and
two recordings of one name get folders of their own.
"""

from __future__ import annotations

import errno
import hashlib
import json
import os
import shutil
import sqlite3
from typing import TYPE_CHECKING

import pytest
from rosbags.rosbag2 import Reader, Writer

from medkit_replay.cli import main
from medkit_replay.errors import MedkitReplayError
from medkit_replay.evidence import EvidenceOptions
from medkit_replay.evidence.folder import MARKER
from medkit_replay.pipeline import replay
from tests.evidence.robot import Robot, at, odometry, write_config, write_robot
from tests.redteam.support import assert_one_line_error, run_limited

if TYPE_CHECKING:
    from pathlib import Path

KEPT = "fault_MOTOR_OVERCURRENT_1700000025000"
"""A clip every run of the robot writes (the 25 s confirmation, kept by the live manager)."""
BATTERY = "fault_LOG_BATTERY_MONITOR_9b912133_1700000015020"
SAME_MS = "fault_MOTOR_OVERCURRENT_1700000010000"


def snapshot(root: Path) -> dict[str, str]:
    """Every entry under ``root``: a file's SHA-256, a link's target, or ``dir``."""
    found: dict[str, str] = {}
    for path in sorted(root.rglob("*")):
        name = str(path.relative_to(root))
        if path.is_symlink():
            found[name] = f"-> {path.readlink()}"
        elif path.is_dir():
            found[name] = "dir"
        else:
            found[name] = hashlib.sha256(path.read_bytes()).hexdigest()
    return found


def analyze(robot: Robot, config: Path, evidence: Path, *extra: str | Path) -> list[str | Path]:
    """The arguments of an analysis of the robot's bag and script writing clips to ``evidence``."""
    return [
        "analyze",
        robot.bag,
        robot.script,
        "--config",
        config,
        "--evidence",
        evidence,
        "--quiet",
        *extra,
    ]


@pytest.fixture
def robot(tmp_path: Path) -> tuple[Robot, Path]:
    """The generated robot recording, its script, graph and capture config under tmp_path."""
    return write_robot(tmp_path), write_config(tmp_path)


def _clips(tmp_path: Path, robot: Robot, config: Path) -> Path:
    """A first run's clips, in ``tmp_path / clips``."""
    clips = tmp_path / "clips"
    assert main([str(a) for a in analyze(robot, config, clips)]) == 0
    assert (clips / KEPT / MARKER).is_file()
    return clips


# --- the evidence folder never overlaps what the run reads -------------------------------------


@pytest.mark.parametrize("given", ["folder", "storage file", "metadata.yaml"])
def test_re_analysing_a_clip_into_its_own_folder_is_refused(
    tmp_path: Path, robot: tuple[Robot, Path], given: str
) -> None:
    """The issue's first case: a clip of an earlier run, analysed with ``--evidence`` naming the
    folder that holds it, was replaced by a 7-message clip of itself."""
    bot, config = robot
    clips = _clips(tmp_path, bot, config)
    clip = clips / KEPT
    source = {
        "folder": clip,
        "storage file": clip / f"{KEPT}_0.mcap",
        "metadata.yaml": clip / "metadata.yaml",
    }[given]
    before = snapshot(clips)
    out = tmp_path / "again.json"
    outcome = run_limited(
        ["analyze", source, "--config", config, "--evidence", clips, "--json", out]
    )
    line = assert_one_line_error(outcome, str(clips), "holds", "write the clips to another folder")
    assert str(source) in line
    assert snapshot(clips) == before
    assert not out.exists()  # refused before the replay


def test_an_input_file_inside_the_evidence_folder_is_refused(
    tmp_path: Path, robot: tuple[Robot, Path]
) -> None:
    bot, config = robot
    clips = tmp_path / "clips"
    clips.mkdir()
    script = clips / "requests.jsonl"
    shutil.move(bot.script, script)
    before = snapshot(clips)
    moved = Robot(bot.bag, script, bot.graph)
    outcome = run_limited(analyze(moved, config, clips))
    assert_one_line_error(outcome, "--evidence folder holds", "requests.jsonl")
    assert snapshot(clips) == before


@pytest.mark.parametrize("inside", ["clips", "a/b"])
def test_the_evidence_folder_inside_an_input_folder_is_refused(
    tmp_path: Path, robot: tuple[Robot, Path], inside: str
) -> None:
    bot, config = robot
    before = snapshot(bot.bag)
    outcome = run_limited(analyze(bot, config, bot.bag / inside))
    assert_one_line_error(outcome, "--evidence folder is inside", str(bot.bag))
    assert snapshot(bot.bag) == before


def test_the_evidence_folder_on_an_input_folder_is_refused(
    tmp_path: Path, robot: tuple[Robot, Path]
) -> None:
    bot, config = robot
    before = snapshot(tmp_path)
    outcome = run_limited(analyze(bot, config, bot.bag))
    assert_one_line_error(outcome, "--evidence folder is", str(bot.bag))
    assert snapshot(tmp_path) == before


@pytest.mark.parametrize("held", ["config", "snapshot file", "graph", "linked config folder"])
def test_the_evidence_folder_on_a_config_or_the_graph_is_refused(
    tmp_path: Path, robot: tuple[Robot, Path], held: str
) -> None:
    """A config, the snapshot file it names (only the config knows it) and the node graph are
    read like the inputs; a link to their folder is seen through."""
    bot, config = robot
    conf, snaps, graphs = tmp_path / "conf", tmp_path / "snaps", tmp_path / "graphs"
    for folder in (conf, snaps, graphs):
        folder.mkdir()
    moved = conf / "capture.yaml"
    text = config.read_text().replace("config_file: snapshots.yaml", "config_file: ../snaps/s.yaml")
    moved.write_text(text)
    shutil.move(tmp_path / "snapshots.yaml", snaps / "s.yaml")
    shutil.move(bot.graph, graphs / "graph.txt")
    (tmp_path / "link").symlink_to(conf, target_is_directory=True)
    evidence = {
        "config": conf,
        "snapshot file": snaps,
        "graph": graphs,
        "linked config folder": tmp_path / "link",
    }[held]
    named = {"config": "capture.yaml", "snapshot file": "s.yaml", "graph": "graph.txt"}
    before = snapshot(tmp_path)
    argv = analyze(bot, moved, evidence, "--graph", graphs / "graph.txt")
    outcome = run_limited(argv)
    assert_one_line_error(outcome, "--evidence folder holds", named.get(held, "capture.yaml"))
    assert snapshot(tmp_path) == before


def test_the_python_api_refuses_an_evidence_folder_inside_an_input(
    robot: tuple[Robot, Path],
) -> None:
    """``replay`` checks the inputs itself before it writes a clip (the command checks earlier)."""
    bot, config = robot
    before = snapshot(bot.bag)
    with pytest.raises(MedkitReplayError, match="is inside"):
        replay([bot.bag, bot.script], [config], evidence=EvidenceOptions(directory=bot.bag / "x"))
    assert snapshot(bot.bag) == before


# --- nothing is replaced but a clip of ours ----------------------------------------------------


def _robot_black_box(clips: Path, name: str) -> None:
    """The robot's own recording, as upstream names it, with a user's notes beside it."""
    folder = clips / name
    folder.mkdir(parents=True)
    (folder / "metadata.yaml").write_text("rosbag2_bagfile_information:\n  version: 9\n")
    (folder / f"{name}_0.mcap").write_bytes(b"\x89MCAP0\r\n" + bytes(range(256)) * 64)
    (clips / "NOTES.txt").write_text("motor trip on the ramp, keep these\n")


def _not_ours(clips: Path, what: str, outside: Path) -> None:
    """Something under the kept clip's name in ``clips`` that this tool did not write."""
    if what == "the robot's black box":
        _robot_black_box(clips, KEPT)
    elif what == "a plain file":
        clips.mkdir(parents=True)
        (clips / KEPT).write_text("not a folder\n")
    elif what == "a clip whose marker was removed":
        shutil.copytree(outside / KEPT, clips / KEPT)
        (clips / KEPT / MARKER).unlink()
    elif what == "a link to a clip of ours":
        clips.mkdir(parents=True)
        (clips / KEPT).symlink_to(outside / KEPT, target_is_directory=True)
    elif what == "a folder with a marker that is a link":
        _robot_black_box(clips, KEPT)
        (clips / KEPT / MARKER).symlink_to(outside / KEPT / MARKER)
    else:
        raise AssertionError(what)


@pytest.mark.parametrize(
    "what",
    [
        "the robot's black box",
        "a plain file",
        "a clip whose marker was removed",
        "a link to a clip of ours",
        "a folder with a marker that is a link",
    ],
)
def test_anything_else_under_a_clips_name_is_left_alone(
    tmp_path: Path, robot: tuple[Robot, Path], what: str
) -> None:
    """The issue's second case: the robot's own ``fault_<CODE>_<ms>/`` (and its neighbour
    NOTES.txt) went. Now no clip is written, one line names the folder, the exit is 2, and the
    other outputs are written, the JSON report byte for byte the one a clean folder gives."""
    bot, config = robot
    clips = tmp_path / "clips"
    outputs = ("--json", tmp_path / "r.json", "--html", tmp_path / "r.html")
    clean = run_limited(analyze(bot, config, clips, *outputs))
    assert clean.status == 0, clean.stderr
    reference = (tmp_path / "r.json").read_bytes()
    earlier = tmp_path / "earlier"
    clips.rename(earlier)
    (tmp_path / "r.json").unlink()
    (tmp_path / "r.html").unlink()
    _not_ours(clips, what, earlier)
    before, beside = snapshot(clips), snapshot(earlier)
    outcome = run_limited(analyze(bot, config, clips, *outputs))
    assert_one_line_error(outcome, str(clips / KEPT), "not a clip this tool wrote", MARKER)
    assert snapshot(clips) == before  # nothing written, nothing removed, no staging left
    assert snapshot(earlier) == beside
    assert (tmp_path / "r.json").read_bytes() == reference
    assert (tmp_path / "r.html").stat().st_size > 0


def test_a_previous_clip_of_ours_is_replaced(tmp_path: Path, robot: tuple[Robot, Path]) -> None:
    """A clip carrying the marker is replaced whole by the next run, and stays a bag that rosbags
    reads (the marker is not among its files)."""
    bot, config = robot
    clips = _clips(tmp_path, bot, config)
    first = snapshot(clips)
    (clips / KEPT / "stale.txt").write_text("left by hand\n")
    (clips / "NOTES.txt").write_text("mine\n")
    assert main([str(a) for a in analyze(bot, config, clips)]) == 0
    assert snapshot(clips) == {**first, "NOTES.txt": snapshot(clips)["NOTES.txt"]}
    assert (clips / "NOTES.txt").read_text() == "mine\n"
    listed = (clips / KEPT / "metadata.yaml").read_text()
    assert MARKER not in listed
    with Reader(clips / KEPT) as reader:
        assert reader.message_count == sum(1 for _ in reader.messages()) > 0
    assert not list(clips.glob(".medkit-replay-partial*"))


def test_a_linked_staging_folder_leads_nowhere(tmp_path: Path, robot: tuple[Robot, Path]) -> None:
    """``DIR/.medkit-replay-partial`` (where clips were staged before) a link to another folder:
    staging is a new folder of its own, so nothing there is followed or deleted."""
    bot, config = robot
    clips, victim = tmp_path / "clips", tmp_path / "victim"
    (victim / KEPT).mkdir(parents=True)
    (victim / KEPT / "metadata.yaml").write_text("precious\n")
    (victim / "precious.txt").write_text("precious\n")
    clips.mkdir()
    (clips / ".medkit-replay-partial").symlink_to(victim, target_is_directory=True)
    before = snapshot(victim)
    assert main([str(a) for a in analyze(bot, config, clips)]) == 0
    assert snapshot(victim) == before
    assert (clips / ".medkit-replay-partial").readlink() == victim
    assert sorted(p.name for p in clips.iterdir()) == [".medkit-replay-partial", BATTERY, KEPT]


def test_an_evidence_folder_that_cannot_be_made_is_one_line(
    tmp_path: Path, robot: tuple[Robot, Path]
) -> None:
    bot, config = robot
    (tmp_path / "a_file").write_text("x\n")
    outcome = run_limited(analyze(bot, config, tmp_path / "a_file" / "clips"))
    assert_one_line_error(outcome, "cannot write in the evidence folder", "Not a directory")
    assert (tmp_path / "a_file").read_text() == "x\n"


# --- a failed write leaves nothing behind ------------------------------------------------------


@pytest.mark.parametrize(
    ("fmt", "error", "said"),
    [
        ("mcap", OSError(errno.ENOSPC, os.strerror(errno.ENOSPC)), "No space left on device"),
        ("sqlite3", sqlite3.OperationalError("database or disk is full"), "disk is full"),
    ],
)
def test_a_full_disk_at_the_writers_close_leaves_nothing(
    tmp_path: Path,
    robot: tuple[Robot, Path],
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    fmt: str,
    error: Exception,
    said: str,
) -> None:
    """The issue's third case: a full disk is met when the writer closes (the file's index and
    metadata are written then), outside the clean-up that covered the writes. The failure is
    injected at rosbags' close, as the disk would raise it there."""
    bot, _ = robot
    config = write_config(tmp_path, fmt)
    clips = tmp_path / "clips"
    closed = Writer.close

    def full(self: Writer) -> None:
        closed(self)  # the file is written, as far as a full disk lets it
        raise error

    monkeypatch.setattr(Writer, "close", full)
    assert main([str(a) for a in analyze(bot, config, clips)]) == 2
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert len(lines) == 1 and "Traceback" not in err and "internal error" not in err, err
    assert "cannot write recording" in lines[0] and said in lines[0], lines[0]
    assert list(clips.iterdir()) == []  # no clip, no staging folder


def test_a_real_file_size_limit_while_writing_clips_leaves_nothing(
    tmp_path: Path, robot: tuple[Robot, Path]
) -> None:
    """A file-size limit (RLIMIT_FSIZE, a full disk for one file) met while a clip is written."""
    bot, config = robot
    clips = tmp_path / "clips"
    outcome = run_limited(analyze(bot, config, clips), file_size=64 * 1024)
    assert_one_line_error(outcome, "cannot write recording", "no part of it was left")
    assert list(clips.iterdir()) == []


# --- recordings of one name ---------------------------------------------------------------------


def test_recordings_in_the_same_millisecond_get_folders_of_their_own(
    tmp_path: Path,
) -> None:
    """Confirmed, cleared and confirmed again within one millisecond: two recordings named
    ``fault_<CODE>_<ms>`` (upstream's recording_id, kept), written to two folders, the second
    ``-2``, the same on every run; each folder holds its own recording."""
    extra = [("/odom", "nav_msgs/msg/Odometry", at(10) + 150, odometry(at(10) + 150, 1.0))]
    bot = write_robot(tmp_path, extra=extra)
    config = write_config(tmp_path)
    settings = "        duration_after_sec: 0.0\n        auto_cleanup: false\n"
    config.write_text(
        config.read_text().replace("        topics: all\n", "        topics: all\n" + settings)
    )
    failed = {"op": "report", "fault_code": "MOTOR_OVERCURRENT", "event_type": "FAILED"}
    lines = [
        {"t_ns": at(10), **failed, "severity": 2, "source_id": "/motor_driver"},
        {"t_ns": at(10) + 100, "op": "clear", "fault_code": "MOTOR_OVERCURRENT"},
        {"t_ns": at(10) + 200, **failed, "severity": 2, "source_id": "/motor_driver"},
    ]
    script = tmp_path / "same_ms.jsonl"
    script.write_text("".join(json.dumps(line) + "\n" for line in lines))
    clips, out = tmp_path / "clips", tmp_path / "r.json"
    argv = [str(a) for a in analyze(Robot(bot.bag, script, bot.graph), config, clips)]
    argv += ["--json", str(out), "--evidence-all"]
    assert main(argv) == 0
    first = out.read_bytes()
    recordings = json.loads(first)["recordings"]
    same = [r for r in recordings if r["recording_id"] == SAME_MS]
    assert [r["path"] for r in same] == [str(clips / SAME_MS), str(clips / f"{SAME_MS}-2")]
    for recording in same:
        with Reader(recording["path"]) as reader:
            times = [t for _, t, _ in reader.messages()]
        assert len(times) == recording["messages"]
        assert all(recording["start_ns"] <= t <= recording["end_ns"] for t in times)
    assert same[1]["messages"] == 1  # the /odom message between the two confirmations
    assert main(argv) == 0  # again, over the first run's clips
    assert out.read_bytes() == first
    assert sorted(p.name for p in clips.iterdir()) == sorted([BATTERY, SAME_MS, f"{SAME_MS}-2"])
