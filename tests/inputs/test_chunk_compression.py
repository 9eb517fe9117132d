"""MCAP chunks compressed with lz4 or zstd (as other writers than rosbag2 produce) are read."""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest
from mcap.writer import CompressionType, Writer

from medkit_replay.inputs import open_recording
from medkit_replay.msgdefs import base_typestore

if TYPE_CHECKING:
    from pathlib import Path

DIAG = "diagnostic_msgs/msg/DiagnosticArray"


def diagnostics(t_ns: int, level: int) -> bytes:
    store = base_typestore()
    types = store.types
    status = types["diagnostic_msgs/msg/DiagnosticStatus"](
        level=level, name="motor temp", message="hot", hardware_id="", values=[]
    )
    header = types["std_msgs/msg/Header"](
        stamp=types["builtin_interfaces/msg/Time"](sec=t_ns // 10**9, nanosec=t_ns % 10**9),
        frame_id="",
    )
    return bytes(store.serialize_cdr(types[DIAG](header=header, status=[status]), DIAG))


@pytest.mark.parametrize("compression", [CompressionType.LZ4, CompressionType.ZSTD])
def test_compressed_chunks(tmp_path: Path, compression: CompressionType) -> None:
    path = tmp_path / "diag.mcap"
    schema_text = base_typestore().generate_msgdef(DIAG)[0]
    with path.open("wb") as stream:
        writer = Writer(stream, compression=compression, chunk_size=256)
        writer.start(profile="ros2", library="test")
        schema = writer.register_schema(DIAG, "ros2msg", schema_text.encode())
        channel = writer.register_channel("/diagnostics", "cdr", schema)
        for i in range(20):
            t_ns = 1_000_000_000 + i * 100_000_000
            writer.add_message(channel, t_ns, diagnostics(t_ns, i % 3), t_ns, sequence=i)
        writer.finish()  # type: ignore[no-untyped-call]  # mcap ships it untyped
    with open_recording([path]) as recording:
        messages = list(recording.messages())
        warnings = recording.warnings
    assert warnings == []
    assert [m.t_ns for m in messages] == [1_000_000_000 + i * 100_000_000 for i in range(20)]
    levels = [m.msg.status[0].level for m in messages]  # type: ignore[attr-defined]
    assert levels == [i % 3 for i in range(20)]
