"""Benchmark: replay a generated JSON-lines script of N ReportFault/ClearFault requests.

Usage: python benchmarks/bench_engine.py [--requests 1000000] [--faults 500] [--out DIR]
Prints requests per second for parsing + replay, end to end through medkit_replay.replay().
"""

from __future__ import annotations

import argparse
import json
import random
import resource
import tempfile
import time
from pathlib import Path

from medkit_replay import replay

CORRELATION = """correlation:
  enabled: true
  patterns:
    motor: {codes: ["MOTOR_*"]}
    sensor: {codes: ["SENSOR_*"]}
  rules:
    - {id: estop, root_cause: {codes: ["ESTOP_*"]}, symptoms: [{pattern: motor}], window_ms: 2000}
    - {id: storm, mode: auto_cluster, match: [{pattern: sensor}], min_count: 3, window_ms: 1000}
"""
PARAMS = """fault_manager:
  ros__parameters:
    confirmation_threshold: -3
    healing_enabled: true
    healing_threshold: 3
    auto_confirm_after_sec: 5.0
    correlation: {config_file: correlation.yaml}
"""


def write_script(path: Path, requests: int, faults: int, seed: int) -> None:
    rng = random.Random(seed)
    prefixes = ["MOTOR", "SENSOR", "ESTOP", "NAV", "BATTERY"]
    codes = [f"{rng.choice(prefixes)}_{i:04d}" for i in range(faults)]
    sources = [f"/robot/node_{i}" for i in range(50)]
    t = 1_700_000_000_000_000_000
    with path.open("w") as out:
        for _ in range(requests):
            t += rng.randrange(0, 20_000_000)
            code = rng.choice(codes)
            roll = rng.random()
            if roll < 0.001:
                line = {"t_ns": t, "op": "clear", "fault_code": code}
            else:
                line = {
                    "t_ns": t,
                    "op": "report",
                    "fault_code": code,
                    "event_type": "FAILED" if roll < 0.6 else "PASSED",
                    "severity": rng.choice([0, 1, 2, 2, 3]),
                    "description": "value out of range",
                    "source_id": rng.choice(sources),
                }
            out.write(json.dumps(line) + "\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--requests", type=int, default=1_000_000)
    parser.add_argument("--faults", type=int, default=500)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = args.out or Path(tmp)
        root.mkdir(parents=True, exist_ok=True)
        script = root / "bench.jsonl"
        (root / "correlation.yaml").write_text(CORRELATION)
        (root / "params.yaml").write_text(PARAMS)
        write_script(script, args.requests, args.faults, args.seed)
        start = time.perf_counter()
        result = replay([script], [root / "params.yaml"])
        elapsed = time.perf_counter() - start
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(
        f"requests: {args.requests}  faults: {len(result.faults)}  "
        f"events: {len(result.events)}  transitions: {len(result.transitions)}"
    )
    print(
        f"replay: {elapsed:.1f} s  ({args.requests / elapsed:,.0f} requests/s), "
        f"peak RSS {peak_mb:.0f} MB"
    )


if __name__ == "__main__":
    main()
