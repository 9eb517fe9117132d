"""Time windows of MCAP files (McapFile.read_window), against the mcap library's indexed reader.

The window delivers what ``SeekingReader.iter_messages`` does for the same topics and inclusive
range, forward and reverse, over chunks that overlap in time, equal log times and every
compression; it reads no chunk outside the window, and a reverse read that takes one message
reads only the chunks at the window's end.
"""

from __future__ import annotations

import random
from typing import TYPE_CHECKING, Any

import pytest
from mcap.reader import SeekingReader

from medkit_replay.inputs.mcap.plan import ChunkIndex
from medkit_replay.inputs.mcap.reader import McapFile
from medkit_replay.inputs.mcap.window import merge_window, window_chunks
from medkit_replay.inputs.merge import Timed
from medkit_replay.inputs.ranges import LocalRanges, LocalSource
from tests.inputs.builders import COMPRESSIONS, TOPICS, Message, write_mcap

if TYPE_CHECKING:
    from collections.abc import Iterator
    from pathlib import Path


def recording(seed: int, count: int = 400) -> list[Message]:
    """Mostly in time order with stretches written late (overlapping chunks), equal times, and
    a large camera frame now and then (runs worth skipping when read by index)."""
    rng = random.Random(seed)
    messages: list[Message] = []
    t_ns = 1_000
    for k in range(count):
        t_ns += rng.choice((0, 0, 1, 7, 50))
        topic = rng.choice(TOPICS)
        size = rng.choice((3, 40, 200)) if topic != "/camera" else rng.choice((2_000, 6_000))
        messages.append((t_ns - rng.choice((0, 0, 0, 300)), topic, bytes([k % 251]) * size))
    return messages


def oracle(
    path: Path, topics: set[str], start_ns: int, end_ns: int, reverse: bool
) -> list[Message]:
    with path.open("rb") as stream:
        reader = SeekingReader(stream, validate_crcs=False)
        found = reader.iter_messages(
            topics=sorted(topics),
            starting_at=start_ns,
            ending_at=end_ns,
            log_time_order=True,
            reverse=reverse,
        )
        return [(m.log_time, c.topic, m.data) for _, c, m in found]


def window(
    file: McapFile, topics: set[str], start_ns: int, end_ns: int, reverse: bool = False
) -> Iterator[Message]:
    for message in file.read_window(lambda c: c.topic in topics, start_ns, end_ns, reverse=reverse):
        connection, data = message.item
        yield message.t_ns, connection.topic, bytes(data)


@pytest.mark.parametrize("compression", sorted(COMPRESSIONS))
@pytest.mark.parametrize("seed", [1, 2])
def test_windows_read_what_the_mcap_library_reads(
    tmp_path: Path, compression: str, seed: int
) -> None:
    path = write_mcap(tmp_path / "r.mcap", recording(seed), compression)
    warnings: list[str] = []
    file = McapFile(path, 0, lambda text, loss=None, /: warnings.append(text))
    assert file.chunk_indexed
    rng = random.Random(seed)
    for _ in range(40):
        topics = set(rng.sample(TOPICS, rng.randint(1, 3)))
        start_ns = rng.randint(0, 7_000)
        end_ns = start_ns + rng.choice((0, 10, 300, 3_000, 20_000))
        for reverse in (False, True):
            got = list(window(file, topics, start_ns, end_ns, reverse))
            assert got == oracle(path, topics, start_ns, end_ns, reverse)
    assert warnings == []


def test_interleaved_windows_keep_their_own_topics(tmp_path: Path) -> None:
    path = write_mcap(tmp_path / "r.mcap", recording(3))
    file = McapFile(path, 0, print)
    cameras = window(file, {"/camera"}, 0, 2**62)
    odometry = window(file, {"/odom"}, 0, 2**62, reverse=True)
    taken: list[Message] = []
    for camera, odom in zip(cameras, odometry, strict=False):
        taken += [camera, odom]
    assert {m[1] for m in taken[0::2]} == {"/camera"}
    assert {m[1] for m in taken[1::2]} == {"/odom"}
    assert taken[1::2] == oracle(path, {"/odom"}, 0, 2**62, reverse=True)[: len(taken) // 2]


class CountingSource:
    """A local file whose range reads are logged (offset, length)."""

    def __init__(self, path: Path) -> None:
        self.local = LocalSource(path)
        self.reads: list[tuple[int, int]] = []

    def ranges(self) -> Counted:
        return Counted(self.local.ranges(), self.reads)

    def stream(self) -> Any:
        return self.local.stream()


class Counted:
    def __init__(self, inner: LocalRanges, reads: list[tuple[int, int]]) -> None:
        self.inner, self.reads = inner, reads
        self.size, self.always_ahead = inner.size, inner.always_ahead

    def read(self, offset: int, length: int) -> bytes:
        self.reads.append((offset, length))
        return self.inner.read(offset, length)

    def read_into(self, offset: int, view: memoryview) -> int:
        self.reads.append((offset, len(view)))
        return self.inner.read_into(offset, view)

    def cached(self, offset: int, length: int) -> bytes | None:
        self.reads.append((offset, length))
        return self.inner.cached(offset, length)

    def will_need(self, offset: int, length: int) -> None:
        self.inner.will_need(offset, length)

    def forget(self, before: int) -> None:
        self.inner.forget(before)

    def close(self) -> None:
        self.inner.close()

    def __enter__(self) -> Counted:
        return self

    def __exit__(self, *exc: object) -> None:
        self.inner.__exit__(None, None, None)


def chunk_indexes(path: Path) -> list[Any]:
    with path.open("rb") as stream:
        summary = SeekingReader(stream).get_summary()
        assert summary is not None
        return list(summary.chunk_indexes)


def touched(reads: list[tuple[int, int]], chunks: list[Any]) -> list[Any]:
    """The chunks (with their message indexes) the reads fall in; every read must fall in one."""
    found = []
    for offset, length in reads:
        (chunk,) = [
            c
            for c in chunks
            if c.chunk_start_offset <= offset
            and offset + length <= c.chunk_start_offset + c.chunk_length + c.message_index_length
        ]
        found.append(chunk)
    return found


@pytest.mark.parametrize("compression", ["none", "zstd"])
def test_a_window_reads_no_chunk_outside_it(tmp_path: Path, compression: str) -> None:
    messages = [(1_000 + 10 * k, TOPICS[k % 4], bytes(500)) for k in range(2_000)]
    path = write_mcap(tmp_path / "r.mcap", messages, compression)
    chunks = chunk_indexes(path)
    assert len(chunks) > 50
    source = CountingSource(path)
    file = McapFile(path, 0, print, source=source)
    source.reads.clear()
    start_ns, end_ns = 9_000, 9_400
    got = list(window(file, {"/odom", "/tf"}, start_ns, end_ns))
    assert got == oracle(path, {"/odom", "/tf"}, start_ns, end_ns, reverse=False)
    assert got and source.reads
    for chunk in touched(source.reads, chunks):
        assert chunk.message_start_time <= end_ns and chunk.message_end_time >= start_ns
    read = sum(length for _, length in source.reads)
    assert read < 6 * max(c.chunk_length for c in chunks)


def test_the_latest_message_is_found_reading_back_from_the_window_end(tmp_path: Path) -> None:
    # /tf only in the first tenth: the reverse read skips the chunks without it unread, then
    # stops at the first chunk that holds it (read from its end).
    messages = [
        (1_000 + 10 * k, "/tf" if k < 200 else TOPICS[k % 3], bytes(500)) for k in range(2_000)
    ]
    path = write_mcap(tmp_path / "r.mcap", messages, "zstd")
    chunks = chunk_indexes(path)
    source = CountingSource(path)
    file = McapFile(path, 0, print, source=source)
    source.reads.clear()
    at_ns = 15_000
    latest = next(window(file, {"/tf"}, 0, at_ns, reverse=True))
    assert latest == oracle(path, {"/tf"}, 0, at_ns, reverse=True)[0]
    assert latest[0] == 1_000 + 10 * 199
    assert {c.chunk_start_offset for c in touched(source.reads, chunks)} == {
        c.chunk_start_offset
        for c in chunks
        if c.message_start_time <= latest[0] <= c.message_end_time
    }
    source.reads.clear()
    newest = next(window(file, {"/odom"}, 0, at_ns, reverse=True))
    assert newest == oracle(path, {"/odom"}, 0, at_ns, reverse=True)[0]
    assert len({c.chunk_start_offset for c in touched(source.reads, chunks)}) == 1


def chunk(start_ns: int, end_ns: int, offset: int) -> ChunkIndex:
    return ChunkIndex(start_ns, offset, 100, frozenset(), 0, end_ns)


def test_the_merge_decodes_a_chunk_only_when_the_order_needs_it() -> None:
    chunks = [chunk(0, 50, 0), chunk(40, 90, 100), chunk(100, 150, 200), chunk(160, 170, 300)]
    contents = {
        0: [0, 45, 50],
        100: [40, 45, 90],
        200: [100, 150],
        300: [160, 170],
    }
    decoded: list[int] = []

    def decode(c: ChunkIndex) -> list[Timed[str]]:
        decoded.append(c.offset)
        return [
            Timed(t, (c.offset, k), f"{c.offset}:{t}") for k, t in enumerate(contents[c.offset])
        ]

    forward = window_chunks(chunks, 45, 150)
    assert [c.offset for c in forward] == [0, 100, 200]
    merged = merge_window(forward, decode, 45, 150)
    assert next(merged) == Timed(45, (0, 1), "0:45")
    assert decoded == [0, 100]  # the second starts before 45: it may hold earlier messages
    assert [m.item for m in merged] == ["100:45", "0:50", "100:90", "200:100", "200:150"]
    decoded.clear()
    backward = window_chunks(chunks, 0, 155, reverse=True)
    assert [c.offset for c in backward] == [200, 100, 0]
    merged = merge_window(backward, decode, 0, 155, reverse=True)
    assert [next(merged).item, next(merged).item] == ["200:150", "200:100"]
    assert decoded == [200]
    assert [m.item for m in merged] == ["100:90", "0:50", "100:45", "0:45", "100:40", "0:0"]
