"""Remote inputs: the 10-minute camera-heavy mission replayed from an HTTP server on loopback.

Serves the mission (``bench_recording.mission_recording(root, seed, 600)``, reused when present)
with the tests' Range server in a child process, then replays it local and remote, ``--repeat``
times each (fastest kept), and prints wall and CPU time, the ratio, and the bytes fetched
(the share of the MCAP file, and what the replay's own topics take of it).

    PYTHONPATH=$PWD python benchmarks/bench_remote.py [--root DIR] [--repeat 3] [--config FILE]
                                                      [--url BASE]

``--url BASE`` replays from another server instead (nginx, say) that serves ROOT at BASE.
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING

from bench_recording import PARAMS, mission_recording

from medkit_replay import replay

if TYPE_CHECKING:
    from multiprocessing.connection import Connection

    from medkit_replay.result import Result


def _serve(root: Path, pipe: Connection) -> None:
    from tests.remote_support import range_server  # noqa: PLC0415  # the repository's root

    with range_server(root) as (base, served):
        pipe.send(base)
        pipe.recv()  # until told to stop
        pipe.send(served.requests)


def _timed(label: str, source: str | Path, params: Path, repeat: int) -> tuple[float, Result]:
    best: tuple[float, Result] | None = None
    for _ in range(repeat):
        load = os.getloadavg()[0]
        cpu0, wall0 = time.process_time(), time.perf_counter()
        result = replay([source], [params])
        wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
        print(f"  {label:<8} {wall:7.2f} s wall  {cpu:7.2f} s cpu  (load {load:.2f})", flush=True)
        if best is None or wall < best[0]:
            best = (wall, result)
    assert best is not None
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--root", type=Path, default=Path(tempfile.gettempdir()))
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--config", type=Path, default=None, help="default: the log bridge on")
    parser.add_argument("--url", default=None, help="a server already serving --root here")
    args = parser.parse_args()
    bag = mission_recording(args.root, args.seed, 600)
    params = args.config
    if params is None:
        params = Path(tempfile.mkdtemp()) / "params.yaml"
        params.write_text(PARAMS)
    mcap = next(bag.glob("*.mcap"))
    if args.url is not None:
        url = f"{args.url.rstrip('/')}/{bag.name}/"
        local_s, local = _timed("local", bag, params, args.repeat)
        remote_s, remote = _timed("remote", url, params, args.repeat)
        requests = None
    else:
        ours, theirs = multiprocessing.Pipe()
        server = multiprocessing.Process(target=_serve, args=(bag.parent, theirs), daemon=True)
        server.start()
        url = f"{ours.recv()}/{bag.name}/"
        try:
            local_s, local = _timed("local", bag, params, args.repeat)
            remote_s, remote = _timed("remote", url, params, args.repeat)
        finally:
            ours.send("stop")
            requests = ours.recv()
            server.join(timeout=10)
    fetched, size = remote.fetched[url.rstrip("/")]
    same = remote.summary == local.summary and remote.faults == local.faults
    read = sum(
        t.messages for s in local.inputs for t in s.topics if t.role is not None
    )  # messages of the topics read
    print(f"\nmission: {mcap} ({mcap.stat().st_size / 1e6:,.1f} MB), {read:,} messages read")
    share = 100 * fetched / size
    print(f"fetched: {fetched / 1e6:,.2f} MB of {size / 1e6:,.1f} MB ({share:.2f} %)")
    if requests is not None:
        print(f"requests served (all passes): {requests:,}")
    print(f"best wall: local {local_s:.2f} s, remote {remote_s:.2f} s ({remote_s / local_s:.2f}x)")
    print(f"same result: {same}")
    if not same:
        sys.exit(1)


if __name__ == "__main__":
    main()
