"""Fleets written in tmp_path: JSON-lines missions, copies of the sample bags, tiny written bags,
and recordings that cannot be replayed.

Deterministic: missions come from seeded random generators, bags are copies or written by
rosbags' Writer from fixed messages.
"""

from __future__ import annotations

import json
import random
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from tests.inputs.builders import Rec, diag, write_bag, write_bare

if TYPE_CHECKING:
    from collections.abc import Iterable

ROOT = Path(__file__).resolve().parents[2]
SAMPLES = ROOT / "sample_bags"
FIXTURES = ROOT / "tests" / "fixtures" / "rosbag2"
BRINGUP = ROOT / "rules" / "bringup" / "fault_manager.yaml"
"""Confirm on the first FAILED, heal after 3 net PASSED (4 PASSED after one FAILED), no
correlation: the config the crafted runs' numbers assume."""
NAV2 = ROOT / "rules" / "nav2" / "fault_manager.yaml"
SEC = 1_000_000_000
CODES = (
    "MOTOR_OVERHEAT",
    "LIDAR_TIMEOUT",
    "BATTERY_LOW",
    "WIFI_WEAK",
    "CAMERA_STALL",
    "IMU_DRIFT",
    "ESTOP_PRESSED",
)


def report(t_s: float, code: str, event: str = "FAILED", severity: int = 2) -> str:
    """One ``report`` line of a script (times in seconds, written as integer nanoseconds)."""
    return json.dumps(
        {
            "t_ns": round(t_s * SEC),
            "op": "report",
            "fault_code": code,
            "event_type": event,
            "severity": severity,
            "source_id": "/robot/" + code.lower(),
        }
    )


def write_script(path: Path, lines: Iterable[str]) -> Path:
    """A JSON-lines script (folders created)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(line + "\n" for line in lines), encoding="utf-8")
    return path


def episode(code: str, start_s: float, heal_after_s: float | None) -> list[tuple[float, str]]:
    """A fault confirmed at ``start_s`` (one FAILED) and, unless None, healed ``heal_after_s``
    later with the BRINGUP config (four PASSED, the last one at the heal): (time, line) pairs."""
    lines = [(start_s, report(start_s, code))]
    if heal_after_s is not None:
        for k in range(1, 5):
            t_s = start_s + heal_after_s * k / 4
            lines.append((t_s, report(t_s, code, "PASSED")))
    return lines


def mission(seed: int) -> list[str]:
    """A random but reproducible mission: a few faults, most of them healing."""
    rng = random.Random(seed)
    lines: list[tuple[float, str]] = []
    t_s = 0.0
    for code in rng.sample(CODES, rng.randint(1, 4)):
        t_s += rng.randint(1, 20)
        lines += episode(code, t_s, rng.choice([None, 2.0, 4.0, 8.0]))
    return [line for _, line in sorted(lines)]


@dataclass
class Fleet:
    """A generated fleet folder and what a replay should make of it."""

    root: Path
    recordings: list[Path] = field(default_factory=list)
    broken: list[Path] = field(default_factory=list)


def tiny_bag_records(seed: int) -> list[Rec]:
    """A few /diagnostics messages: one status failing then recovering."""
    rng = random.Random(seed)
    start = 1_700_000_000 * SEC + seed * SEC
    name = rng.choice(["motor", "lidar", "battery"])
    levels = [2, 2, 0, 0, 0, 0] if seed % 2 else [1, 2, 2, 2, 0]
    return [diag(start + n * SEC, name=name, level=level) for n, level in enumerate(levels)]


def build_fleet(root: Path, scripts: int = 44) -> Fleet:
    """A fleet of ``scripts`` missions in nested folders, the sample bags (MCAP, sqlite3, a bare
    file), tiny written bags (MCAP and sqlite3 folders, a bare file), a split bag, and three
    recordings that cannot be replayed."""
    fleet = Fleet(root)
    for index in range(scripts):
        path = root / "scripts" / f"robot_{index % 6}" / f"mission_{index}.jsonl"
        fleet.recordings.append(write_script(path, mission(index)))
    bags = root / "bags"
    for name in ("nav2_mission_mcap", "nav2_mission_sqlite3"):
        fleet.recordings.append(Path(shutil.copytree(SAMPLES / name, bags / "samples" / name)))
    bags.mkdir(parents=True, exist_ok=True)
    fleet.recordings.append(Path(shutil.copy(SAMPLES / "service_calls.mcap", bags)))
    tiny = bags / "tiny"
    fleet.recordings.append(write_bag(tiny / "tiny_mcap", tiny_bag_records(1)))
    fleet.recordings.append(
        write_bag(tiny / "tiny_sqlite3", tiny_bag_records(2), storage="sqlite3")
    )
    tiny.mkdir(exist_ok=True)
    fleet.recordings.append(write_bare(tiny / "bare.mcap", tiny_bag_records(3)))
    fleet.recordings.append(
        Path(shutil.copytree(FIXTURES / "split_bag_mcap", bags / "split_bag_mcap"))
    )
    broken = root / "broken"
    broken.mkdir()
    garbage = broken / "garbage.mcap"
    garbage.write_bytes(b"not a bag at all")
    backwards = write_script(
        broken / "backwards.jsonl", [report(2.0, "MOTOR_OVERHEAT"), report(1.0, "MOTOR_OVERHEAT")]
    )
    empty_bag = broken / "empty"
    empty_bag.mkdir()
    (empty_bag / "metadata.yaml").write_text("rosbag2_bagfile_information: {}\n")
    fleet.broken += [garbage, backwards, empty_bag]
    fleet.recordings += fleet.broken
    (root / "notes.txt").write_text("not a recording\n")
    return fleet


def fleet_tree(root: Path) -> Path:
    """Two bag folders (one split-named without metadata), a bare file, a file that is not a
    recording, a hidden folder, and a bag folder's subfolder that is not looked at: a fleet to
    copy under a prefix of an object store."""
    shutil.copytree(SAMPLES / "nav2_mission_mcap", root / "robot7" / "nav2_mission_mcap")
    shutil.copytree(SAMPLES / "nav2_mission_sqlite3", root / "robot7" / "sqlite_run")
    (root / "robot7" / "sqlite_run" / "sqlite_run.db3").write_bytes(
        (root / "robot7" / "sqlite_run" / "nav2_mission_sqlite3.db3").read_bytes()
    )
    (root / "robot7" / "sqlite_run" / "nav2_mission_sqlite3.db3").unlink()
    (root / "robot7" / "sqlite_run" / "metadata.yaml").unlink()
    (root / "robot9").mkdir()
    shutil.copy(SAMPLES / "service_calls.mcap", root / "robot9" / "service_calls.mcap")
    (root / "robot9" / "notes.txt").write_text("not a recording\n")
    (root / ".trash").mkdir()
    shutil.copy(SAMPLES / "service_calls.mcap", root / ".trash" / "old.mcap")
    return root


def fleet_rows(out: Path, name: str) -> list[dict[str, object]]:
    """The rows of a fleet's runs.json, each path made relative to ``name``, sorted by it."""
    runs: list[dict[str, object]] = json.loads((out / "runs.json").read_text())
    for run in runs:
        run["path"] = str(run["path"]).removeprefix(name).rstrip("/")
    return sorted(runs, key=lambda run: str(run["path"]))
