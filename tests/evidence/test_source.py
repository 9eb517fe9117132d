"""The evidence source over MCAP files: the replay's reader, windows by time, damage as notes.

What is read is checked against the mcap library's reader (tests/inputs/test_mcap_window.py
checks the windows themselves); here: the source's own queries, and damage inside a window.
"""

from __future__ import annotations

import tracemalloc
from typing import TYPE_CHECKING

from mcap.reader import SeekingReader

from medkit_replay.evidence.source import EvidenceSource, RawMessage
from tests.inputs.builders import write_mcap

if TYPE_CHECKING:
    from pathlib import Path

TOPICS = ("/camera", "/diagnostics", "/odom", "/tf")


def mission(path: Path, compression: str = "zstd") -> Path:
    """Four topics every 10 ns from t=1000, 500-byte payloads: about 130 chunks."""
    messages = [
        (1_000 + 10 * k, TOPICS[k % 4], k.to_bytes(4, "little") * 125) for k in range(2_000)
    ]
    return write_mcap(path, messages, compression)


def chunk_offsets(path: Path) -> list[tuple[int, int, int]]:
    """(offset, first log time, last log time) of each chunk."""
    with path.open("rb") as stream:
        summary = SeekingReader(stream).get_summary()
    assert summary is not None
    return [
        (c.chunk_start_offset, c.message_start_time, c.message_end_time)
        for c in summary.chunk_indexes
    ]


def test_first_last_and_ranges(tmp_path: Path) -> None:
    path = mission(tmp_path / "m.mcap")
    source = EvidenceSource([path])
    try:
        assert source.skipped == []
        assert source.topics["/odom"].type == "std_msgs/msg/String"
        assert [(m.t_ns, m.topic) for m in source.read(["/tf", "/odom"], 5_000, 5_035)] == [
            (5_020, "/odom"),
            (5_030, "/tf"),
        ]
        first = source.first("/tf", 5_030, 6_000)  # strictly after
        assert first is not None and first.t_ns == 5_070
        last = source.last("/tf", 5_069, 10_000)
        assert last == RawMessage(5_030, "/tf", (403).to_bytes(4, "little") * 125)
        assert source.last("/tf", 5_069, 100) is None  # every payload is larger
        assert source.last("/tf", 500, 10_000) is None
        assert source.any_between(["/camera"], 5_000, 5_000)
        assert not source.any_between(["/camera"], 5_001, 5_039)
    finally:
        source.close()


def test_a_hostile_chunk_in_a_window_is_noted_not_inflated(tmp_path: Path) -> None:
    path = mission(tmp_path / "m.mcap")
    data = bytearray(path.read_bytes())
    offset, start_ns, end_ns = chunk_offsets(path)[40]
    # The chunk's uncompressed size (after opcode, length, start and end times): 1 GB claimed.
    data[offset + 25 : offset + 33] = (1 << 30).to_bytes(8, "little")
    path.write_bytes(bytes(data))
    source = EvidenceSource([path])
    try:
        tracemalloc.start()
        got = list(source.read(TOPICS, start_ns - 100, end_ns + 100))
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    finally:
        source.close()
    assert peak < 16 * 1024 * 1024
    times = [m.t_ns for m in got]
    assert times == [
        t for t in range(start_ns - 100, end_ns + 101, 10) if not start_ns <= t <= end_ns
    ]
    (note,) = source.skipped
    assert note.startswith(f"{path}: chunk at byte {offset} (log times {start_ns}..{end_ns})")
    assert "cannot be decompressed" in note


def test_a_damaged_chunk_is_noted_once_and_the_rest_is_read(tmp_path: Path) -> None:
    path = mission(tmp_path / "m.mcap")
    data = bytearray(path.read_bytes())
    offset, start_ns, end_ns = chunk_offsets(path)[10]
    data[offset + 80 : offset + 90] = bytes(10)  # inside the zstd frame
    path.write_bytes(bytes(data))
    source = EvidenceSource([path])
    try:
        for _ in range(2):
            got = list(source.read(["/odom"], start_ns - 40, end_ns + 40))
            assert got and all(not start_ns <= m.t_ns <= end_ns for m in got)
        assert source.last("/odom", end_ns, 10_000) == source.last("/odom", start_ns - 1, 10_000)
    finally:
        source.close()
    (note,) = source.skipped
    assert note.startswith(f"{path}: chunk at byte {offset}")


def test_a_truncated_file_is_not_read_for_evidence(tmp_path: Path) -> None:
    path = mission(tmp_path / "m.mcap")
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    source = EvidenceSource([path])
    source.close()
    assert source.files == []
    assert source.skipped == [
        f"{path}: not read for evidence: no summary section (a truncated file?)"
    ]


def test_an_unchunked_file_is_not_read_for_evidence(tmp_path: Path) -> None:
    # Windows are read through the chunk index; without one every capture would scan the file.
    path = write_mcap(tmp_path / "m.mcap", [(1_000, "/tf", b"x")], chunked=False)
    source = EvidenceSource([path])
    source.close()
    assert source.skipped == [
        f"{path}: not read for evidence: no chunk index in its summary section"
    ]
