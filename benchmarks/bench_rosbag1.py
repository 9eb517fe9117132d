"""ROS 1 against ROS 2: one recording as a ROS 1 bag, replayed and timed beside the rosbag2 one.

Converts a rosbag2 recording message by message (every topic, camera frames included) into ROS 1
bags (plain and LZ4 chunks) and times, on each, reading the replayed topics and ``replay()``
(log bridge on) in CPU seconds, keeping the fastest of ``--repeat``.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from rosbags.rosbag1 import Writer
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore

from medkit_replay import replay
from medkit_replay.inputs import open_recording
from medkit_replay.msgdefs import base_typestore

TS2 = base_typestore()
TS1 = get_typestore(Stores.ROS1_NOETIC)
STATUS_TO_ROS1 = {1: 0, 2: 1, 3: 6, 4: 3, 5: 2, 6: 4}
"""action_msgs codes to the actionlib codes a ROS 1 server sends (CANCELED: PREEMPTED)."""
LEVEL_TO_ROS1 = {10: 1, 20: 2, 30: 4, 40: 8, 50: 16}


def to_ros1(msg: Any, ros1_type: str) -> object:
    """A ROS 2 message as the ROS 1 type of the same name: fields copied by name, ``seq`` 0."""
    fields = TS1.fielddefs[ros1_type][1]
    values: dict[str, object] = {}
    for name, desc in fields:
        value = getattr(msg, name, None)
        if name == "seq" and value is None:
            value = 0
        elif desc[0] == 2:  # a nested message
            value = to_ros1(value, desc[1])
        elif desc[0] == 4 and desc[1][0][0] == 2:  # a sequence of messages
            value = [to_ros1(item, desc[1][0][1]) for item in value]
        values[name] = value
    return TS1.types[ros1_type](**values)


def goal_status_array(msg: Any, t_ns: int) -> object:
    stamp = TS1.types["builtin_interfaces/msg/Time"](sec=t_ns // 10**9, nanosec=t_ns % 10**9)
    goals = [
        TS1.types["actionlib_msgs/msg/GoalStatus"](
            goal_id=TS1.types["actionlib_msgs/msg/GoalID"](
                stamp=to_ros1(goal.goal_info.stamp, "builtin_interfaces/msg/Time"),
                id=bytes(goal.goal_info.goal_id.uuid).hex(),
            ),
            status=STATUS_TO_ROS1.get(goal.status, 9),
            text="",
        )
        for goal in msg.status_list
    ]
    header = TS1.types["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id="")
    return TS1.types["actionlib_msgs/msg/GoalStatusArray"](header=header, status_list=goals)


def log(msg: Any) -> object:
    header = TS1.types["std_msgs/msg/Header"](
        seq=0, stamp=to_ros1(msg.stamp, "builtin_interfaces/msg/Time"), frame_id=""
    )
    return TS1.types["rosgraph_msgs/msg/Log"](
        header=header,
        level=LEVEL_TO_ROS1.get(msg.level, 8),
        name="/" + msg.name,
        msg=msg.msg,
        file=msg.file,
        function=msg.function,
        line=msg.line,
        topics=[],
    )


def convert(source: Path, targets: dict[str, Path]) -> int:
    """Write ``source`` as ROS 1 bags, one per chunk compression; returns the message count."""
    writers: dict[str, Writer] = {}
    for compression, path in targets.items():
        writer = Writer(path)
        if compression != "none":
            writer.set_compression(Writer.CompressionFormat[compression.upper()])
        writer.open()
        writers[compression] = writer
    connections: dict[tuple[str, int], Any] = {}
    count = 0
    with Reader(source) as reader:
        for connection, t_ns, raw in reader.messages():
            msg: Any = TS2.deserialize_cdr(raw, connection.msgtype)
            topic, msgtype = connection.topic, connection.msgtype
            if msgtype == "action_msgs/msg/GoalStatusArray":
                topic = topic.removesuffix("/_action/status") + "/status"
                msgtype, ros1 = "actionlib_msgs/msg/GoalStatusArray", goal_status_array(msg, t_ns)
            elif msgtype == "rcl_interfaces/msg/Log":
                msgtype, ros1 = "rosgraph_msgs/msg/Log", log(msg)
            else:
                ros1 = to_ros1(msg, msgtype)
            data = bytes(TS1.serialize_ros1(ros1, msgtype))
            for compression, writer in writers.items():
                key = (compression, connection.id)
                if key not in connections:
                    connections[key] = writer.add_connection(topic, msgtype, typestore=TS1)
                writer.write(connections[key], t_ns, data)
            count += 1
    for writer in writers.values():
        writer.close()
    return count


def best_of(repeat: int, path: Path, configs: list[Path]) -> tuple[float, float, int]:
    """Fewest CPU seconds over ``repeat`` runs of reading the replayed topics alone and of
    ``replay()``, and the messages read (CPU time: other processes on the machine count less)."""
    reads, replays = [], []
    messages = 0
    for _ in range(repeat):
        start = time.process_time()
        with open_recording([path], rosout=True) as recording:
            messages = sum(1 for _ in recording.message_tuples())
        reads.append(time.process_time() - start)
        start = time.process_time()
        replay([path], configs)
        replays.append(time.process_time() - start)
    return min(reads), min(replays), messages


def main(argv: list[str] | None = None) -> int:
    """Command line: ``python benchmarks/bench_rosbag1.py [SOURCE] [--out DIR] [--repeat N]``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "source", type=Path, nargs="?", default=Path("/work/bench/mission_600s_seed1")
    )
    parser.add_argument("--out", type=Path, help="keep the ROS 1 bags here (default: deleted)")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="bench-rosbag1-")) if args.out is None else args.out
    work.mkdir(parents=True, exist_ok=True)
    try:
        targets = {c: work / f"{args.source.name}_{c}.bag" for c in ("none", "lz4")}
        for path in targets.values():
            path.unlink(missing_ok=True)
        start = time.perf_counter()
        count = convert(args.source, targets)
        took = time.perf_counter() - start
        sys.stdout.write(f"converted {count} messages in {took:.1f} s\n")
        params = work / "log_bridge.yaml"
        params.write_text("medkit_replay:\n  ros__parameters:\n    enable_log_bridge: true\n")
        size = sum(p.stat().st_size for p in args.source.rglob("*") if p.is_file())
        rows = [("rosbag2 " + args.source.name, args.source, size)]
        rows += [(f"ROS 1 bag, chunks {c}", p, p.stat().st_size) for c, p in targets.items()]
        for label, path, nbytes in rows:
            reading, seconds, read = best_of(args.repeat, path, [params])
            sys.stdout.write(
                f"{label:36} {nbytes / 1e6:6.0f} MB  {read} messages read: reading {reading:5.2f}"
                f" s, replay {seconds:5.2f} s CPU ({read / seconds:6.0f} msg/s)\n"
            )
    finally:
        if args.out is None:
            shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
