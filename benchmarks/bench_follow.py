"""Following a recording while it is written: CPU of ``medkit-replay follow`` and how soon it ends.

A writer thread writes the recording (an MCAP folder relayed byte range by byte range at a chosen
rate, or an sqlite3 bag in WAL mode written with rosbags); ``follow`` runs as its own process.
Prints its CPU time, how long after the writer it said the recording was finished, and whether
its JSON report is analyze's on the finished recording, byte for byte.

    PYTHONPATH=$PWD python benchmarks/bench_follow.py --mcap MISSION_FOLDER --rate 10
    PYTHONPATH=$PWD python benchmarks/bench_follow.py --sqlite-seconds 30
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import yaml
from rosbags.rosbag2 import Writer
from rosbags.rosbag2.enums import StoragePlugin

from sample_bags.make_sample_bags import definition
from tests.inputs.builders import TS, Rec, diag, string_msg

ROOT = Path(__file__).resolve().parents[1]
STEP = 1 << 20


def relay_mcap(source: Path, target: Path, rate: float) -> None:
    """Copy a finished rosbag2 MCAP folder at ``rate`` times its real time, then metadata.yaml."""
    info = yaml.safe_load((source / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    files = sorted(p for p in source.iterdir() if p.suffix == ".mcap")
    total = sum(p.stat().st_size for p in files)
    seconds = info["duration"]["nanoseconds"] / 1e9 / rate
    pause = seconds * STEP / total
    target.mkdir()
    for path in files:
        with path.open("rb") as stream, (target / path.name).open("wb") as sink:
            while block := stream.read(STEP):
                sink.write(block)
                sink.flush()
                time.sleep(pause)
    shutil.copyfile(source / "metadata.yaml", target / "metadata.yaml")


def write_sqlite(target: Path, seconds: float) -> None:
    """10 Hz diagnostics with 5 s fault episodes and 10 Hz 300 kB blobs, one commit each 0.1 s."""
    writer = Writer(target, version=9, storage_plugin=StoragePlugin.SQLITE3)
    writer.open()
    conn = writer.storage.conn  # type: ignore[union-attr]
    conn.commit()
    conn.execute("PRAGMA journal_mode=WAL")
    connections: dict[tuple[str, str], object] = {}

    def put(rec: Rec) -> None:
        key = (rec.topic, rec.msgtype)
        if key not in connections:
            connections[key] = writer.add_connection(
                rec.topic,
                rec.msgtype,
                msgdef=definition(rec.msgtype),
                rihs01=TS.hash_rihs01(rec.msgtype),
            )
        data = bytes(TS.serialize_cdr(rec.msg, rec.msgtype))
        writer.write(connections[key], rec.t_ns, data)  # type: ignore[arg-type]

    start, blob = 1_773_480_413 * 10**9, "x" * 300_000
    for k in range(int(seconds * 10)):
        t_ns, hot = start + k * 100_000_000, bool((k // 50) % 2)
        put(diag(t_ns, level=2 if hot else 0, message="hot" if hot else "ok"))
        put(string_msg(t_ns + 1, topic="/camera", text=blob))
        conn.commit()
        time.sleep(0.1)
    writer.close()


def run(target: Path, write: threading.Thread, out: Path) -> None:
    followed, analyzed = out / "followed.json", out / "analyzed.json"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    command = [sys.executable, "-m", "medkit_replay.cli"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    follower = subprocess.Popen(
        [*command, "follow", str(target), "--json", str(followed), "--quiet"],
        env=env,
        stderr=subprocess.PIPE,
        text=True,
    )
    write.start()
    finished_at = None
    assert follower.stderr is not None
    for line in follower.stderr:
        if "the recording is finished" in line:
            finished_at = time.monotonic()
    follower.wait()
    write.join()
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    writer_done = getattr(write, "done_at", None)
    subprocess.run(
        [*command, "analyze", str(target), "--json", str(analyzed), "--quiet"], env=env, check=True
    )
    size = sum(p.stat().st_size for p in target.iterdir())
    print(f"recording: {size / 1e6:.1f} MB; follow CPU {cpu:.2f} s (user + system)")
    if finished_at is not None and writer_done is not None:
        print(f"'the recording is finished' {finished_at - writer_done:+.2f} s after the writer")
    same = followed.read_bytes() == analyzed.read_bytes()
    print(f"report equals analyze's on the finished recording: {same}")


class _Timed(threading.Thread):
    def run(self) -> None:
        super().run()
        self.done_at = time.monotonic()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mcap", type=Path, help="a finished rosbag2 MCAP folder to relay")
    parser.add_argument("--rate", type=float, default=10.0, help="times real time (--mcap)")
    parser.add_argument("--sqlite-seconds", type=float, help="write an sqlite3 bag this long")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-follow-") as tmp:
        out = Path(tmp)
        target = out / "bag"
        if args.mcap is not None:
            write = _Timed(target=relay_mcap, args=(args.mcap, target, args.rate))
        elif args.sqlite_seconds is not None:
            write = _Timed(target=write_sqlite, args=(target, args.sqlite_seconds))
        else:
            parser.error("--mcap or --sqlite-seconds")
        run(target, write, out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
