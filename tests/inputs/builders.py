"""Test bags written in tmp_path with rosbags' Writer from constructed messages, and damage helpers.

Builds only files a test asks for; reads nothing from /work/shared.
"""

from __future__ import annotations

import shutil
import sqlite3
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import yaml
from mcap.writer import CompressionType, Writer as PlainWriter
from rosbags.rosbag2 import Writer
from rosbags.rosbag2.enums import CompressionFormat, CompressionMode, StoragePlugin
from rosbags.rosbag2.storage_mcap import McapWriter

from medkit_replay.msgdefs import base_typestore

if TYPE_CHECKING:
    from collections.abc import Iterable, Sequence

Storage = Literal["mcap", "sqlite3"]
Compression = Literal["none", "file", "message", "chunk"]

TS = base_typestore()
FAKE_HASH = "RIHS01_" + "0" * 64
INTERFACES = Path(__file__).parents[2] / "medkit_replay" / "inputs" / "interfaces"
REPORT_FAULT = "ros2_medkit_msgs/srv/ReportFault_Event"
CLEAR_FAULT = "ros2_medkit_msgs/srv/ClearFault_Event"
DIAGNOSTICS = "diagnostic_msgs/msg/DiagnosticArray"


@dataclass(frozen=True, slots=True)
class Rec:
    """One message to write: topic, type, log time (ns), message object."""

    topic: str
    msgtype: str
    t_ns: int
    msg: object


def _new(msgtype: str, /, **fields: Any) -> object:
    return TS.types[msgtype](**fields)


def stamp(t_ns: int) -> object:
    return _new("builtin_interfaces/msg/Time", sec=t_ns // 10**9, nanosec=t_ns % 10**9)


def diag(t_ns: int, name: str = "motor", level: int = 2, message: str = "hot") -> Rec:
    """A /diagnostics message with one status."""
    header = _new("std_msgs/msg/Header", stamp=stamp(t_ns), frame_id="")
    status = _new(
        "diagnostic_msgs/msg/DiagnosticStatus",
        level=level,
        name=name,
        message=message,
        hardware_id="hw",
        values=[_new("diagnostic_msgs/msg/KeyValue", key="k", value="v")],
    )
    return Rec("/diagnostics", DIAGNOSTICS, t_ns, _new(DIAGNOSTICS, header=header, status=[status]))


def goal_status(t_ns: int, status: int, topic: str = "/navigate/_action/status") -> Rec:
    """A GoalStatusArray with one goal in ``status``."""
    info = _new(
        "action_msgs/msg/GoalInfo",
        goal_id=_new("unique_identifier_msgs/msg/UUID", uuid=np.arange(16, dtype=np.uint8)),
        stamp=stamp(t_ns),
    )
    goal = _new("action_msgs/msg/GoalStatus", goal_info=info, status=status)
    name = "action_msgs/msg/GoalStatusArray"
    return Rec(topic, name, t_ns, _new(name, status_list=[goal]))


def log(t_ns: int, level: int = 40, text: str = "boom", name: str = "node") -> Rec:
    """A /rosout message."""
    msg = _new(
        "rcl_interfaces/msg/Log",
        stamp=stamp(t_ns),
        level=level,
        name=name,
        msg=text,
        file="f.cpp",
        function="fn",
        line=1,
    )
    return Rec("/rosout", "rcl_interfaces/msg/Log", t_ns, msg)


def _event_info(t_ns: int, event_type: int, sequence: int) -> object:
    return _new(
        "service_msgs/msg/ServiceEventInfo",
        event_type=event_type,
        stamp=stamp(t_ns),
        client_gid=np.full(16, 7, dtype=np.uint8),
        sequence_number=sequence,
    )


def report_fault(t_ns: int, code: str = "MOTOR_HOT", event_type: int = 1, sequence: int = 1) -> Rec:
    """A ReportFault service event carrying the request (REQUEST_RECEIVED by default)."""
    request = _new(
        "ros2_medkit_msgs/srv/ReportFault_Request",
        fault_code=code,
        event_type=0,
        severity=2,
        description="too hot",
        source_id="/motor",
    )
    info = _event_info(t_ns, event_type, sequence)
    msg = _new(REPORT_FAULT, info=info, request=[request], response=[])
    return Rec("/fault_manager/report_fault/_service_event", REPORT_FAULT, t_ns, msg)


def clear_fault(t_ns: int, code: str = "MOTOR_HOT", sequence: int = 1) -> Rec:
    """A ClearFault service event (REQUEST_RECEIVED)."""
    request = _new(
        "ros2_medkit_msgs/srv/ClearFault_Request",
        fault_code=code,
        skip_correlation_auto_clear=False,
    )
    msg = _new(CLEAR_FAULT, info=_event_info(t_ns, 1, sequence), request=[request], response=[])
    return Rec("/fault_manager/clear_fault/_service_event", CLEAR_FAULT, t_ns, msg)


def fault_event(t_ns: int, code: str = "MOTOR_HOT") -> Rec:
    """A FaultEvent as the live fault manager publishes it."""
    fault = _new(
        "ros2_medkit_msgs/msg/Fault",
        fault_code=code,
        severity=2,
        description="too hot",
        first_occurred=stamp(t_ns),
        last_occurred=stamp(t_ns),
        last_passed=stamp(0),
        occurrence_count=1,
        status="CONFIRMED",
        reporting_sources=["/motor"],
    )
    name = "ros2_medkit_msgs/msg/FaultEvent"
    msg = _new(
        name,
        event_type="fault_confirmed",
        fault=fault,
        timestamp=stamp(t_ns),
        auto_cleared_codes=[],
    )
    return Rec("/fault_manager/events", name, t_ns, msg)


def string_msg(t_ns: int, topic: str = "/chatter", text: str = "x") -> Rec:
    """A std_msgs/String on an unselected topic."""
    return Rec(topic, "std_msgs/msg/String", t_ns, _new("std_msgs/msg/String", data=text))


def _definition(msgtype: str, definitions: bool) -> str:
    if not definitions:
        return ""
    if "/srv/" in msgtype:
        # rosbag2 stores the service's .srv text as a service event topic's definition.
        name = msgtype.rsplit("/", maxsplit=1)[-1].removesuffix("_Event")
        return (INTERFACES / "ros2_medkit_msgs" / "srv" / f"{name}.srv").read_text()
    return TS.generate_msgdef(msgtype, ros_version=2)[0]


def write_bag(
    path: Path,
    records: Iterable[Rec],
    *,
    storage: Storage = "mcap",
    compression: Compression = "none",
    definitions: bool = True,
    chunk_every: int | None = None,
    serialization: str = "cdr",
) -> Path:
    """Write records (in the given order) as a rosbag2 directory; returns its path.

    Args:
        definitions: store message definitions (False: empty ones, as old bags have).
        chunk_every: MCAP only: close a chunk after this many messages.
    """
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    writer = Writer(path, version=9, storage_plugin=plugin)
    modes = {"file": CompressionMode.FILE, "message": CompressionMode.MESSAGE}
    modes["chunk"] = CompressionMode.STORAGE
    if compression != "none":
        writer.set_compression(modes[compression], CompressionFormat.ZSTD)
    connections = {}
    with writer:
        for count, rec in enumerate(records, 1):
            key = (rec.topic, rec.msgtype)
            if key not in connections:
                connections[key] = writer.add_connection(
                    rec.topic,
                    rec.msgtype,
                    msgdef=_definition(rec.msgtype, definitions),
                    rihs01=FAKE_HASH,
                    serialization_format=serialization,
                )
            writer.write(connections[key], rec.t_ns, TS.serialize_cdr(rec.msg, rec.msgtype))
            if chunk_every and count % chunk_every == 0 and isinstance(writer.storage, McapWriter):
                writer.storage.close_chunk()
    return path


def write_bare(path: Path, records: Sequence[Rec], **options: object) -> Path:
    """Write a bag and keep only its storage file, renamed to ``path`` (``.mcap`` or ``.db3``)."""
    storage: Storage = "mcap" if path.suffix == ".mcap" else "sqlite3"
    bag = write_bag(path.with_name(path.stem + "_bag"), records, storage=storage, **options)  # type: ignore[arg-type]
    storage_file = next(p for p in bag.iterdir() if p.suffix in {".mcap", ".db3"})
    storage_file.rename(path)
    shutil.rmtree(bag)
    return path


def storage_file(bag: Path) -> Path:
    """The single storage file of a bag directory."""
    return next(p for p in sorted(bag.iterdir()) if p.name != "metadata.yaml")


def set_metadata(bag: Path, **changes: object) -> None:
    """Change top-level keys of metadata.yaml (None deletes a key)."""
    path = bag / "metadata.yaml"
    document = yaml.safe_load(path.read_text())
    info = document["rosbag2_bagfile_information"]
    for key, value in changes.items():
        if value is None:
            info.pop(key, None)
        else:
            info[key] = value
    path.write_text(yaml.safe_dump(document))


def as_wal(db: Path) -> None:
    """Switch an sqlite3 storage file to WAL journal mode (as rosbag2 may leave it)."""
    with closing(sqlite3.connect(db)) as connection:
        connection.execute("PRAGMA journal_mode=WAL")


def truncated(source: Path, target: Path, size: int) -> Path:
    """A copy of ``source`` cut to ``size`` bytes."""
    target.write_bytes(source.read_bytes()[:size])
    return target


def flipped(source: Path, target: Path, offset: int) -> Path:
    """A copy of ``source`` with every bit of the byte at ``offset`` inverted."""
    data = bytearray(source.read_bytes())
    data[offset] ^= 0xFF
    target.write_bytes(bytes(data))
    return target


def chunks(mcap: Path) -> list[tuple[int, int]]:
    """(start, end) byte offsets of each chunk record of a well-formed MCAP (test-side parser)."""
    data = mcap.read_bytes()
    pos, found = 8, []
    while pos + 9 <= len(data) and data[pos] != 0x0F:
        end = pos + 9 + int.from_bytes(data[pos + 1 : pos + 9], "little")
        if data[pos] == 0x06:
            found.append((pos, end))
        pos = end
    return found


TOPICS = ("/camera", "/diagnostics", "/odom", "/tf")
COMPRESSIONS = {
    "none": CompressionType.NONE,
    "zstd": CompressionType.ZSTD,
    "lz4": CompressionType.LZ4,
}
Message = tuple[int, str, bytes]


def write_mcap(
    path: Path,
    messages: list[Message],
    compression: str = "none",
    chunk_size: int = 8_000,
    crcs: bool = False,
    chunked: bool = True,
) -> Path:
    """A bare MCAP file written by the mcap library, messages in the order given (not sorted:
    chunks may then overlap in time), on TOPICS, their payloads as given."""
    with path.open("wb") as stream:
        writer = PlainWriter(
            stream,
            chunk_size=chunk_size,
            compression=COMPRESSIONS[compression],
            enable_crcs=crcs,
            use_chunking=chunked,
        )
        writer.start(profile="ros2")
        schema = writer.register_schema("std_msgs/msg/String", "ros2msg", b"string data")
        channels = {t: writer.register_channel(t, "cdr", schema) for t in TOPICS}
        for sequence, (t_ns, topic, data) in enumerate(messages):
            writer.add_message(channels[topic], t_ns, data, t_ns, sequence)
        writer.finish()  # type: ignore[no-untyped-call]  # mcap ships it untyped
    return path
