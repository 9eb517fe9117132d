"""Remote inputs: the 10-minute camera-heavy mission replayed from an HTTP server on loopback.

Serves the mission (``bench_recording.mission_recording(root, seed, 600)``, reused when present)
with the tests' Range server in a child process, then replays it local and remote, ``--repeat``
times each (fastest kept), with the log bridge on and off (or with ``--config FILE`` only), and
prints wall and CPU time, the ratio, the bytes fetched (the share of the MCAP file) and the
range requests per pass (asked by the reader; served, as the server counted them).

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
from typing import TYPE_CHECKING, Any

from bench_recording import PARAMS, mission_recording

from medkit_replay import replay
from medkit_replay.inputs.remote.store import RemoteObject

if TYPE_CHECKING:
    from multiprocessing.connection import Connection

    from medkit_replay.result import Result

PARAMS_LOG_OFF = """medkit_replay:
  ros__parameters:
    enable_log_bridge: false
"""
ASKED = [0]  # ranges the reader asked for (counted around RemoteObject.fetch_many)


def _counting(fetch_many: Any) -> Any:
    def counted(self: RemoteObject, starts: list[int], ends: list[int], stop: Any = None) -> Any:
        ASKED[0] += len(starts)
        return fetch_many(self, starts, ends, stop)

    return counted


RemoteObject.fetch_many = _counting(RemoteObject.fetch_many)  # type: ignore[method-assign]


def _serve(root: Path, pipe: Connection) -> None:
    from tests.remote_support import range_server  # noqa: PLC0415  # the repository's root

    with range_server(root) as (base, served):
        pipe.send(base)
        while pipe.recv() == "count":  # until told to stop
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


def _served(pipe: Connection | None) -> int:
    if pipe is None:
        return 0
    pipe.send("count")
    count: int = pipe.recv()
    return count


def _compare(
    name: str, bag: Path, url: str, params: Path, repeat: int, pipe: Connection | None
) -> bool:
    print(f"{name}:")
    local_s, local = _timed("local", bag, params, repeat)
    asked, served = ASKED[0], _served(pipe)
    remote_s, remote = _timed("remote", url, params, repeat)
    asked, served = (ASKED[0] - asked) // repeat, (_served(pipe) - served) // repeat
    fetched, size = remote.fetched[url.rstrip("/")]
    same = remote.summary == local.summary and remote.faults == local.faults
    read = sum(t.messages for s in local.inputs for t in s.topics if t.role is not None)
    share = 100 * fetched / size
    print(f"  {read:,} messages read; fetched {fetched / 1e6:,.2f} MB of {size / 1e6:,.1f} MB")
    print(f"  ({share:.2f} %), {asked:,} ranges asked per pass", end="")
    print(f", {served:,} requests served per pass" if pipe is not None else "")
    print(
        f"  best wall: local {local_s:.2f} s, remote {remote_s:.2f} s ({remote_s / local_s:.2f}x)"
    )
    print(f"  same result: {same}\n", flush=True)
    return same


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--root", type=Path, default=Path(tempfile.gettempdir()))
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--config", type=Path, default=None, help="default: log bridge on, off")
    parser.add_argument("--url", default=None, help="a server already serving --root here")
    args = parser.parse_args()
    bag = mission_recording(args.root, args.seed, 600)
    mcap = next(bag.glob("*.mcap"))
    print(f"mission: {mcap} ({mcap.stat().st_size / 1e6:,.1f} MB)\n")
    configs = {str(args.config): args.config} if args.config is not None else {}
    if args.config is None:
        folder = Path(tempfile.mkdtemp())
        for name, text in (("log bridge on", PARAMS), ("log bridge off", PARAMS_LOG_OFF)):
            configs[name] = folder / f"{name.replace(' ', '_')}.yaml"
            configs[name].write_text(text)
    server = pipe = None
    if args.url is not None:
        base = args.url.rstrip("/")
    else:
        pipe, theirs = multiprocessing.Pipe()
        server = multiprocessing.Process(target=_serve, args=(bag.parent, theirs), daemon=True)
        server.start()
        base = pipe.recv()
    try:
        same = [
            _compare(name, bag, f"{base}/{bag.name}/", params, args.repeat, pipe)
            for name, params in configs.items()
        ]
    finally:
        if server is not None and pipe is not None:
            pipe.send("stop")
            server.join(timeout=10)
    if not all(same):
        sys.exit(1)


if __name__ == "__main__":
    main()
