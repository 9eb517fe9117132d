"""ROS 1 test bags written in tmp_path with rosbags' rosbag1 Writer, and a test-side record walker.

Builds only what a test asks for: messages in ROS 1 types, bags with a chosen chunk compression,
the same bag without its index; the walker finds records to damage.
"""

from __future__ import annotations

import bz2
import struct
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal, NamedTuple

import lz4.frame  # type: ignore[import-untyped]
from rosbags.rosbag1 import Writer
from rosbags.typesys import Stores, get_typestore

if TYPE_CHECKING:
    from collections.abc import Sequence
    from pathlib import Path

Chunks = Literal["none", "bz2", "lz4"]
TS1 = get_typestore(Stores.ROS1_NOETIC)
MAGIC = b"#ROSBAG V2.0\n"
DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"
GOAL_STATUS_ARRAY = "actionlib_msgs/msg/GoalStatusArray"
LOG = "rosgraph_msgs/msg/Log"


@dataclass(frozen=True, slots=True)
class Rec1:
    """One ROS 1 message to write: topic, type, log time (ns), message object."""

    topic: str
    msgtype: str
    t_ns: int
    msg: object


def new1(msgtype: str, /, **fields: Any) -> object:
    """A message of a ROS 1 Noetic type."""
    return TS1.types[msgtype](**fields)


def time1(t_ns: int) -> object:
    return new1("builtin_interfaces/msg/Time", sec=t_ns // 10**9, nanosec=t_ns % 10**9)


def header1(t_ns: int, seq: int = 7) -> object:
    return new1("std_msgs/msg/Header", seq=seq, stamp=time1(t_ns), frame_id="base")


def diag1(
    t_ns: int, name: str = "motor", level: int = 2, message: str = "hot", hardware_id: str = "hw"
) -> Rec1:
    """A /diagnostics DiagnosticArray with one status holding one key/value pair."""
    status = new1(
        "diagnostic_msgs/msg/DiagnosticStatus",
        level=level,
        name=name,
        message=message,
        hardware_id=hardware_id,
        values=[new1("diagnostic_msgs/msg/KeyValue", key="temp", value="91")],
    )
    return Rec1(
        "/diagnostics",
        DIAGNOSTIC_ARRAY,
        t_ns,
        new1(DIAGNOSTIC_ARRAY, header=header1(t_ns), status=[status]),
    )


def status1(t_ns: int, *goals: tuple[str, int], topic: str = "/navigate/status") -> Rec1:
    """An actionlib GoalStatusArray listing (goal id, actionlib status code) pairs."""
    listed = [
        new1(
            "actionlib_msgs/msg/GoalStatus",
            goal_id=new1("actionlib_msgs/msg/GoalID", stamp=time1(t_ns - 10**9), id=goal_id),
            status=code,
            text="",
        )
        for goal_id, code in goals
    ]
    msg = new1(GOAL_STATUS_ARRAY, header=header1(t_ns), status_list=listed)
    return Rec1(topic, GOAL_STATUS_ARRAY, t_ns, msg)


def log1(
    t_ns: int, level: int = 8, text: str = "boom", name: str = "/node", topic: str = "/rosout"
) -> Rec1:
    """A rosgraph_msgs/Log line (ROS 1 levels: 1, 2, 4, 8, 16)."""
    msg = new1(
        LOG,
        header=header1(t_ns),
        level=level,
        name=name,
        msg=text,
        file="node.cpp",
        function="loop",
        line=42,
        topics=["/rosout"],
    )
    return Rec1(topic, LOG, t_ns, msg)


def string1(t_ns: int, topic: str = "/chatter", text: str = "x" * 40) -> Rec1:
    """A std_msgs/String: a topic no bridge reads."""
    return Rec1(topic, "std_msgs/msg/String", t_ns, new1("std_msgs/msg/String", data=text))


def write_bag1(
    path: Path, records: Sequence[Rec1], chunks: Chunks = "none", chunk_bytes: int = 1 << 20
) -> Path:
    """Write records (in the order given) as a ROS 1 bag; a new chunk after ``chunk_bytes``."""
    writer = Writer(path)
    if chunks != "none":
        writer.set_compression(Writer.CompressionFormat[chunks.upper()])
    writer.chunk_threshold = chunk_bytes
    connections: dict[str, Any] = {}
    with writer:
        for rec in records:
            if rec.topic not in connections:
                connections[rec.topic] = writer.add_connection(
                    rec.topic, rec.msgtype, typestore=TS1, callerid="/recorder"
                )
            data = bytes(TS1.serialize_ros1(rec.msg, rec.msgtype))
            writer.write(connections[rec.topic], rec.t_ns, data)
    return path


class Record(NamedTuple):
    """A top-level record of a well-formed bag: its op and byte offsets in the file."""

    op: int
    start: int  # its header length field
    data_start: int
    end: int


def records(path: Path) -> list[Record]:
    """The top-level records of a well-formed bag, in file order (test-side parser)."""
    data = path.read_bytes()
    pos, found = len(MAGIC), []
    while pos < len(data):
        (header_len,) = struct.unpack_from("<I", data, pos)
        header = data[pos + 4 : pos + 4 + header_len]
        op = header[header.index(b"op=") + 3]
        (data_len,) = struct.unpack_from("<I", data, pos + 4 + header_len)
        data_start = pos + 8 + header_len
        found.append(Record(op, pos, data_start, data_start + data_len))
        pos = data_start + data_len
    return found


def index_pos(path: Path) -> int:
    """Where a bag's index starts: the first connection record after the last chunk's indexes."""
    listed = records(path)
    last_chunk = max(k for k, r in enumerate(listed) if r.op == 0x05)
    following = [r for r in listed[last_chunk + 1 :] if r.op != 0x04]
    return following[0].start


def unindexed(source: Path, target: Path) -> Path:
    """The bag as a recorder leaves it when stopped before writing its index: the index cut off,
    the bag header's ``index_pos``, ``conn_count`` and ``chunk_count`` zero."""
    data = bytearray(source.read_bytes()[: index_pos(source)])
    for name, size in ((b"index_pos=", 8), (b"conn_count=", 4), (b"chunk_count=", 4)):
        at = data.index(name, len(MAGIC)) + len(name)
        data[at : at + size] = bytes(size)
    target.write_bytes(bytes(data))
    return target


def patched(source: Path, target: Path, offset: int, value: bytes) -> Path:
    """A copy of ``source`` with ``value`` written over the bytes at ``offset``."""
    data = bytearray(source.read_bytes())
    data[offset : offset + len(value)] = value
    target.write_bytes(bytes(data))
    return target


def _fields(header: bytes) -> dict[bytes, bytes]:
    out, pos = {}, 0
    while pos < len(header):
        (length,) = struct.unpack_from("<I", header, pos)
        name, _, value = header[pos + 4 : pos + 4 + length].partition(b"=")
        out[name] = value
        pos += 4 + length
    return out


def chunk_messages(path: Path) -> list[tuple[int, list[int]]]:
    """(end offset, log times of its messages) of each chunk of a well-formed bag (test-side)."""
    data = path.read_bytes()
    found = []
    for record in records(path):
        if record.op != 0x05:
            continue
        (header_len,) = struct.unpack_from("<I", data, record.start)
        compression = _fields(data[record.start + 4 : record.start + 4 + header_len])[
            b"compression"
        ]
        body = data[record.data_start : record.end]
        body = {b"none": bytes, b"bz2": bz2.decompress, b"lz4": lz4.frame.decompress}[compression](
            body
        )
        pos, t_ns = 0, []
        while pos < len(body):
            (inner_len,) = struct.unpack_from("<I", body, pos)
            fields = _fields(body[pos + 4 : pos + 4 + inner_len])
            (data_len,) = struct.unpack_from("<I", body, pos + 4 + inner_len)
            if fields[b"op"] == b"\x02":
                sec, nsec = struct.unpack("<II", fields[b"time"])
                t_ns.append(sec * 10**9 + nsec)
            pos += 8 + inner_len + data_len
        found.append((record.end, t_ns))
    return found
