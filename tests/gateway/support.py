"""Served recordings for the gateway tests: the nav2 sample under its rules, and the generated
robot of the evidence tests with its black-box recordings written."""

from __future__ import annotations

import socket
import threading
import time
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

import httpx
import uvicorn

from medkit_replay.commands.serve import retain_on_clear
from medkit_replay.evidence import EvidenceOptions, load_graph
from medkit_replay.gateway.recording import served_recording
from medkit_replay.history import FaultHistory
from medkit_replay.pipeline import replay

if TYPE_CHECKING:
    from collections.abc import Iterator

    from starlette.types import ASGIApp

    from medkit_replay.gateway.recording import ServedRecording

ROOT = Path(__file__).resolve().parents[2]
MISSION = ROOT / "sample_bags" / "nav2_mission_mcap"
NAV2 = ROOT / "rules" / "nav2" / "fault_manager.yaml"
NS = 1_000_000_000


def serve_replay(
    inputs: list[Path],
    configs: list[Path],
    *,
    graph: Path | None = None,
    clips: Path | None = None,
    at_sec: float | None = None,
) -> ServedRecording:
    """What ``medkit-replay serve`` answers from, built the way the command builds it."""
    node_graph = load_graph(graph) if graph is not None else None
    history = FaultHistory()
    result = replay(
        inputs,
        configs,
        evidence=EvidenceOptions(graph=node_graph, directory=clips),
        history=history,
    )
    retained = retain_on_clear(configs)
    return served_recording(result, history, node_graph, at_sec, retain_on_clear=retained)


def seconds(served: ServedRecording, t_ns: int) -> str:
    """``t_ns`` as the ``at`` parameter (seconds from the recording's start, to the ns)."""
    offset = t_ns - served.origin_ns
    return f"{offset // NS}.{offset % NS:09d}"


@contextmanager
def running(app: ASGIApp) -> Iterator[httpx.Client]:
    """``app`` served by uvicorn on a free loopback port in a thread, and an httpx client
    on it (the gateway's clients are httpx too); stopped on the way out."""
    listener = socket.socket()
    listener.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    listener.bind(("127.0.0.1", 0))
    listener.listen(16)
    port = listener.getsockname()[1]
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning", lifespan="off"))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [listener]}, daemon=True)
    thread.start()
    deadline = time.monotonic() + 30
    while not server.started:
        if time.monotonic() > deadline or not thread.is_alive():
            raise RuntimeError("the test server did not start")
        time.sleep(0.01)
    try:
        with httpx.Client(base_url=f"http://127.0.0.1:{port}", timeout=60) as client:
            yield client
    finally:
        server.should_exit = True
        thread.join(timeout=30)
        listener.close()
