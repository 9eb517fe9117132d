"""Runs of unwanted records skipped when reading MCAP chunks by index, and the read-ahead window.

With the log bridge off, /rosout lines sit between camera frames: a run of unwanted records
worth a request is skipped whole (only its first record's header is read). Planned on plain
bytes first; then on bags, against the whole-chunk route: the same messages and warnings for
every flipped byte the index route reads, and every wanted message for a flip it does not.
"""

from __future__ import annotations

from struct import pack
from typing import TYPE_CHECKING

import pytest

from medkit_replay.errors import InputError
from medkit_replay.inputs import open_recording
from medkit_replay.inputs.mcap.plan import (
    AHEAD_BYTES,
    HEADS_AHEAD,
    PIECES_AHEAD,
    PLAIN_CHUNK_HEAD,
    SKIP_AT_LEAST,
    ChunkIndex,
    Plan,
    ReadAhead,
    plan_chunk,
)
from tests.inputs.builders import diag, flipped, log, storage_file, string_msg, write_bag
from tests.speed.support import plain

if TYPE_CHECKING:
    from pathlib import Path

SEC = 1_000_000_000
HEADER = 11  # opcode, record length, channel id: what is read of a skipped run


def index_bytes(records: list[tuple[int, int]]) -> tuple[bytes, list[int]]:
    """Message index records for a chunk whose records are (channel id, record bytes), in
    order; and the records' starts."""
    starts, at = [], 0
    for _, length in records:
        starts.append(at)
        at += length
    entries: dict[int, list[int]] = {}
    for (cid, _), start in zip(records, starts, strict=True):
        entries.setdefault(cid, []).append(start)
    out = b""
    for cid, offsets in sorted(entries.items()):
        body = b"".join(pack("<QQ", 1000 + k, offset) for k, offset in enumerate(offsets))
        out += pack("<BQHI", 0x07, 6 + len(body), cid, len(body)) + body
    return out, starts


def chunk_of(records: list[tuple[int, int]]) -> tuple[ChunkIndex, int, bytes, list[int]]:
    """A chunk of such records as the summary describes it, its records' size, its index
    and the records' starts."""
    index, starts = index_bytes(records)
    size = sum(length for _, length in records)
    names = frozenset(cid for cid, _ in records)
    return ChunkIndex(0, 0, PLAIN_CHUNK_HEAD + size, names, len(index)), size, index, starts


CAMERA, DIAGNOSTICS, ROSOUT = 1, 2, 3
FRAME, LINE, STATUS = 60_000, 200, 2_000


def test_a_run_of_unwanted_records_worth_a_request_is_skipped_but_its_first_header() -> None:
    # diagnostics, then a frame and three lines (one run), a diagnostic, two lines (a short
    # run, read), a diagnostic.
    records = [
        (DIAGNOSTICS, STATUS),
        (CAMERA, FRAME),
        (ROSOUT, LINE),
        (ROSOUT, LINE),
        (ROSOUT, LINE),
        (DIAGNOSTICS, STATUS),
        (ROSOUT, LINE),
        (ROSOUT, LINE),
        (DIAGNOSTICS, STATUS),
    ]
    chunk, size, index, starts = chunk_of(records)
    plan = plan_chunk(chunk, size, index, lambda cid: cid == DIAGNOSTICS)
    assert plan is not None
    run_end = starts[5]
    assert plan.pieces == [(0, starts[1] + HEADER), (run_end, size)]
    assert plan.wanted == {DIAGNOSTICS}
    # the same lines wanted: only the frame is skipped
    logs = plan_chunk(chunk, size, index, lambda cid: cid != CAMERA)
    assert logs is not None
    assert logs.pieces == [(0, starts[1] + HEADER), (starts[2], size)]


def test_a_short_run_is_read_and_a_mostly_wanted_chunk_is_not_planned() -> None:
    short = SKIP_AT_LEAST // LINE - 1  # lines shorter than a request together
    records = [(DIAGNOSTICS, STATUS), *[(ROSOUT, LINE)] * short, (DIAGNOSTICS, STATUS)]
    records += [(CAMERA, FRAME)]
    chunk, size, index, starts = chunk_of(records)
    plan = plan_chunk(chunk, size, index, lambda cid: cid == DIAGNOSTICS)
    assert plan is not None
    assert plan.pieces == [(0, starts[-1] + HEADER)]
    logs = plan_chunk(chunk, size, index, lambda cid: cid != CAMERA)
    assert logs is not None
    assert logs.pieces == plan.pieces
    assert plan_chunk(chunk, size, index, lambda cid: cid != ROSOUT) is None  # mostly wanted


def test_an_index_that_disagrees_with_the_summary_is_not_planned() -> None:
    records = [(DIAGNOSTICS, STATUS), (CAMERA, FRAME), (ROSOUT, LINE), (DIAGNOSTICS, STATUS)]
    chunk, size, index, _ = chunk_of(records)
    assert plan_chunk(chunk, size, index, lambda cid: cid == DIAGNOSTICS) is not None
    named = chunk._replace(channels=frozenset({DIAGNOSTICS, CAMERA, 9}))
    assert plan_chunk(named, size, index, lambda cid: cid == DIAGNOSTICS) is None
    # the /rosout index record relabelled as the camera's (a flipped channel id): the lines
    # would be taken for frames and skipped unseen
    at = 0
    relabelled = bytearray(index)
    while at < len(index):
        if int.from_bytes(index[at + 9 : at + 11], "little") == ROSOUT:
            relabelled[at + 9 : at + 11] = pack("<H", CAMERA)
        at += 9 + int.from_bytes(index[at + 1 : at + 9], "little")
    assert relabelled != index
    assert plan_chunk(chunk, size, bytes(relabelled), lambda cid: cid == DIAGNOSTICS) is None


class Bytes:
    """Hints over bytes in memory: what is asked for, and everything at hand."""

    def __init__(self, data: bytes) -> None:
        self.data = data
        self.asked: list[tuple[int, int]] = []

    def cached(self, offset: int, length: int) -> bytes | None:
        return self.data[offset : offset + length]

    def will_need(self, offset: int, length: int) -> None:
        self.asked.append((offset, length))


def test_the_window_asks_ahead_within_its_bounds() -> None:
    records = [(DIAGNOSTICS, STATUS), (CAMERA, FRAME), (DIAGNOSTICS, STATUS)]
    index, _ = index_bytes(records)
    size = sum(length for _, length in records)
    head = pack("<BQQQQII", 0x06, PLAIN_CHUNK_HEAD - 9 + size, 0, 0, size, 0, 0)
    head += pack("<Q", size)
    one = head + bytes(size) + index
    count = 3 * HEADS_AHEAD
    data = one * count
    chunks = [
        ChunkIndex(k, k * len(one), len(head) + size, frozenset({1, 2}), len(index))
        for k in range(count)
    ]

    def plan(chunk: ChunkIndex, head: bytes, index: bytes) -> Plan | None:
        return plan_chunk(chunk, size, index, lambda cid: cid == DIAGNOSTICS)

    reader = Bytes(data)
    ahead = ReadAhead(chunks, plan, len(data))
    ahead.advance(reader, 0)
    heads = {offset for offset, length in reader.asked if length == PLAIN_CHUNK_HEAD}
    assert heads == {chunk.offset for chunk in chunks[:HEADS_AHEAD]}
    assert sorted(ahead.plans) == list(range(PIECES_AHEAD))
    piece_bytes = sum(length for _, length in reader.asked if length > len(index))
    assert piece_bytes <= AHEAD_BYTES
    # half a window later nothing is asked; past it, the window is topped up
    reader.asked.clear()
    ahead.advance(reader, PIECES_AHEAD // 2 - 1)
    assert reader.asked == []
    ahead.advance(reader, PIECES_AHEAD // 2)
    assert max(ahead.plans) == PIECES_AHEAD // 2 + PIECES_AHEAD - 1
    assert min(ahead.plans) == PIECES_AHEAD // 2  # plans of chunks passed are let go


# -- on bags, against the whole-chunk route ---------------------------------------------------


def logs_bag(tmp_path: Path, frames: int = 8) -> Path:
    """Each camera frame followed by two /rosout lines and a diagnostic; three frames a chunk."""
    recs = []
    for k in range(frames):
        t_ns = SEC + k * SEC // 10
        recs.append(string_msg(t_ns, "/camera/image", "x" * 20_000))
        recs.append(log(t_ns + 1, 40, f"line {k}"))
        recs.append(log(t_ns + 2, 30, f"more {k}"))
        recs.append(diag(t_ns + 3, f"s{k}", k % 3))
    return storage_file(write_bag(tmp_path / "bag", recs, chunk_every=12))


def read(path: Path, *, use_index: bool) -> object:
    try:
        with open_recording([path], rosout=False, use_index=use_index) as recording:
            messages = [(m.t_ns, m.topic, plain(m.msg)) for m in recording.messages()]
            return messages, list(recording.warnings), recording.inputs
    except InputError as exc:
        return str(exc)


def skipped_bytes(path: Path) -> set[int]:
    """The bytes inside runs of unwanted records the index route skips, past their first
    header: found by walking the chunks' records (topics from the channel records); none in
    a chunk that declares a channel between its messages (it is read whole)."""
    data = path.read_bytes()
    topics: dict[int, str] = {}
    skipped: set[int] = set()
    at = 8
    while at + 9 <= len(data):
        op, length = data[at], int.from_bytes(data[at + 1 : at + 9], "little")
        if op == 0x06:
            name_length = int.from_bytes(data[at + 37 : at + 41], "little")
            inner = at + 41 + name_length + 8
            run: list[tuple[int, int]] = []
            mine: set[int] = set()
            messages = irregular = False
            while inner < at + 9 + length:
                kind = data[inner]
                size = 9 + int.from_bytes(data[inner + 1 : inner + 9], "little")
                if kind == 0x04:
                    cid = int.from_bytes(data[inner + 9 : inner + 11], "little")
                    topic_length = int.from_bytes(data[inner + 13 : inner + 17], "little")
                    topics[cid] = data[inner + 17 : inner + 17 + topic_length].decode()
                cid = int.from_bytes(data[inner + 9 : inner + 11], "little")
                unwanted = kind == 0x05 and topics.get(cid) != "/diagnostics"
                irregular |= messages and kind != 0x05  # a channel between messages
                messages |= kind == 0x05
                if unwanted:
                    run.append((inner, inner + size))
                if run and (not unwanted or inner + size >= at + 9 + length):
                    if run[-1][1] - run[0][0] - HEADER >= SKIP_AT_LEAST:
                        mine.update(range(run[0][0] + HEADER, run[-1][1]))
                    run = []
                inner += size
            if not irregular:  # else the chunk is read whole
                skipped |= mine
        at += 9 + length
    return skipped


def test_runs_of_frames_and_lines_are_skipped(tmp_path: Path) -> None:
    path = logs_bag(tmp_path)
    skipped = skipped_bytes(path)
    data = path.read_bytes()
    assert data.count(b"line ") == 8
    # all but those of the first chunk, which declares channels between its messages
    assert sum(1 for k in skipped if data[k : k + 5] == b"line ") == 5
    assert read(path, use_index=True) == read(path, use_index=False)


@pytest.mark.parametrize("inside", [False, True])
def test_flipped_bytes_with_the_log_bridge_off(tmp_path: Path, inside: bool) -> None:
    # Every third byte the index route reads (outside the frames' filler): the same as the
    # whole-chunk route. Inside a skipped run the records are taken to be what the index
    # says (as chunks without a wanted topic are never read): every wanted message arrives.
    source = logs_bag(tmp_path)
    data = source.read_bytes()
    skipped = skipped_bytes(source)
    intact = read(source, use_index=True)
    assert isinstance(intact, tuple)
    offsets = [k for k in range(len(data)) if data[k] != ord("x") and (k in skipped) == inside]
    assert offsets
    for offset in offsets[:: 3 if not inside else 7]:
        path = flipped(source, tmp_path / "flip.mcap", offset)
        got = read(path, use_index=True)
        if inside:
            assert isinstance(got, tuple), offset
            assert got[0] == intact[0] and got[1] == [], offset
        else:
            assert got == read(path, use_index=False), offset
