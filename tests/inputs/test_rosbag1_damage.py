"""Damaged ROS 1 bags: unindexed, truncated, corrupt chunks, hostile length fields, non-bags.

The rule of tests/inputs/test_damage.py: everything readable is read, a warning names the file and
the loss, never a traceback; InputError (one line naming the path) only when nothing can be read.
"""

from __future__ import annotations

import tracemalloc
from typing import TYPE_CHECKING, Any

import pytest

from medkit_replay.errors import InputError
from medkit_replay.inputs import Message, open_recording
from tests.inputs.ros1_builders import (
    MAGIC,
    chunk_messages,
    diag1,
    index_pos,
    log1,
    patched,
    records,
    unindexed,
    write_bag1,
)

if TYPE_CHECKING:
    from pathlib import Path

T = 1_700_000_000 * 10**9
COUNT = 60
OP_CHUNK, OP_MSG_DATA = 0x05, 0x02


def attempt(path: Path) -> tuple[list[Message], list[str]] | InputError:
    """Read a damaged bag; an InputError is returned, any other exception fails the test."""
    try:
        with open_recording([path], rosout=True) as recording:
            return list(recording.messages()), list(recording.warnings)
    except InputError as exc:
        assert "\n" not in str(exc)
        assert str(exc).startswith(f"{path}: ")
        return exc


def good_bag(tmp_path: Path, chunks: Any = "none", name: str = "good.bag") -> Path:
    recs = []
    for k in range(COUNT):
        recs.append(diag1(T + k * 10**8, f"s{k}"))
        if k % 6 == 0:
            recs.append(log1(T + k * 10**8 + 1, 8, f"line {k}"))
    return write_bag1(tmp_path / name, recs, chunks, chunk_bytes=600)


def times(messages: list[Message]) -> list[int]:
    return [m.t_ns for m in messages]


def full(path: Path) -> list[Message]:
    got = attempt(path)
    assert not isinstance(got, InputError)
    messages, warnings = got
    assert warnings == []
    return messages


def chunk_spans(path: Path) -> list[tuple[int, int, int]]:
    """(position, start, end) of each chunk's data."""
    return [(r.start, r.data_start, r.end) for r in records(path) if r.op == OP_CHUNK]


@pytest.mark.parametrize("chunks", ["none", "bz2", "lz4"])
def test_an_unindexed_bag_is_read_whole_with_a_warning(tmp_path: Path, chunks: Any) -> None:
    bag = good_bag(tmp_path, chunks)
    cut = unindexed(bag, tmp_path / "unindexed.bag")
    got = attempt(cut)
    assert not isinstance(got, InputError)
    messages, warnings = got
    assert times(messages) == times(full(bag))
    assert warnings == [
        f"{cut}: not indexed (the recorder stopped before writing its index?); "
        "its chunks are scanned; how much was lost is unknown"
    ]
    with open_recording([cut]) as recording:
        list(recording.messages())
        (summary,) = recording.inputs
    assert summary.message_count == COUNT + COUNT // 6  # counted while scanning


@pytest.mark.parametrize("chunks", ["none", "bz2", "lz4"])
def test_a_truncated_bag_keeps_every_whole_chunk(tmp_path: Path, chunks: Any) -> None:
    bag = good_bag(tmp_path, chunks)
    expected = times(full(bag))
    data = bag.read_bytes()
    spans = chunk_spans(bag)
    by_chunk = chunk_messages(bag)
    assert len(spans) > 5
    step = max(1, len(data) // 97)
    for size in range(0, len(data), step):
        cut = tmp_path / f"cut_{size}.bag"
        cut.write_bytes(data[:size])
        got = attempt(cut)
        if isinstance(got, InputError):
            assert size < spans[0][0]  # only a cut inside the magic or the bag header
            continue
        messages, warnings = got
        assert warnings, size
        assert all(w.startswith(f"{cut}: ") for w in warnings)
        kept = times(messages)
        assert set(kept) <= set(expected)
        assert kept == sorted(kept)
        whole = {t for end, chunk in by_chunk if end <= size for t in chunk}
        assert whole <= set(kept), size  # every message of the chunks before the cut


def unindexed_copy(path: Path) -> Path:
    data = bytearray(path.read_bytes())
    at = data.index(b"index_pos=", len(MAGIC)) + len(b"index_pos=")
    data[at : at + 8] = bytes(8)
    path.write_bytes(bytes(data))
    return path


def test_a_bag_cut_inside_its_index_is_scanned(tmp_path: Path) -> None:
    bag = good_bag(tmp_path, "lz4")
    size = (index_pos(bag) + bag.stat().st_size) // 2
    cut = tmp_path / "cut_index.bag"
    cut.write_bytes(bag.read_bytes()[:size])
    got = attempt(cut)
    assert not isinstance(got, InputError)
    messages, warnings = got
    assert times(messages) == times(full(bag))
    assert len(warnings) == 1
    assert warnings[0].startswith(f"{cut}: index is damaged (")
    assert warnings[0].endswith("; its chunks are scanned; no message lost")


@pytest.mark.parametrize("chunks", ["bz2", "lz4"])
def test_a_corrupt_compressed_chunk_costs_that_chunk(tmp_path: Path, chunks: Any) -> None:
    bag = good_bag(tmp_path, chunks)
    expected = times(full(bag))
    pos, start, end = chunk_spans(bag)[2]
    middle = (start + end) // 2
    damaged = patched(bag, tmp_path / "corrupt.bag", middle, b"\xa5\x5a\xa5\x5a\xa5\x5a")
    got = attempt(damaged)
    assert not isinstance(got, InputError)
    messages, warnings = got
    assert warnings == [
        w
        for w in warnings
        if w.startswith(f"{damaged}: chunk at byte {pos} cannot be decompressed")
    ]
    assert len(warnings) == 1
    kept = times(messages)
    assert set(kept) < set(expected)
    assert len(expected) - len(kept) < 10  # one chunk of a few messages
    lost = sorted(set(expected) - set(kept))
    assert warnings[0].endswith(
        f"; {len(lost)} messages ({end - pos:,} bytes) from bag time "
        f"{lost[0] / 1e9:.3f} s to {lost[-1] / 1e9:.3f} s skipped"
    )


def test_a_corrupt_record_in_a_plain_chunk_keeps_those_before_it(tmp_path: Path) -> None:
    bag = good_bag(tmp_path)
    expected = times(full(bag))
    pos, start, _ = chunk_spans(bag)[3]
    data = bag.read_bytes()
    # The second record of the chunk: give it a header length running past the chunk.
    first_len = int.from_bytes(data[start : start + 4], "little")
    second = (
        start
        + 8
        + first_len
        + int.from_bytes(data[start + 4 + first_len : start + 8 + first_len], "little")
    )
    damaged = patched(bag, tmp_path / "corrupt.bag", second, (0xFFFFFF00).to_bytes(4, "little"))
    got = attempt(damaged)
    assert not isinstance(got, InputError)
    messages, warnings = got
    assert len(warnings) == 1
    assert warnings[0].startswith(f"{damaged}: chunk at byte {pos}: record at byte ")
    assert "runs past it; the 1 messages before it are kept; " in warnings[0]
    assert set(times(messages)) < set(expected)
    lost = len(expected) - len(messages)
    assert f"; {lost} messages (size unknown) from bag time " in warnings[0]


@pytest.mark.parametrize(
    ("where", "value", "warning"),
    [
        ("chunk_header_len", 0xFFFFFFF0, "damaged record at byte"),
        ("chunk_data_len", 0xFFFFFFF0, "damaged record at byte"),
        ("chunk_data_len", 0x3FFFFFF0, "file ends inside a record"),
        ("chunk_size", 0xFFFFFFF0, "bytes uncompressed: damaged"),
        ("chunk_size", 0x3FFFFFF0, "cannot be decompressed"),
        ("message_data_len", 0xFFFFFFF0, "runs past it"),
        ("index_pos", 0xFFFFFFFFFFFFFFF0, "is beyond the end of the file"),
        ("chunk_info_count", 0xFFFFFFF0, "index is damaged"),
    ],
)
def test_hostile_length_fields_allocate_little(
    tmp_path: Path, where: str, value: int, warning: str
) -> None:
    bag = good_bag(tmp_path, "lz4")
    offset, size = _field(bag, where)
    damaged = patched(bag, tmp_path / f"{where}.bag", offset, value.to_bytes(size, "little"))
    tracemalloc.start()
    try:
        got = attempt(damaged)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 32 * 1024 * 1024, peak
    assert not isinstance(got, InputError)
    _, warnings = got
    assert any(warning in w for w in warnings), warnings


def _field(bag: Path, where: str) -> tuple[int, int]:
    """Offset and size of a length field to damage in the second chunk (or the bag header)."""
    data = bag.read_bytes()
    if where == "index_pos":
        return data.index(b"index_pos=") + len(b"index_pos="), 8
    if where == "chunk_info_count":
        at = data.index(b"\x0a\x00\x00\x00count=", index_pos(bag))
        return at + len(b"\x0a\x00\x00\x00count="), 4
    pos, start, _ = chunk_spans(bag)[1]
    header_len = int.from_bytes(data[pos : pos + 4], "little")
    if where == "chunk_header_len":
        return pos, 4
    if where == "chunk_data_len":
        return pos + 4 + header_len, 4
    if where == "chunk_size":
        return data.index(b"size=", pos) + len(b"size="), 4
    assert where == "message_data_len"
    plain = write_bag1(bag.with_name("plain.bag"), [diag1(T), diag1(T + 1)])
    pos, start, _ = chunk_spans(plain)[0]
    raw = plain.read_bytes()
    # the chunk's first record is a connection record; the message comes after it
    conn_len = int.from_bytes(raw[start : start + 4], "little")
    conn_end = (
        start
        + 8
        + conn_len
        + int.from_bytes(raw[start + 4 + conn_len : start + 8 + conn_len], "little")
    )
    msg_header = int.from_bytes(raw[conn_end : conn_end + 4], "little")
    bag.write_bytes(raw)
    return conn_end + 4 + msg_header, 4


@pytest.mark.parametrize(
    ("content", "reason"),
    [
        (b"", "empty file, not a ROS 1 bag"),
        (b"not a bag at all, just text\n" * 4, "not a ROS 1 bag (bad magic)"),
        (b"#ROSBAG V1.2\n" + bytes(64), "ROS 1 bag of format '1.2'; only 2.0 is read"),
        (MAGIC + b"\xff\xff\xff\x7f", "ROS 1 bag header record is damaged"),
        (MAGIC + bytes(3), "ROS 1 bag header record is damaged (the file ends inside it)"),
    ],
)
def test_a_file_that_is_no_bag_is_one_input_error(
    tmp_path: Path, content: bytes, reason: str
) -> None:
    path = tmp_path / "x.bag"
    path.write_bytes(content)
    got = attempt(path)
    assert isinstance(got, InputError)
    assert str(got).startswith(f"{path}: {reason}")


def _field_bytes(name: bytes, value: bytes) -> bytes:
    return (len(name) + 1 + len(value)).to_bytes(4, "little") + name + b"=" + value


def test_an_encrypted_bag_is_one_input_error(tmp_path: Path) -> None:
    header = b"".join(
        _field_bytes(name, value)
        for name, value in (
            (b"op", b"\x03"),
            (b"index_pos", bytes(8)),
            (b"conn_count", bytes(4)),
            (b"chunk_count", bytes(4)),
            (b"encryptor", b"rosbag/AesCbcEncryptor"),
        )
    )
    path = tmp_path / "secret.bag"
    path.write_bytes(MAGIC + len(header).to_bytes(4, "little") + header + bytes(4))
    got = attempt(path)
    assert isinstance(got, InputError)
    assert str(got) == (
        f"{path}: ROS 1 bag encrypted with 'rosbag/AesCbcEncryptor'; cannot be read"
    )


def test_a_chunk_of_unknown_compression_is_named(tmp_path: Path) -> None:
    bag = good_bag(tmp_path, "lz4")
    pos, _, _ = chunk_spans(bag)[1]
    at = bag.read_bytes().index(b"compression=lz4", pos) + len(b"compression=")
    damaged = patched(bag, tmp_path / "zzz.bag", at, b"zzz")
    got = attempt(damaged)
    assert not isinstance(got, InputError)
    _, warnings = got
    assert len(warnings) == 1
    assert warnings[0].startswith(
        f"{damaged}: chunk at byte {pos}: compression 'zzz' is not supported; it is lost; "
    )
    assert warnings[0].endswith(" skipped")


def test_messages_whose_connection_record_is_lost_are_counted(tmp_path: Path) -> None:
    bag = good_bag(tmp_path)
    spans = chunk_spans(bag)
    data = bag.read_bytes()
    # Cut the first chunk (holding the connection records) out and drop the index.
    first, second = spans[0][0], spans[1][0]
    cut = tmp_path / "orphans.bag"
    cut.write_bytes(data[:first] + data[second : index_pos(bag)])
    unindexed_copy(cut)
    got = attempt(cut)
    assert not isinstance(got, InputError)
    messages, warnings = got
    assert any("belong to connections whose records are lost" in w for w in warnings)
    assert len(messages) < len(full(bag))


def test_the_service_call_pre_pass_reads_no_chunk(tmp_path: Path) -> None:
    """ROS 1 has no ros2_medkit service events: a pass for them reads nothing."""
    bag = good_bag(tmp_path, "lz4")
    pos, start, end = chunk_spans(bag)[2]
    damaged = patched(bag, tmp_path / "corrupt.bag", (start + end) // 2, b"\xa5" * 6)
    cut = unindexed(damaged, tmp_path / "unindexed.bag")
    with open_recording([cut], only_roles=["report_fault"]) as recording:
        assert list(recording.messages()) == []
        assert not [w for w in recording.warnings if f"chunk at byte {pos}" in w]
    with open_recording([cut]) as recording:
        list(recording.messages())
        assert [w for w in recording.warnings if f"chunk at byte {pos}" in w]


def test_a_bag_left_active_by_its_recorder_is_read(tmp_path: Path) -> None:
    """``rosbag record`` writes NAME.bag.active and renames it when done; a crash leaves it so."""
    bag = good_bag(tmp_path)
    active = unindexed(bag, tmp_path / "run_3.bag.active")
    got = attempt(active)
    assert not isinstance(got, InputError)
    messages, warnings = got
    assert times(messages) == times(full(bag))
    assert warnings == [
        f"{active}: not indexed (the recorder stopped before writing its index?); "
        "its chunks are scanned; how much was lost is unknown"
    ]
