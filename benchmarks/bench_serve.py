"""Benchmark: ``medkit-replay serve`` on the 10-minute mission; the web stacks it was chosen from.

Usage:
    python benchmarks/bench_serve.py [--out DIR] [--requests 1000] [--seed 1]
    python benchmarks/bench_serve.py --index [--out DIR] [--seed 1]
    python benchmarks/bench_serve.py --stacks [--requests 2000]

Serve mode starts the real command (``python -m medkit_replay.cli serve MISSION --config PARAMS
--port 0 --quiet``, the log bridge on) on ``bench_recording.mission_recording(root, 1, 600)``,
measures the time until it listens (replay and index) and its peak RSS, then one client (httpx,
one connection) sends ``--requests`` ``GET /api/v1/faults?status=all&at=T`` at random moments
T and prints p50, p99 and the slowest, and the same for the fault detail and the entity list.

Index mode replays the same mission with ``replay()`` in a child process, once without and once
with a FaultHistory (what serve answers from), and prints the FaultEvents, the states the
history holds (``len(history)``) and each child's peak RSS.

Stacks mode serves one ~40 KB JSON body (a fault list) with Starlette on uvicorn and with
aiohttp, each in its own process, and prints their import time and request latencies from
the same client (the measurement behind the choice of Starlette).
"""

from __future__ import annotations

import argparse
import os
import random
import resource
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import httpx

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_recording import PARAMS, mission_recording


def percentiles(samples: list[float]) -> str:
    ordered = sorted(samples)
    p50 = statistics.median(ordered)
    p99 = ordered[min(len(ordered) - 1, round(0.99 * len(ordered)) - 1)]
    return f"p50 {p50 * 1000:.2f} ms, p99 {p99 * 1000:.2f} ms, max {ordered[-1] * 1000:.2f} ms"


def timed(client: httpx.Client, urls: list[str], ok: tuple[int, ...] = (200,)) -> list[float]:
    samples = []
    for url in urls:
        started = time.perf_counter()
        answer = client.get(url)
        answer.read()
        samples.append(time.perf_counter() - started)
        if answer.status_code not in ok:
            raise SystemExit(f"{url}: {answer.status_code} {answer.text[:200]}")
    return samples


def serve_mode(out: Path, requests: int, seed: int) -> None:
    out.mkdir(parents=True, exist_ok=True)
    bag = mission_recording(out, seed, 600)
    params = out / "bench_params.yaml"
    params.write_text(PARAMS)
    command = [sys.executable, "-m", "medkit_replay.cli", "serve", str(bag), "--config",
               str(params), "--port", "0", "--quiet"]  # fmt: skip
    started = time.perf_counter()
    server = subprocess.Popen(command, stderr=subprocess.PIPE, text=True)
    assert server.stderr is not None
    line = ""
    while "Serving" not in line:
        line = server.stderr.readline()
        if not line and server.poll() is not None:
            raise SystemExit(f"serve ended: {server.returncode}")
    ready = time.perf_counter() - started
    base = line.split(" at ", 1)[1].split("/api/v1", 1)[0]
    print(f"serve listening after {ready:.1f} s (replay and index): {line.strip()}")
    rng = random.Random(seed)
    with httpx.Client(base_url=base, timeout=30) as client:
        facts = client.get("/api/v1/x-medkit/recording").json()
        span = facts["duration_sec"]
        faults = client.get("/api/v1/faults", params={"status": "all"}).json()["items"]
        codes = [f["fault_code"] for f in faults]
        apps = [a["id"] for a in client.get("/api/v1/apps").json()["items"]]
        print(f"{span:.0f} s recorded, {len(codes)} faults, {len(apps)} apps, "
              f"{facts['events']:,} events")  # fmt: skip
        timed(client, ["/api/v1/faults"] * 20)  # warm up
        moments = [rng.uniform(0, span) for _ in range(requests)]
        lists = timed(client, [f"/api/v1/faults?status=all&at={t:.3f}" for t in moments])
        print(f"GET /faults?status=all&at=T   x{requests}: {percentiles(lists)}")
        pairs = [
            (app, item["fault_code"])
            for app in apps
            for item in client.get(f"/api/v1/apps/{app}/faults?status=all").json()["items"]
        ]
        if pairs:
            chosen = [rng.choice(pairs) for _ in moments]
            urls = [
                f"/api/v1/apps/{a}/faults/{c}?at={t:.3f}"
                for (a, c), t in zip(chosen, moments, strict=True)
            ]
            details = timed(client, urls, ok=(200, 404))  # 404: not reported yet at T
            print(f"GET /apps/A/faults/C?at=T      x{requests}: {percentiles(details)}")
            urls = [
                f"/api/v1/apps/{a}/faults?status=all&at={t:.3f}"
                for (a, _), t in zip(chosen, moments, strict=True)
            ]
            entity = timed(client, urls)
            print(f"GET /apps/A/faults?at=T        x{requests}: {percentiles(entity)}")
    server.send_signal(2)
    server.wait(timeout=30)
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    print(f"server stopped on Ctrl-C with status {server.returncode}; "
          f"peak RSS {usage.ru_maxrss / 1024:.0f} MiB")  # fmt: skip


INDEX = """
import resource, sys
from medkit_replay.history import FaultHistory
from medkit_replay.pipeline import replay
history = FaultHistory() if sys.argv[3] == "index" else None
result = replay([sys.argv[1]], [sys.argv[2]], history=history)
held = f", {len(history):,} states in the index" if history is not None else ""
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(f"{len(result.events):,} FaultEvents{held}; peak RSS {peak:.0f} MiB")
"""


def index_mode(out: Path, seed: int) -> None:
    out.mkdir(parents=True, exist_ok=True)
    bag = mission_recording(out, seed, 600)
    params = out / "bench_params.yaml"
    params.write_text(PARAMS)
    for kind in ("replay", "index"):
        line = subprocess.run(
            [sys.executable, "-c", INDEX, str(bag), str(params), kind],
            check=True, capture_output=True, text=True,
        ).stdout.strip()  # fmt: skip
        print(f"{'replay alone' if kind == 'replay' else 'with the index':14}: {line}")


STARLETTE = """
import json, sys, time
t = time.perf_counter()
import uvicorn
from starlette.applications import Starlette
from starlette.responses import Response
from starlette.routing import Route
imported = time.perf_counter() - t
body = json.dumps({"items": [{"fault_code": f"F{i}", "severity": 2, "status": "CONFIRMED",
    "description": "x" * 200} for i in range(150)]})
async def faults(request):
    return Response(body, media_type="application/json")
app = Starlette(routes=[Route("/api/v1/faults", faults)])
print(f"ready {imported:.3f}", flush=True)
uvicorn.run(app, fd=int(sys.argv[1]), log_level="warning")
"""

AIOHTTP = """
import json, socket, sys, time
t = time.perf_counter()
from aiohttp import web
imported = time.perf_counter() - t
body = json.dumps({"items": [{"fault_code": f"F{i}", "severity": 2, "status": "CONFIRMED",
    "description": "x" * 200} for i in range(150)]})
async def faults(request):
    return web.Response(text=body, content_type="application/json")
app = web.Application()
app.router.add_get("/api/v1/faults", faults)
print(f"ready {imported:.3f}", flush=True)
web.run_app(app, sock=socket.socket(fileno=int(sys.argv[1])), print=None)
"""


def stacks_mode(requests: int) -> None:
    for name, code in (("starlette+uvicorn", STARLETTE), ("aiohttp", AIOHTTP)):
        listener = socket.socket()
        listener.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)  # as serve's listener
        listener.bind(("127.0.0.1", 0))
        listener.listen(16)
        port = listener.getsockname()[1]
        with tempfile.TemporaryDirectory() as folder:
            script = Path(folder) / "server.py"
            script.write_text(code)
            server = subprocess.Popen(
                [sys.executable, str(script), str(listener.fileno())],
                pass_fds=[listener.fileno()], stdout=subprocess.PIPE, text=True,
            )  # fmt: skip
            assert server.stdout is not None
            imported = server.stdout.readline().split()[1]
            with httpx.Client(base_url=f"http://127.0.0.1:{port}") as client:
                timed(client, ["/api/v1/faults"] * 50)
                samples = timed(client, ["/api/v1/faults"] * requests)
            server.terminate()
            server.wait()
        listener.close()
        print(f"{name:18} import {float(imported) * 1000:.0f} ms; x{requests}: "
              f"{percentiles(samples)}")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path(tempfile.gettempdir()) / "bench_serve")
    parser.add_argument("--requests", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--stacks", action="store_true")
    parser.add_argument("--index", action="store_true")
    args = parser.parse_args()
    print(f"machine: {os.cpu_count()} cores, Python {sys.version.split()[0]}")
    if args.stacks:
        stacks_mode(args.requests)
    elif args.index:
        index_mode(args.out, args.seed)
    else:
        serve_mode(args.out, args.requests, args.seed)


if __name__ == "__main__":
    main()
