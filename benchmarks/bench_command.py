"""Benchmark: the command users run, whole processes under /usr/bin/time.

Usage:
    python benchmarks/bench_command.py [--out DIR] [--hour-out DIR] [--repeat 3] [--hour-repeat 1]
                                       [--no-hour]

Measures, each a fresh process (interpreter start, imports, replay and writing included):

- start-up: ``medkit-replay --version``, ``--help`` and ``analyze --help`` against
  ``python -c "import rosbags.rosbag2"`` (target: within 2.5x);
- on the 10-minute mission (``bench_recording.mission_recording(root, 1, 600)``) and the
  one-hour mission (``mission_recording(root, 1)``), log bridge on: ``analyze --quiet`` with no
  output, ``--json FILE`` (plain, ``.gz``, ``.zst``), ``--html FILE`` and ``--json FILE --html
  FILE``, and ``--json FILE`` once without ``--quiet`` (the summary drawn, into /dev/null):
  wall time, CPU time, peak RSS and how much faster than real time (targets on the 10-minute
  mission: ``--json`` >= 500x, aiming at 1,000x; ``--json --html`` >= 400x), with the sizes of
  the report (plain, gzip, zstd) and of the page;
- in one process on the 10-minute mission: the report written by the stdlib encoder it had
  before (``tests/oracle/json_report.py``) against today's (target: >= 5x faster).

Each figure is the fastest of ``--repeat`` runs (other work on the machine only ever slows a run
down). Recordings go to ``--out DIR`` (kept and reused) or to a temporary directory.
"""

from __future__ import annotations

import argparse
import io
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from bench_recording import PARAMS, disk_size, mission_recording, time_binary

if TYPE_CHECKING:
    from collections.abc import Callable

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # tests.oracle: the stdlib encoder, for the before/after ratio

CLI = [sys.executable, "-c", "from medkit_replay.cli import run; run()"]
"""What the ``medkit-replay`` console script runs (without the shell wrappers some installs
put in front of it, which are the environment's, not ours)."""
SHORT_S, HOUR_S = 600, 3600
SAMPLE = ROOT / "sample_bags" / "nav2_mission_mcap"


@dataclass(frozen=True)
class Run:
    """One process: wall and CPU seconds, peak RSS in kB."""

    wall_s: float
    cpu_s: float
    rss_kb: int


def installed_env(cache: Path) -> dict[str, str]:
    """The environment of an installed package: byte code cached (pip compiles it at install
    time; a checkout run with PYTHONDONTWRITEBYTECODE would compile every module on each run),
    kept in ``cache``, outside the source tree."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = str(cache)
    return env


ENV: dict[str, str] = dict(os.environ)


def timed(command: list[str], repeat: int) -> Run:
    """The fastest of ``repeat`` runs of ``command`` under /usr/bin/time (stdout discarded)."""
    best: Run | None = None
    for _ in range(repeat):
        done = subprocess.run(
            [time_binary(), "-f", "%e %U %S %M", *command],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            check=False,
            env=ENV,
            cwd=ROOT,  # python -c puts the working directory first on the path: this checkout
        )
        if done.returncode != 0:
            raise SystemExit(f"{' '.join(command)} failed ({done.returncode}):\n{done.stderr}")
        wall, user, system, rss = done.stderr.strip().splitlines()[-1].split()
        run = Run(float(wall), float(user) + float(system), int(rss))
        if best is None or run.wall_s < best.wall_s:
            best = run
    assert best is not None
    return best


def startup(repeat: int) -> None:
    print("start-up (fresh process, fastest of", repeat, "runs)")
    base = timed([sys.executable, "-c", "import rosbags.rosbag2"], repeat)
    label = 'python -c "import rosbags.rosbag2"'
    print(f"  {label:<36} {base.wall_s:6.3f} s")
    for arguments in (["--version"], ["--help"], ["analyze", "--help"]):
        run = timed([*CLI, *arguments], repeat)
        ratio = run.wall_s / base.wall_s
        verdict = "met" if ratio <= 2.5 else "NOT met"
        label = "medkit-replay " + " ".join(arguments)
        print(f"  {label:<36} {run.wall_s:6.3f} s  {ratio:4.2f}x rosbags (<= 2.5x: {verdict})")


def mission(bag: Path, params: Path, out: Path, mission_s: int, repeat: int) -> None:
    print(f"\n{bag.name}: {disk_size(bag) / 1e9:.2f} GB, {mission_s} s of bag time")
    analyze = [*CLI, "analyze", str(bag), "--config", str(params)]
    report, page = out / "report.json", out / "report.html"
    quiet = "--quiet"
    cases = [
        ("analyze (no output)", [quiet], None),
        ("analyze --json", ["--json", str(report), quiet], 500),
        ("analyze --json, summary", ["--json", str(report)], None),  # drawn into a file
        ("analyze --json .gz", ["--json", f"{report}.gz", quiet], None),
        ("analyze --json .zst", ["--json", f"{report}.zst", quiet], None),
        ("analyze --html", ["--html", str(page), quiet], None),
        ("analyze --json --html", ["--json", str(report), "--html", str(page), quiet], 400),
    ]
    for label, extra, target in cases:
        run = timed([*analyze, *extra], repeat)
        speed = mission_s / run.wall_s
        verdict = ""
        if target is not None and mission_s == SHORT_S:
            verdict = f"  (>= {target}x: {'met' if speed >= target else 'NOT met'})"
        print(
            f"  {label:<24} {run.wall_s:6.2f} s wall {run.cpu_s:6.2f} s cpu "
            f"{run.rss_kb / 1024:5.0f} MB peak  {speed:5.0f}x real time{verdict}"
        )
    sizes = {
        name: path.stat().st_size
        for name, path in (
            ("plain", report),
            ("gzip", Path(f"{report}.gz")),
            ("zstd", Path(f"{report}.zst")),
            ("page", page),
        )
    }
    print(
        f"  report: {sizes['plain'] / 1e6:.1f} MB plain, {sizes['gzip'] / 1e6:.2f} MB gzip "
        f"({sizes['plain'] / sizes['gzip']:.0f}x smaller), {sizes['zstd'] / 1e6:.2f} MB zstd "
        f"({sizes['plain'] / sizes['zstd']:.0f}x); page {sizes['page'] / 1e6:.2f} MB "
        f"(< 10 MB: {'met' if sizes['page'] < 10_000_000 else 'NOT met'})"
    )


def encoders(bag: Path, params: Path, repeat: int) -> None:
    """The report written by the stdlib encoder of before and by today's, in one process."""
    from medkit_replay.outputs.json_report import write_json_bytes  # noqa: PLC0415
    from medkit_replay.pipeline import replay  # noqa: PLC0415
    from tests.oracle.json_report import stdlib_dumps  # noqa: PLC0415

    result = replay([bag], [params])

    def best(write: Callable[[], None]) -> float:
        fastest = float("inf")
        for _ in range(repeat):
            start = time.perf_counter()
            write()
            fastest = min(fastest, time.perf_counter() - start)
        return fastest

    with tempfile.TemporaryDirectory(prefix="bench-command-") as tmp:
        target = Path(tmp) / "report.json"

        def before() -> None:
            target.write_text(stdlib_dumps(result), encoding="ascii")

        def after() -> None:
            with target.open("wb") as stream:
                write_json_bytes(result, stream)

        old, new = best(before), best(after)
    sink = io.BytesIO()
    write_json_bytes(result, sink)
    print(
        f"\nthe report of {bag.name} ({len(sink.getvalue()) / 1e6:.1f} MB) in one process: "
        f"stdlib encoder {old:.2f} s, msgspec {new:.2f} s: {old / new:.1f}x faster "
        f"(>= 5x: {'met' if old / new >= 5 else 'NOT met'})"
    )


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--out", type=Path, default=None, help="keep recordings here")
    parser.add_argument(
        "--hour-out", type=Path, default=None, help="the one-hour mission's folder (default: --out)"
    )
    parser.add_argument("--repeat", type=int, default=3, help="runs per figure; fastest kept")
    parser.add_argument("--hour-repeat", type=int, default=1, help="runs per hour figure")
    parser.add_argument("--no-hour", action="store_true", help="skip the one-hour mission")
    args = parser.parse_args()
    load = os.getloadavg()[0]
    print(f"load average {load:.2f}, {os.cpu_count()} CPUs")
    with tempfile.TemporaryDirectory(prefix="bench-command-") as tmp:
        root = args.out or Path(tmp)
        root.mkdir(parents=True, exist_ok=True)
        ENV.clear()  # the installed environment replaces this one: PYTHONDONTWRITEBYTECODE goes
        ENV.update(installed_env(Path(tmp) / "pycache"))
        warm = [
            *CLI,
            "analyze",
            str(SAMPLE),
            "--quiet",
            "--json",
            "/dev/null",
            "--html",
            "/dev/null",
        ]
        timed(warm, 1)  # fills the byte-code cache of every module a run below imports
        params = Path(tmp) / "params.yaml"
        params.write_text(PARAMS)
        outputs = Path(tmp) / "outputs"
        outputs.mkdir()
        startup(max(args.repeat, 1))
        short = mission_recording(root, 1, SHORT_S)
        mission(short, params, outputs, SHORT_S, max(args.repeat, 1))
        encoders(short, params, max(args.repeat, 1))
        if not args.no_hour:
            hour_root = args.hour_out or root
            hour_root.mkdir(parents=True, exist_ok=True)
            hour = mission_recording(hour_root, 1, HOUR_S)
            mission(hour, params, outputs, HOUR_S, max(args.hour_repeat, 1))
    print(f"load average at the end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
