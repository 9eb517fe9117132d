"""Benchmark: what evidence costs. ``analyze`` on the 10-minute mission three ways, each in a fresh
process under ``/usr/bin/time -v``: plain (log bridge on, no capture config), with a capture
config (freeze frames of /diagnostics and an action status topic, black box ``topics: all``)
listing the captures, and the same writing every recording with ``--evidence DIR``.

Usage:
    python benchmarks/bench_evidence.py [--mission DIR] [--out DIR] [--repeat 3]

``--mission`` is a rosbag2 folder made by bench_recording.py's ``mission_recording(root, 1,
600)``; without it the mission is generated under ``--out`` (or a temporary directory).
Each run is repeated and the fastest wall time (and its peak RSS) kept: other work on the
machine only ever slows a run down. Targets: ``--evidence`` within 1.5x of plain, memory flat.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_recording import mission_recording, time_binary

PLAIN = """medkit_replay:
  ros__parameters:
    enable_log_bridge: true
"""
CAPTURE = (
    PLAIN
    + """fault_manager:
  ros__parameters:
    snapshots:
      default_topics: [/diagnostics, /navigate_to_pose/_action/status]
      rosbag:
        enabled: true
        topics: all
"""
)


def run(bag: Path, config: Path, report: Path, extra: list[str]) -> tuple[float, float, int]:
    """Wall seconds, CPU seconds and peak RSS (kB) of one analyze in a fresh process."""
    command = [
        time_binary(),
        "-v",
        sys.executable,
        "-m",
        "medkit_replay.cli",
        "analyze",
        str(bag),
        "--quiet",
        "--json",
        str(report),
        "--config",
        str(config),
        *extra,
    ]
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise SystemExit(f"analyze failed ({done.returncode}):\n{done.stderr}")
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", done.stderr)
    wall = re.search(r"Elapsed \(wall clock\) time .*: (?:(\d+):)?(\d+):([\d.]+)", done.stderr)
    user = re.search(r"User time \(seconds\): ([\d.]+)", done.stderr)
    system = re.search(r"System time \(seconds\): ([\d.]+)", done.stderr)
    if rss is None or wall is None or user is None or system is None:
        raise SystemExit(f"unexpected /usr/bin/time output:\n{done.stderr}")
    hours, minutes, seconds = wall.groups()
    elapsed = int(hours or 0) * 3600 + int(minutes) * 60 + float(seconds)
    return elapsed, float(user[1]) + float(system[1]), int(rss[1])


def best(
    bag: Path, config: Path, report: Path, extra: list[str], repeat: int
) -> tuple[float, float, int]:
    """The fastest of ``repeat`` runs (wall), with the least CPU time and peak RSS seen."""
    runs = [run(bag, config, report, extra) for _ in range(repeat)]
    return min(r[0] for r in runs), min(r[1] for r in runs), max(r[2] for r in runs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mission", type=Path, default=None)
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    work = args.out or Path(tempfile.mkdtemp(prefix="bench_evidence_"))
    work.mkdir(parents=True, exist_ok=True)
    try:
        bag = args.mission or mission_recording(work, 1, 600)
        plain, capture = work / "plain.yaml", work / "capture.yaml"
        plain.write_text(PLAIN)
        capture.write_text(CAPTURE)
        evidence = work / "evidence"
        shutil.rmtree(evidence, ignore_errors=True)
        base = best(bag, plain, work / "plain.json", [], args.repeat)
        listed = best(bag, capture, work / "capture.json", [], args.repeat)
        written = best(
            bag, capture, work / "evidence.json", ["--evidence", str(evidence)], args.repeat
        )
        report = json.loads((work / "evidence.json").read_text())
        recordings = report["recordings"]
        size = sum(p.stat().st_size for p in evidence.rglob("*") if p.is_file())
        print(f"mission: {bag}")
        print(
            f"captures: {len(report['snapshots'])} freeze frames, {len(recordings)} recordings "
            f"({sum(r['messages'] for r in recordings):,} messages, {size / 1e6:.1f} MB written)"
        )
        for name, (wall, cpu, rss) in (
            ("plain analyze", base),
            ("with captures listed", listed),
            ("with --evidence", written),
        ):
            print(
                f"{name:>22}: {wall:6.2f} s wall ({wall / base[0]:.2f}x), {cpu:6.2f} s CPU "
                f"({cpu / base[1]:.2f}x), {rss / 1024:6.1f} MB peak RSS"
            )
        ratio = written[1] / base[1]
        verdict = "ok" if ratio <= 1.5 else "OVER"
        print(f"target --evidence <= 1.5x plain (CPU time): {ratio:.2f}x {verdict}")
    finally:
        if args.out is None:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
