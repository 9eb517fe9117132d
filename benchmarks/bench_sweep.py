"""Benchmark: a sweep of 24 fault-manager variants on the 10-minute mission against one analyze.

Usage:
    python benchmarks/bench_sweep.py [--out DIR] [--seed 1] [--repeat 3] [--jobs N]
    python benchmarks/bench_sweep.py --memory

The mission is ``bench_recording.mission_recording(root, seed, 600)`` (rosbag2, MCAP storage,
~0.9 GB, 15 Hz camera frames around the traffic the replay reads), written to ``--out DIR``
(kept and reused) or a temporary directory. Both commands run as CLIs in fresh processes with
the log bridge on (``medkit_replay: {enable_log_bridge: true}``), as bench_recording does:

- ``medkit-replay analyze MISSION --config PARAMS --quiet``;
- ``medkit-replay sweep MISSION --config PARAMS --quiet --out TMP`` over the grid
  ``confirmation_threshold=-1,-3,-5`` x ``healing_threshold=1,3,5,10`` x
  ``auto_confirm_after_sec=0.0,5.0`` with healing on: 24 variants, one bridge setting;
  with the default workers (one per CPU) and with ``--jobs 1``.

Each is run ``--repeat`` times, interleaved, and the fastest wall time kept (other work on the
machine only slows a run down); the target is sweep <= 4x analyze. CPU time (user + system) is
given for the commands that run in one process: on a loaded machine it is the steadier figure.

Memory mode (``--memory``) sweeps ``healing_threshold`` over 10 values on 10 of the tuning
fleet's missions (100 rows) and over 100 values on 100 missions (10,000 rows), writing the
tables, and prints the peak RSS of each (``/usr/bin/time``): flat means the second is close to
the first.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench_recording import PARAMS, mission_recording  # this script's folder is on sys.path

GRID = (
    "fault_manager.confirmation_threshold=-1,-3,-5",
    "fault_manager.healing_enabled=true",
    "fault_manager.healing_threshold=1,3,5,10",
    "fault_manager.auto_confirm_after_sec=0.0,5.0",
)
TARGET = 4.0


def timed(argv: list[str]) -> tuple[float, float]:
    """Wall seconds and CPU seconds (user + system, its worker processes included) of one
    command in a fresh process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(argv, check=True, stdout=subprocess.DEVNULL)
    elapsed = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    return elapsed, cpu


def memory() -> None:
    """Peak RSS of a 100-row and a 10,000-row sweep (tables written)."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from sample_bags.make_tuning_fleet import PARAMS as FLEET_PARAMS, mission  # noqa: PLC0415

    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        params = folder / "params.yaml"
        params.write_text(FLEET_PARAMS)
        scripts = []
        for index in range(100):
            path = folder / "missions" / f"run_{index:03d}.jsonl"
            path.parent.mkdir(exist_ok=True)
            path.write_text("\n".join(json.dumps(r) for r in mission(index % 12)) + "\n")
            scripts.append(str(path))
        for count in (10, 100):
            values = ",".join(str(v) for v in range(1, count + 1))
            argv = ["/usr/bin/time", "-f", "%e %M", sys.executable, "-m", "medkit_replay.cli"]
            argv += ["sweep", *scripts[:count], "--config", str(params), "--quiet"]
            argv += [f"--vary=fault_manager.healing_threshold={values}"]
            argv += ["--out", str(folder / f"tables{count}")]
            done = subprocess.run(argv, check=True, capture_output=True, text=True)
            seconds, kb = done.stderr.split()[-2:]
            rss = int(kb) / 1024
            print(f"{count * count:6,} rows: {float(seconds):6.2f} s, peak RSS {rss:.0f} MB")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--jobs", type=int, default=None, help="workers of the first sweep")
    parser.add_argument("--memory", action="store_true", help="peak RSS of 100 and 10,000 rows")
    args = parser.parse_args()
    if args.memory:
        memory()
        return
    with tempfile.TemporaryDirectory() as scratch:
        root = args.out if args.out is not None else Path(scratch)
        root.mkdir(parents=True, exist_ok=True)
        mission = mission_recording(root, args.seed, 600)
        params = Path(scratch) / "params.yaml"
        params.write_text(PARAMS)
        cli = [sys.executable, "-m", "medkit_replay.cli"]
        analyze = [*cli, "analyze", str(mission), "--config", str(params), "--quiet"]
        sweep = [*cli, "sweep", str(mission), "--config", str(params), "--quiet"]
        sweep += [f"--vary={spec}" for spec in GRID]
        sweep += ["--out", str(Path(scratch) / "tables")]
        default = sweep + ([f"--jobs={args.jobs}"] if args.jobs else [])
        commands = {"analyze": analyze, "sweep": default, "sweep --jobs 1": [*sweep, "--jobs=1"]}
        best: dict[str, float] = {}
        best_cpu: dict[str, float] = {}
        for round_ in range(args.repeat):
            for name, argv in commands.items():
                elapsed, cpu = timed(argv)
                best[name] = min(best.get(name, elapsed), elapsed)
                best_cpu[name] = min(best_cpu.get(name, cpu), cpu)
                print(f"round {round_ + 1}: {name:15} {elapsed:6.2f} s ({cpu:.2f} s CPU)")
        load = os.getloadavg()[0]
        print(f"\nbest of {args.repeat} (1-minute load {load:.1f}, {os.cpu_count()} CPUs):")
        for name, seconds in best.items():
            ratio = seconds / best["analyze"]
            cpu_ratio = best_cpu[name] / best_cpu["analyze"]
            # A pool's workers are the forkserver's children: their CPU is not counted here.
            in_process = name != "sweep" or args.jobs == 1
            cpu = f"{best_cpu[name]:6.2f} s CPU" if in_process else "(workers' CPU not counted)"
            line = f"  {name:15} {seconds:6.2f} s wall, {cpu}"
            if name != "analyze":
                met = "met" if ratio <= TARGET else "NOT met"
                line += f"  {ratio:.2f}x analyze (target <= {TARGET:g}x: {met})"
                line += f", CPU {cpu_ratio:.2f}x" if in_process else ""
            print(line, flush=True)
        rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
        print(f"  peak RSS of any process: {rss / 1024:.0f} MB")


if __name__ == "__main__":
    main()
