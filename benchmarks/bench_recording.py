"""Benchmark: read a large generated MCAP recording, and the peak memory of analyze over two sizes.

Usage:
    python benchmarks/bench_recording.py [--size-gb 1.0] [--out DIR] [--seed 1] [--repeat 3]
    python benchmarks/bench_recording.py --mission-hour [--out DIR] [--repeat 2]
    python benchmarks/bench_recording.py --memory [--small-gb 0.2] [--large-gb 2.0] [--out DIR]
    python benchmarks/bench_recording.py --size-gb 0.2 --profile

The recording (rosbag2, MCAP storage, no compression, so its size is real) holds camera frames
(sensor_msgs/msg/Image 640x480 rgb8 at 15 Hz) as filler and the traffic the replay reads:
/diagnostics (DiagnosticArray of 5 statuses, 100 Hz, WARN/ERROR episodes), three
``*/_action/status`` topics (GoalStatusArray on every goal transition, some aborts) and
/rosout (rcl_interfaces/msg/Log, ~50 Hz, some WARN/ERROR). It is written streaming, one
message at a time, and is deterministic for a seed.

Throughput mode prints messages per second over the read topics for (a) rosbags reading them
raw, (b) rosbags reading and deserializing them, (c) ``medkit_replay.replay`` end to end with
the log bridge on, (d) a straightforward pipeline (rosbags AnyReader + deserialize + our
bridges and engine, no spooling), and the ratios c/a, c/b, c/d against the targets (c/a >= 0.5,
aiming at 1.0; c/d >= 5). Each is run ``--repeat`` times and the fastest wall time is kept
(other work on the machine only ever slows a run down).

Mission mode writes a one-hour mission (10 Hz DiagnosticArrays of 20 statuses, 5 action
servers, 50 rosout lines per second, 5 GB of 15 Hz camera frames), streaming, and measures
(a), (b) and (c) on it: (c) must run at least 500 times faster than real time.

Memory mode runs ``/usr/bin/time -v python -m medkit_replay.cli analyze BAG --quiet --json
/dev/null --config PARAMS`` on a small and a large recording of the same topic mix and prints
both peak RSS values and their ratio (target: large within 1.5x of small).

Generated recordings go to ``--out DIR`` (kept, and reused by later runs with the same size and
seed) or to a temporary directory deleted at exit.
"""

from __future__ import annotations

import argparse
import cProfile
import heapq
import io
import json
import os
import pstats
import random
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from rosbags.highlevel import AnyReader
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.typesys.stores.ros2_jazzy import (
    action_msgs__msg__GoalInfo as GoalInfo,
    action_msgs__msg__GoalStatus as GoalStatus,
    action_msgs__msg__GoalStatusArray as GoalStatusArray,
    builtin_interfaces__msg__Time as Time,
    diagnostic_msgs__msg__DiagnosticArray as DiagnosticArray,
    diagnostic_msgs__msg__DiagnosticStatus as DiagnosticStatus,
    diagnostic_msgs__msg__KeyValue as KeyValue,
    rcl_interfaces__msg__Log as Log,
    sensor_msgs__msg__CompressedImage as CompressedImage,
    sensor_msgs__msg__Image as Image,
    std_msgs__msg__Header as Header,
    unique_identifier_msgs__msg__UUID as UUID,
)

from medkit_replay.bridges.action_status import ActionStatusBridge
from medkit_replay.bridges.diagnostic import DiagnosticBridge
from medkit_replay.bridges.log import LogBridge
from medkit_replay.config.fault_manager import fault_manager_config
from medkit_replay.config.params import load_parameters
from medkit_replay.config.replay_options import replay_options
from medkit_replay.engine.manager import FaultManager
from medkit_replay.engine.timeline import Timeline
from medkit_replay.msgdefs import base_typestore
from medkit_replay.pipeline import replay

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator, Sequence

    from medkit_replay.model import ClearRequest, ReportRequest

GENERATOR_VERSION = 2  # bump when the generated content changes: old --out recordings are redone
PARAMS = """medkit_replay:
  ros__parameters:
    enable_log_bridge: true
"""
T0_NS = 1_700_000_000 * 10**9
MCAP_MESSAGE_OVERHEAD = 1 + 8 + 22  # opcode, record length, channel/sequence/log/publish time
IMAGE_TOPIC = "/camera/front/image_raw"
DIAGNOSTICS_TOPIC = "/diagnostics"
ROSOUT_TOPIC = "/rosout"
ACTION_SUFFIX = "/_action/status"
WIDTH, HEIGHT = 640, 480
CAMERA_HZ = 15
DIAGNOSTICS_HZ = 100
ROSOUT_HZ = 50
STATUS_ACCEPTED, STATUS_EXECUTING, STATUS_SUCCEEDED, STATUS_CANCELED, STATUS_ABORTED = (
    1,
    2,
    4,
    5,
    6,
)
LEVEL_OK, LEVEL_WARN, LEVEL_ERROR = 0, 1, 2

Event = tuple[int, str, bytes | memoryview]
"""One message to write: log time (ns), topic, serialized CDR payload."""


@dataclass(frozen=True, slots=True)
class ActionProfile:
    """How often an action server gets goals, how long they run, how many fail."""

    name: str
    gap_s: tuple[float, float]
    duration_s: tuple[float, float]
    abort_p: float
    cancel_p: float


ACTIONS = (
    ActionProfile("/navigate_to_pose", (2.0, 8.0), (3.0, 15.0), 0.15, 0.05),
    ActionProfile("/follow_path", (1.0, 4.0), (2.0, 10.0), 0.20, 0.05),
    ActionProfile("/compute_path_to_pose", (0.5, 1.5), (0.02, 0.3), 0.10, 0.0),
)
DIAGNOSTIC_SOURCES = (
    ("camera_front: Frame rate", "/sensors/camera_front", "Frame rate below expected"),
    ("lidar_top: Connection", "/sensors/lidar_top", "Packets dropped"),
    ("motor_controller: Temperature", "/powertrain/motor_left", "Motor temperature high"),
    ("battery: Voltage", "/power/battery", "Battery voltage low"),
    ("imu: Status", "/sensors/imu", "IMU data noisy"),
)
LOG_NODES = ("controller_server", "planner_server", "bt_navigator", "amcl", "camera_driver")
LOG_TEMPLATES = {
    20: (
        "Received a goal, begin computing control effort.",
        "Passing new path to controller.",
        "Reached the goal!",
        "Setting pose: {x:.3f} {y:.3f} {a:.3f}",
        "Frame {n} published",
    ),
    30: (
        "Control loop missed its desired rate of 20.0000 Hz. Current loop rate is {r:.4f} Hz.",
        "Frame {n} dropped: {ms} ms late",
        "Message Filter dropping message: frame 'laser' at time {x:.3f} for reason 'discarding'",
    ),
    40: (
        "Failed to make progress",
        "GridBased: failed to create plan with tolerance {a:.2f}.",
        "No valid trajectories out of {n}!",
        "Camera driver: USB transfer error {n}",
    ),
}


# -- generation --------------------------------------------------------------------------------


def _time(t_ns: int) -> Time:
    return Time(sec=t_ns // 10**9, nanosec=t_ns % 10**9)


def _camera(seed: int) -> Iterator[Event]:
    """640x480 rgb8 frames at 15 Hz, cycling over a few random images (no compression)."""
    store = base_typestore()
    rng = np.random.default_rng(seed)
    frames = [rng.integers(0, 256, WIDTH * HEIGHT * 3, dtype=np.uint8) for _ in range(4)]
    period = 10**9 // CAMERA_HZ
    k = 0
    while True:
        t_ns = T0_NS + 3_000_000 + k * period
        image = Image(
            header=Header(stamp=_time(t_ns), frame_id="camera_front"),
            height=HEIGHT,
            width=WIDTH,
            encoding="rgb8",
            is_bigendian=0,
            step=WIDTH * 3,
            data=frames[k % len(frames)],
        )
        yield t_ns, IMAGE_TOPIC, store.serialize_cdr(image, Image.__msgtype__)
        k += 1


class _Episodes:
    """One diagnostic status: OK most of the time, WARN or ERROR for 0.5-5 s episodes."""

    def __init__(self, rng: random.Random, mean_gap_s: float) -> None:
        self.rng = rng
        self.mean_gap_ns = int(mean_gap_s * 1e9)
        self.level = LEVEL_OK
        self.until_ns = T0_NS + int(rng.expovariate(1.0) * self.mean_gap_ns)

    def level_at(self, t_ns: int) -> int:
        if t_ns >= self.until_ns:
            if self.level == LEVEL_OK:
                self.level = LEVEL_WARN if self.rng.random() < 0.75 else LEVEL_ERROR
                self.until_ns = t_ns + int(self.rng.uniform(0.5, 5.0) * 1e9)
            else:
                self.level = LEVEL_OK
                self.until_ns = t_ns + int(self.rng.expovariate(1.0) * self.mean_gap_ns)
        return self.level


def _diagnostics(seed: int) -> Iterator[Event]:
    """A DiagnosticArray of 5 statuses at 100 Hz, as an aggregator-less robot publishes them."""
    store = base_typestore()
    rng = random.Random(f"{seed}/diagnostics")
    episodes = [_Episodes(rng, mean_gap_s=30.0) for _ in DIAGNOSTIC_SOURCES]
    period = 10**9 // DIAGNOSTICS_HZ
    k = 0
    while True:
        t_ns = T0_NS + k * period
        statuses = []
        for (name, hardware_id, problem), episode in zip(DIAGNOSTIC_SOURCES, episodes, strict=True):
            level = episode.level_at(t_ns)
            statuses.append(
                DiagnosticStatus(
                    level=level,
                    name=name,
                    message="OK" if level == LEVEL_OK else problem,
                    hardware_id=hardware_id,
                    values=[
                        KeyValue(key="value", value=f"{rng.gauss(50.0, 5.0):.2f}"),
                        KeyValue(key="samples", value=str(k)),
                    ],
                )
            )
        array = DiagnosticArray(header=Header(stamp=_time(t_ns), frame_id=""), status=statuses)
        yield t_ns, DIAGNOSTICS_TOPIC, store.serialize_cdr(array, DiagnosticArray.__msgtype__)
        k += 1


def _action(seed: int, profile: ActionProfile) -> Iterator[Event]:
    """One action server's status topic: ACCEPTED, EXECUTING, then the result of each goal."""
    store = base_typestore()
    rng = random.Random(f"{seed}/{profile.name}")
    topic = profile.name + ACTION_SUFFIX
    t_ns = T0_NS + int(rng.uniform(*profile.gap_s) * 1e9)
    while True:
        goal_id = UUID(uuid=np.frombuffer(rng.randbytes(16), dtype=np.uint8))
        info = GoalInfo(goal_id=goal_id, stamp=_time(t_ns))
        roll = rng.random()
        if roll < profile.abort_p:
            result = STATUS_ABORTED
        elif roll < profile.abort_p + profile.cancel_p:
            result = STATUS_CANCELED
        else:
            result = STATUS_SUCCEEDED
        end_ns = t_ns + int(rng.uniform(*profile.duration_s) * 1e9)
        for when, status in ((t_ns, STATUS_ACCEPTED), (t_ns + 2_000_000, STATUS_EXECUTING)):
            array = GoalStatusArray(status_list=[GoalStatus(goal_info=info, status=status)])
            yield when, topic, store.serialize_cdr(array, GoalStatusArray.__msgtype__)
        array = GoalStatusArray(status_list=[GoalStatus(goal_info=info, status=result)])
        yield end_ns, topic, store.serialize_cdr(array, GoalStatusArray.__msgtype__)
        t_ns = end_ns + int(rng.uniform(*profile.gap_s) * 1e9)


def _rosout(seed: int, hz: int = ROSOUT_HZ) -> Iterator[Event]:
    """Log lines at ~50 Hz from five nodes: mostly INFO, some WARN, a few ERROR."""
    store = base_typestore()
    rng = random.Random(f"{seed}/rosout")
    period = 10**9 // hz
    t_ns = T0_NS + 1_000_000
    n = 0
    while True:
        t_ns += period + rng.randrange(-period // 4, period // 4)
        roll = rng.random()
        level = 40 if roll < 0.02 else 30 if roll < 0.10 else 20
        node = "fault_manager" if rng.random() < 0.01 else rng.choice(LOG_NODES)
        text = rng.choice(LOG_TEMPLATES[level]).format(
            x=rng.uniform(-50, 50),
            y=rng.uniform(-50, 50),
            a=rng.uniform(0, 3),
            r=rng.uniform(5, 19),
            n=n,
            ms=rng.randrange(5, 200),
        )
        log = Log(
            stamp=_time(t_ns),
            level=level,
            name=node,
            msg=text,
            file=f"/opt/ros/jazzy/src/{node}.cpp",
            function="on_timer",
            line=100 + level,
        )
        yield t_ns, ROSOUT_TOPIC, store.serialize_cdr(log, Log.__msgtype__)
        n += 1


def _event_time(event: Event) -> int:
    return event[0]


def generate(path: Path, size_bytes: int, seed: int) -> None:
    """Write a rosbag2 directory (MCAP storage, uncompressed) of about ``size_bytes``.

    Streams: each topic is a generator and they are merged lazily in time order, so memory
    holds one message per topic plus the writer's current chunk.
    """
    store = base_typestore()
    streams = [
        _camera(seed),
        _diagnostics(seed),
        _rosout(seed),
        *(_action(seed, profile) for profile in ACTIONS),
    ]
    types = {
        IMAGE_TOPIC: Image.__msgtype__,
        DIAGNOSTICS_TOPIC: DiagnosticArray.__msgtype__,
        ROSOUT_TOPIC: Log.__msgtype__,
        **{p.name + ACTION_SUFFIX: GoalStatusArray.__msgtype__ for p in ACTIONS},
    }
    written = 0
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connections = {
            topic: writer.add_connection(topic, msgtype, typestore=store)
            for topic, msgtype in types.items()
        }
        for t_ns, topic, payload in heapq.merge(*streams, key=_event_time):
            writer.write(connections[topic], t_ns, payload)
            written += len(payload) + MCAP_MESSAGE_OVERHEAD
            if written >= size_bytes:
                break


def recording(root: Path, size_gb: float, seed: int) -> Path:
    """The recording for this size and seed under ``root``: reused if complete, else written."""
    size_bytes = int(size_gb * 1e9)
    name = f"recording_{size_bytes // 10**6}mb_seed{seed}"
    path, marker = root / name, root / f"{name}.json"
    stamp = {"generator": GENERATOR_VERSION, "size_bytes": size_bytes, "seed": seed}
    if path.is_dir() and marker.is_file() and json.loads(marker.read_text()) == stamp:
        print(f"reusing {path} ({disk_size(path) / 1e9:.2f} GB)")
        return path
    marker.unlink(missing_ok=True)
    if path.exists():
        shutil.rmtree(path)
    print(f"generating {path} ({size_gb:g} GB, seed {seed}) ...", flush=True)
    start = time.perf_counter()
    generate(path, size_bytes, seed)
    marker.write_text(json.dumps(stamp))
    elapsed = time.perf_counter() - start
    size = disk_size(path)
    print(f"  wrote {size / 1e9:.2f} GB in {elapsed:.1f} s ({size / 1e6 / elapsed:.0f} MB/s)")
    return path


def disk_size(path: Path) -> int:
    return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())


# -- throughput --------------------------------------------------------------------------------


def is_read_topic(topic: str) -> bool:
    """The topics the replay reads in this recording (with the log bridge on)."""
    return topic in (DIAGNOSTICS_TOPIC, ROSOUT_TOPIC) or (
        topic.endswith(ACTION_SUFFIX) and topic != ACTION_SUFFIX
    )


def rosbags_raw(bag: Path, _params: Path) -> int:
    """(a) rosbags' Reader over the read topics, payloads left as bytes."""
    count = 0
    with Reader(bag) as reader:
        connections = [c for c in reader.connections if is_read_topic(c.topic)]
        for _connection, _t_ns, _raw in reader.messages(connections=connections):
            count += 1
    return count


def rosbags_deserialize(bag: Path, _params: Path) -> int:
    """(b) As (a), each payload deserialized with the typestore the replay uses."""
    store = base_typestore()
    count = 0
    with Reader(bag) as reader:
        connections = [c for c in reader.connections if is_read_topic(c.topic)]
        for connection, _t_ns, raw in reader.messages(connections=connections):
            store.deserialize_cdr(raw, connection.msgtype)
            count += 1
    return count


def medkit_analyze(bag: Path, params: Path) -> int:
    """(c) ``medkit-replay analyze`` minus writing outputs: the whole pipeline."""
    return replay([bag], [params]).summary.messages_read


def straightforward(bag: Path, params: Path) -> int:
    """(d) rosbags AnyReader + deserialize, fed to our bridges and engine directly.

    What one would write first: no damage handling, no reorder window, no recorded-service
    pre-pass, engine records kept in plain lists.
    """
    parameters = load_parameters([params])
    manager_config, _ = fault_manager_config(parameters.node("fault_manager"))
    options, _ = replay_options(parameters)
    diagnostic = DiagnosticBridge(options.diagnostic)
    action = ActionStatusBridge(options.action_status, action_sources=options.action_sources)
    log = LogBridge(options.log)
    timeline = Timeline(FaultManager(manager_config))
    count = 0
    with AnyReader([bag], default_typestore=base_typestore()) as reader:
        connections = [c for c in reader.connections if is_read_topic(c.topic)]
        for connection, t_ns, raw in reader.messages(connections=connections):
            topic, msgtype = connection.topic, connection.msgtype
            msg = reader.deserialize(raw, msgtype)
            count += 1
            timeline.advance(t_ns)
            requests: Sequence[ReportRequest | ClearRequest] = ()
            if action.wants(topic, msgtype):
                requests = action.on_message(t_ns, topic, msg)
            elif diagnostic.wants(topic, msgtype):
                requests = diagnostic.on_message(t_ns, topic, msg)
            elif log.wants(topic, msgtype):
                requests = log.on_message(t_ns, topic, msg)
            for request in requests:
                timeline.apply(request)
    return count


@dataclass(frozen=True, slots=True)
class Measurement:
    """The fastest of the repeated runs of one reader."""

    label: str
    messages: int
    wall_s: float
    cpu_s: float
    load: float

    @property
    def rate(self) -> float:
        return self.messages / self.wall_s


def cpu_seconds() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def measure(
    label: str, run: Callable[[Path, Path], int], bag: Path, params: Path, repeat: int
) -> Measurement:
    best: Measurement | None = None
    for _ in range(repeat):
        load = os.getloadavg()[0]
        cpu0, wall0 = cpu_seconds(), time.perf_counter()
        messages = run(bag, params)
        wall, cpu = time.perf_counter() - wall0, cpu_seconds() - cpu0
        print(
            f"  {label:<44} {messages:>9,} msgs  {wall:7.2f} s wall  {cpu:7.2f} s cpu  "
            f"{messages / wall:>10,.0f} msgs/s  (load {load:.2f})",
            flush=True,
        )
        if best is None or wall < best.wall_s:
            best = Measurement(label, messages, wall, cpu, load)
    assert best is not None
    return best


def throughput(bag: Path, params: Path, repeat: int, with_straightforward: bool) -> None:
    size = disk_size(bag)
    print(f"recording: {bag} ({size / 1e9:.2f} GB on disk, in the page cache after writing)")
    runs: list[tuple[str, Callable[[Path, Path], int]]] = [
        ("(a) rosbags Reader, raw", rosbags_raw),
        ("(b) rosbags Reader + deserialize_cdr", rosbags_deserialize),
        ("(c) medkit_replay analyze (replay())", medkit_analyze),
    ]
    if with_straightforward:
        runs.append(("(d) AnyReader + deserialize + bridges/engine", straightforward))
    results = [measure(label, run, bag, params, repeat) for label, run in runs]
    print(f"\nbest of {repeat}, {results[0].messages:,} messages on the read topics:")
    for m in results:
        print(
            f"  {m.label:<44} {m.rate:>10,.0f} msgs/s  {m.wall_s:7.2f} s wall  "
            f"{m.cpu_s:7.2f} s cpu  {size / 1e6 / m.wall_s:6.0f} MB/s of recording"
        )
    if len({m.messages for m in results}) != 1:
        print("  WARNING: the readers did not read the same number of messages")
    a, b, c = results[0], results[1], results[2]
    print(f"  c/a = {c.rate / a.rate:.2f}   c/b = {c.rate / b.rate:.2f}", end="")
    if with_straightforward:
        print(f"   c/d = {c.rate / results[3].rate:.2f}", end="")
    print("   (throughput ratios by wall time: >1 means analyze is faster)")
    print(f"  c/a = {a.cpu_s / c.cpu_s:.2f}   c/b = {b.cpu_s / c.cpu_s:.2f}", end="")
    if with_straightforward:
        print(f"   c/d = {results[3].cpu_s / c.cpu_s:.2f}", end="")
    print("   (the same by CPU time, less sensitive to other load on the machine)")
    print(
        f"  target c/a >= 0.5 (aim 1.0): {'met' if c.rate >= 0.5 * a.rate else 'NOT met'}", end=""
    )
    if with_straightforward:
        met = c.rate >= 5 * results[3].rate
        print(f"   target c/d >= 5: {'met' if met else 'NOT met'}", end="")
    print()
    rss, wall = peak_rss(bag, params)
    print(
        f"  (c) as a CLI in a fresh process (/usr/bin/time): {wall:.2f} s wall including start-up "
        f"({c.messages / wall:,.0f} msgs/s), peak RSS {rss / 1024:.0f} MB"
    )


# -- the one-hour mission ----------------------------------------------------------------------

MISSION_S = 3600
MISSION_CAMERA_BYTES = 5 * 10**9
MISSION_CAMERA_HZ = 15
MISSION_DIAGNOSTICS_HZ = 10
MISSION_ROSOUT_HZ = 50
MISSION_COMPONENTS = (
    ("camera_front", "/sensors/camera_front"),
    ("camera_rear", "/sensors/camera_rear"),
    ("lidar_top", "/sensors/lidar_top"),
    ("imu", "/sensors/imu"),
    ("gps", "/sensors/gps"),
    ("motor_left", "/powertrain/motor_left"),
    ("motor_right", "/powertrain/motor_right"),
    ("battery", "/power/battery"),
    ("charger", "/power/charger"),
    ("wifi", "/comms/wifi"),
)
MISSION_CHECKS = (("Status", "Degraded"), ("Rate", "Rate below expected"))
MISSION_ACTIONS = (
    *ACTIONS,
    ActionProfile("/spin", (20.0, 60.0), (2.0, 6.0), 0.10, 0.05),
    ActionProfile("/dock_robot", (120.0, 300.0), (10.0, 30.0), 0.20, 0.0),
)


def _mission_camera(seed: int) -> Iterator[Event]:
    """JPEG-sized incompressible frames at 15 Hz: 5 GB over the hour."""
    store = base_typestore()
    rng = np.random.default_rng(seed)
    size = MISSION_CAMERA_BYTES // (MISSION_CAMERA_HZ * 3600)
    frames = [rng.integers(0, 256, size, dtype=np.uint8) for _ in range(4)]
    period = 10**9 // MISSION_CAMERA_HZ
    k = 0
    while True:
        t_ns = T0_NS + 3_000_000 + k * period
        image = CompressedImage(
            header=Header(stamp=_time(t_ns), frame_id="camera_front"),
            format="jpeg",
            data=frames[k % len(frames)],
        )
        yield (
            t_ns,
            IMAGE_TOPIC + "/compressed",
            store.serialize_cdr(image, CompressedImage.__msgtype__),
        )
        k += 1


def _mission_diagnostics(seed: int) -> Iterator[Event]:
    """One DiagnosticArray of 20 statuses (10 components, 2 checks each) at 10 Hz."""
    store = base_typestore()
    rng = random.Random(f"{seed}/mission-diagnostics")
    sources = [
        (f"{component}: {check}", hardware_id, problem)
        for component, hardware_id in MISSION_COMPONENTS
        for check, problem in MISSION_CHECKS
    ]
    episodes = [_Episodes(rng, mean_gap_s=300.0) for _ in sources]
    period = 10**9 // MISSION_DIAGNOSTICS_HZ
    k = 0
    while True:
        t_ns = T0_NS + k * period
        statuses = []
        for (name, hardware_id, problem), episode in zip(sources, episodes, strict=True):
            level = episode.level_at(t_ns)
            statuses.append(
                DiagnosticStatus(
                    level=level,
                    name=name,
                    message="OK" if level == LEVEL_OK else problem,
                    hardware_id=hardware_id,
                    values=[
                        KeyValue(key="value", value=f"{rng.gauss(50.0, 5.0):.2f}"),
                        KeyValue(key="samples", value=str(k)),
                    ],
                )
            )
        array = DiagnosticArray(header=Header(stamp=_time(t_ns), frame_id=""), status=statuses)
        yield t_ns, DIAGNOSTICS_TOPIC, store.serialize_cdr(array, DiagnosticArray.__msgtype__)
        k += 1


def generate_mission(path: Path, seed: int, mission_s: int = MISSION_S) -> None:
    """Write the mission, one hour unless told (rosbag2 folder, MCAP, uncompressed), streaming."""
    store = base_typestore()
    streams = [
        _mission_camera(seed),
        _mission_diagnostics(seed),
        _rosout(seed, MISSION_ROSOUT_HZ),
        *(_action(seed, profile) for profile in MISSION_ACTIONS),
    ]
    types = {
        IMAGE_TOPIC + "/compressed": CompressedImage.__msgtype__,
        DIAGNOSTICS_TOPIC: DiagnosticArray.__msgtype__,
        ROSOUT_TOPIC: Log.__msgtype__,
        **{p.name + ACTION_SUFFIX: GoalStatusArray.__msgtype__ for p in MISSION_ACTIONS},
    }
    end_ns = T0_NS + mission_s * 10**9
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connections = {
            topic: writer.add_connection(topic, msgtype, typestore=store)
            for topic, msgtype in types.items()
        }
        for t_ns, topic, payload in heapq.merge(*streams, key=_event_time):
            if t_ns >= end_ns:
                break
            writer.write(connections[topic], t_ns, payload)


def mission_recording(root: Path, seed: int, mission_s: int = MISSION_S) -> Path:
    """The mission (one hour unless told) under ``root``: reused if complete, else written."""
    name = (
        f"mission_hour_seed{seed}" if mission_s == MISSION_S else f"mission_{mission_s}s_seed{seed}"
    )
    path, marker = root / name, root / f"{name}.json"
    stamp = {"generator": GENERATOR_VERSION, "mission_s": mission_s, "seed": seed}
    if path.is_dir() and marker.is_file() and json.loads(marker.read_text()) == stamp:
        print(f"reusing {path} ({disk_size(path) / 1e9:.2f} GB)")
        return path
    marker.unlink(missing_ok=True)
    if path.exists():
        shutil.rmtree(path)
    print(f"generating {path} ({mission_s} s, seed {seed}) ...", flush=True)
    start = time.perf_counter()
    generate_mission(path, seed, mission_s)
    marker.write_text(json.dumps(stamp))
    elapsed = time.perf_counter() - start
    size = disk_size(path)
    print(f"  wrote {size / 1e9:.2f} GB in {elapsed:.1f} s ({size / 1e6 / elapsed:.0f} MB/s)")
    return path


def mission_hour(root: Path, params: Path, repeat: int, seed: int) -> None:
    """Analyse the one-hour mission: how much faster than real time, next to rosbags' read."""
    bag = mission_recording(root, seed)
    size = disk_size(bag)
    print(f"recording: {bag} ({size / 1e9:.2f} GB, {MISSION_S} s of bag time)")
    runs: list[tuple[str, Callable[[Path, Path], int]]] = [
        ("(a) rosbags Reader, raw", rosbags_raw),
        ("(b) rosbags Reader + deserialize_cdr", rosbags_deserialize),
        ("(c) medkit_replay analyze (replay())", medkit_analyze),
    ]
    results = [measure(label, run, bag, params, repeat) for label, run in runs]
    a, b, c = results
    print(f"\nbest of {repeat}, {c.messages:,} messages on the read topics:")
    for m in results:
        print(
            f"  {m.label:<44} {m.rate:>10,.0f} msgs/s  {m.wall_s:7.2f} s wall  "
            f"{m.cpu_s:7.2f} s cpu  {MISSION_S / m.wall_s:6.0f}x real time"
        )
    print(f"  c/a = {c.rate / a.rate:.2f}   c/b = {c.rate / b.rate:.2f}   (by wall time)")
    verdict = "met" if MISSION_S / c.wall_s >= 500 else "NOT met"
    print(
        f"  analyze: {MISSION_S / c.wall_s:.0f}x faster than real time (target >= 500x: {verdict})"
    )
    rss, wall = peak_rss(bag, params, json_report=False)
    print(
        f"  (c) as a CLI in a fresh process (/usr/bin/time, no --json): {wall:.2f} s wall "
        f"including start-up ({MISSION_S / wall:.0f}x real time), peak RSS {rss / 1024:.0f} MB"
    )


# -- memory ------------------------------------------------------------------------------------


def time_binary() -> str:
    binary = "/usr/bin/time"
    if not Path(binary).exists():
        print("/usr/bin/time is missing: installing it (apt-get install -y time)")
        subprocess.run(["apt-get", "install", "-y", "time"], check=True)
    return binary


def peak_rss(bag: Path, params: Path, *, json_report: bool = True) -> tuple[int, float]:
    """Peak RSS (kB) and wall time (s) of ``analyze`` on ``bag`` in a fresh process."""
    report = ["--json", "/dev/null"] if json_report else []
    command = [
        time_binary(),
        "-v",
        sys.executable,
        "-m",
        "medkit_replay.cli",
        "analyze",
        str(bag),
        "--quiet",
        *report,
        "--config",
        str(params),
    ]
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise SystemExit(f"analyze failed ({done.returncode}):\n{done.stderr}")
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", done.stderr)
    wall = re.search(r"Elapsed \(wall clock\) time .*: (?:(\d+):)?(\d+):([\d.]+)", done.stderr)
    if rss is None or wall is None:
        raise SystemExit(f"unexpected /usr/bin/time output:\n{done.stderr}")
    hours, minutes, seconds = wall.groups()
    return int(rss[1]), int(hours or 0) * 3600 + int(minutes) * 60 + float(seconds)


def baseline_rss() -> int:
    """Peak RSS (kB) of an interpreter that only imports the CLI: the floor of any run."""
    done = subprocess.run(
        [time_binary(), "-v", sys.executable, "-c", "import medkit_replay.cli"],
        capture_output=True,
        text=True,
        check=True,
    )
    match = re.search(r"Maximum resident set size \(kbytes\): (\d+)", done.stderr)
    assert match is not None
    return int(match[1])


def memory(root: Path, params: Path, sizes_gb: tuple[float, float], seed: int) -> None:
    peaks: list[int] = []
    floor = baseline_rss()
    print(f"baseline (python -c 'import medkit_replay.cli'): peak RSS {floor / 1024:.0f} MB")
    for size_gb in sizes_gb:
        bag = recording(root, size_gb, seed)
        load = os.getloadavg()[0]
        rss, wall = peak_rss(bag, params)
        size = disk_size(bag)
        print(
            f"  analyze {size / 1e9:5.2f} GB: peak RSS {rss / 1024:6.0f} MB, {wall:6.1f} s wall, "
            f"{size / 1e6 / wall:5.0f} MB/s (load {load:.2f})",
            flush=True,
        )
        peaks.append(rss)
    ratio = peaks[1] / peaks[0]
    verdict = "within" if ratio <= 1.5 else "NOT within"
    print(
        f"peak RSS {sizes_gb[1]:g} GB / {sizes_gb[0]:g} GB = {ratio:.2f} "
        f"({verdict} the 1.5x target)"
    )


# -- profile -----------------------------------------------------------------------------------


def profile(bag: Path, params: Path, top: int) -> None:
    profiler = cProfile.Profile()
    profiler.enable()
    messages = medkit_analyze(bag, params)
    profiler.disable()
    for order in ("tottime", "cumulative"):
        out = io.StringIO()
        stats = pstats.Stats(profiler, stream=out)
        stats.sort_stats(order).print_stats(top)
        print(f"--- analyze of {messages:,} messages, top {top} by {order} ---")
        print(out.getvalue())


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--size-gb", type=float, default=1.0, help="throughput recording size")
    parser.add_argument("--out", type=Path, default=None, help="keep recordings here")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--repeat", type=int, default=3, help="runs per reader; fastest kept")
    parser.add_argument(
        "--no-straightforward", action="store_true", help="skip (d), the AnyReader pipeline"
    )
    parser.add_argument("--memory", action="store_true", help="peak RSS mode")
    parser.add_argument("--small-gb", type=float, default=0.2)
    parser.add_argument("--large-gb", type=float, default=2.0)
    parser.add_argument("--profile", action="store_true", help="cProfile analyze instead")
    parser.add_argument(
        "--mission-hour",
        action="store_true",
        help="the one-hour mission (10 Hz x 20 statuses, 5 actions, 50 rosout/s, 5 GB camera)",
    )
    parser.add_argument("--top", type=int, default=25, help="functions listed by --profile")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-recording-") as tmp:
        root = args.out or Path(tmp)
        root.mkdir(parents=True, exist_ok=True)
        params = Path(tmp) / "params.yaml"
        params.write_text(PARAMS)
        if args.mission_hour:
            mission_hour(root, params, max(args.repeat, 1), args.seed)
        elif args.memory:
            memory(root, params, (args.small_gb, args.large_gb), args.seed)
        elif args.profile:
            profile(recording(root, args.size_gb, args.seed), params, args.top)
        else:
            bag = recording(root, args.size_gb, args.seed)
            throughput(bag, params, max(args.repeat, 1), not args.no_straightforward)


if __name__ == "__main__":
    main()
