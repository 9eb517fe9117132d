"""Builds ``examples/tuning_fleet/``: twelve JSON-lines missions with a known fault structure,
to tune a fault manager on (``sweep``) and to learn correlation rules from (``suggest-rules``).

Deterministic (seeded, no wall clock). Every mission lasts ten minutes and holds:

- a cascade: ``MOTOR_OVERHEAT`` confirms, then ``WHEEL_SLIP`` and ``ODOM_DRIFT`` confirm
  0.2-0.9 s later (in 9 of 12 missions; one more mission has a lone ``WHEEL_SLIP``);
- a burst: ``LIDAR_TIMEOUT``, ``CAMERA_STALL`` and ``IMU_DRIFT`` confirm within 0.3 s of each
  other, in random order (in 8 of 12 missions);
- an independent flapping code: ``WIFI_WEAK`` fails for a moment every 20-40 s and passes 1-4
  times in between, in every mission;
- each fault passes again 5-30 s after it confirmed (so healing settings matter).

It lives in ``examples/``, not beside the sample bags, so that ``fleet sample_bags`` still finds
the three sample recordings only.

Usage: ``python sample_bags/make_tuning_fleet.py [--out DIR]`` (default: ``examples/``).
"""

from __future__ import annotations

import argparse
import json
import random
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
FOLDER = "tuning_fleet"
NS = 1_000_000_000
MS = 1_000_000
T0_NS = 1_773_480_413 * NS
"""Mission time zero: 2026-03-14 09:26:53 UTC, as the sample bags."""
MISSIONS = 12
MISSION_S = 600
SEED = 20260314
PARAMS = """# The fault manager the tuning fleet was recorded with: confirm on the first FAILED,
# heal after 2 net PASSED (try other values with medkit-replay sweep).
fault_manager:
  ros__parameters:
    confirmation_threshold: -1
    healing_enabled: true
    healing_threshold: 2
"""
SOURCES = {
    "MOTOR_OVERHEAT": "/drive/motor_left",
    "WHEEL_SLIP": "/drive/odometry",
    "ODOM_DRIFT": "/localization/ekf",
    "LIDAR_TIMEOUT": "/sensors/lidar",
    "CAMERA_STALL": "/sensors/camera_front",
    "IMU_DRIFT": "/sensors/imu",
    "WIFI_WEAK": "/network/wifi",
}


def _report(t_ns: int, code: str, event: str, severity: int = 2) -> dict[str, object]:
    return {
        "t_ns": t_ns,
        "op": "report",
        "fault_code": code,
        "event_type": event,
        "severity": severity,
        "description": f"{code.lower().replace('_', ' ')} ({event.lower()})",
        "source_id": SOURCES[code],
    }


def _episode(rng: random.Random, t_ns: int, code: str, severity: int) -> list[dict[str, object]]:
    """A fault that fails twice, then passes 5-30 s later (three times)."""
    heal_ns = t_ns + rng.randint(5_000, 30_000) * MS
    return [
        _report(t_ns, code, "FAILED", severity),
        _report(t_ns + 500 * MS, code, "FAILED", severity),
        *(_report(heal_ns + i * NS, code, "PASSED") for i in range(3)),
    ]


def mission(index: int) -> list[dict[str, object]]:
    """One mission's requests, in time order."""
    rng = random.Random(SEED * 100 + index)
    requests: list[dict[str, object]] = []
    start = T0_NS + index * 3600 * NS
    if index % 4 != 3:  # 9 of 12
        root_ns = start + rng.randint(60, 400) * NS
        requests += _episode(rng, root_ns, "MOTOR_OVERHEAT", 3)
        for code in ("WHEEL_SLIP", "ODOM_DRIFT"):
            requests += _episode(rng, root_ns + rng.randint(200, 900) * MS, code, 2)
    elif index == 3:
        requests += _episode(rng, start + rng.randint(60, 400) * NS, "WHEEL_SLIP", 2)
    if index % 3 != 2:  # 8 of 12
        burst_ns = start + rng.randint(100, 500) * NS
        codes = ["LIDAR_TIMEOUT", "CAMERA_STALL", "IMU_DRIFT"]
        rng.shuffle(codes)
        for code in codes:
            requests += _episode(rng, burst_ns + rng.randint(0, 300) * MS, code, 2)
    t_ns = start + rng.randint(5, 30) * NS
    while t_ns < start + (MISSION_S - 45) * NS:
        requests.append(_report(t_ns, "WIFI_WEAK", "FAILED", 1))
        for step in range(rng.randint(1, 4)):
            requests.append(_report(t_ns + (step + 1) * 2 * NS, "WIFI_WEAK", "PASSED"))
        t_ns += rng.randint(20, 40) * NS
    requests.append(_report(start + MISSION_S * NS, "WIFI_WEAK", "PASSED"))
    return sorted(requests, key=lambda r: (r["t_ns"], str(r["fault_code"])))


def write_fleet(out: Path) -> list[Path]:
    """Write the missions and their parameter file under ``out/tuning_fleet``."""
    folder = out / FOLDER
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "params.yaml").write_text(PARAMS, encoding="utf-8")
    paths = []
    for index in range(MISSIONS):
        path = folder / f"mission_{index + 1:02d}.jsonl"
        lines = [json.dumps(r, separators=(",", ":")) for r in mission(index)]
        path.write_text("\n".join(lines) + "\n", encoding="utf-8")
        paths.append(path)
    return paths


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=EXAMPLES)
    args = parser.parse_args()
    for path in write_fleet(args.out):
        print(path)  # noqa: T201  # a script, not the package


if __name__ == "__main__":
    main()
