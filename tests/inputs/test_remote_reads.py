"""Remote MCAP reads request by request, against the tests' Range server on 127.0.0.1.

What a replay with the log bridge off fetches of a camera-heavy bag with /rosout lines between
the frames (none of their bytes, fewer requests than frames); a batch of ranges that meets a
refusal, a missing object or a dropped connection behaves as one range does; what is asked
ahead stays within its bound, and the report is the local one whatever is let go.
"""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING

import pytest

from medkit_replay.errors import InputError
from medkit_replay.inputs.mcap import plan as mcap_plan
from medkit_replay.inputs.remote import ranges as remote
from medkit_replay.inputs.remote.ranges import RemoteRanges
from medkit_replay.inputs.remote.store import RemoteObject, Tally, open_store, parse_location
from tests.inputs.builders import diag, log, string_msg, write_bag
from tests.remote_support import range_server, same_as_local

if TYPE_CHECKING:
    from pathlib import Path

pytest.importorskip("obstore")

SEC = 1_000_000_000
FRAMES = 60


def camera_and_logs_bag(root: Path) -> Path:
    """2 s of 30 Hz 30 kB frames on an unread topic, each followed by two /rosout lines;
    10 Hz diagnostics; chunks of 24 messages."""
    recs = []
    for k in range(FRAMES):
        t_ns = 10**18 + k * SEC // 30
        recs.append(string_msg(t_ns, "/camera/image", "x" * 30_000))
        recs.append(log(t_ns + 1, 40, f"line {k} " + "y" * 100))
        recs.append(log(t_ns + 2, 20, f"more {k} " + "y" * 100))
        if k % 3 == 0:
            recs.append(diag(t_ns + 3, f"s{k}", 2 if k % 9 else 0))
    return write_bag(root / "logs_bag", recs, chunk_every=24)


def message_records(path: Path) -> dict[str, list[tuple[int, int, int]]]:
    """[start, end) and chunk number of every message record in the file's chunks, by topic
    (the test's own walk of the records)."""
    data = path.read_bytes()
    topics: dict[int, str] = {}
    found: dict[str, list[tuple[int, int, int]]] = {}
    at, chunk = 8, -1
    while at + 9 <= len(data):
        op, length = data[at], int.from_bytes(data[at + 1 : at + 9], "little")
        if op == 0x06:
            chunk += 1
            inner = at + 41 + int.from_bytes(data[at + 37 : at + 41], "little") + 8
            while inner < at + 9 + length:
                kind = data[inner]
                size = 9 + int.from_bytes(data[inner + 1 : inner + 9], "little")
                cid = int.from_bytes(data[inner + 9 : inner + 11], "little")
                if kind == 0x04:
                    topic_length = int.from_bytes(data[inner + 13 : inner + 17], "little")
                    topics[cid] = data[inner + 17 : inner + 17 + topic_length].decode()
                elif kind == 0x05:
                    found.setdefault(topics[cid], []).append((inner, inner + size, chunk))
                inner += size
        at += 9 + length
    return found


def fetched(ranges: list[tuple[str, int, int]], start: int, end: int) -> bool:
    return any(first < end and start < stop for _, first, stop in ranges)


def test_with_the_log_bridge_off_no_rosout_line_is_fetched(tmp_path: Path) -> None:
    bag = camera_and_logs_bag(tmp_path)
    mcap = next(bag.glob("*.mcap"))
    records = message_records(mcap)
    assert len(records["/rosout"]) == 2 * FRAMES
    on, off = tmp_path / "on.yaml", tmp_path / "off.yaml"
    for path, value in ((on, "true"), (off, "false")):
        path.write_text(f"medkit_replay:\n  ros__parameters:\n    enable_log_bridge: {value}\n")
    with range_server(tmp_path) as (base, served):
        url = f"{base}/logs_bag/"
        same_as_local(url, bag, [str(off)])
        asked = [r for r in served.ranges if r[0].endswith(".mcap")]
        served.ranges.clear()
        same_as_local(url, bag, [str(on)])
        asked_on = [r for r in served.ranges if r[0].endswith(".mcap")]
    payload = 9 + 22  # past a record's opcode, length and message header
    # The lines in a run of records with a frame: all but those of the first chunk (which
    # declares its channels between its messages: it is read whole) and a line or two on
    # their own at the start of a chunk (a run too short to be worth a request).
    order = sorted(
        (s, e, chunk, topic) for topic, found in records.items() for s, e, chunk in found
    )
    runs: list[list[tuple[int, int, int, str]]] = [[]]
    for record in order:
        if record[3] == "/diagnostics" or (runs[-1] and runs[-1][-1][2] != record[2]):
            runs.append([])
        if record[3] != "/diagnostics":
            runs[-1].append(record)
    lines = [
        (s + payload, e)
        for run in runs
        if any(topic == "/camera/image" for *_, topic in run)
        for s, e, chunk, topic in run
        if topic == "/rosout" and chunk
    ]
    assert len(lines) > 0.8 * 2 * FRAMES
    assert not any(fetched(asked, start, end) for start, end in lines)
    assert all(fetched(asked, s + payload, e) for s, e, _ in records["/diagnostics"])
    assert all(fetched(asked_on, start, end) for start, end in lines)  # the lines are read
    # a request per run of diagnostics, not per gap between frames
    assert len(asked) < FRAMES <= len(asked_on), (len(asked), len(asked_on))


def reader_of(base: str, name: str) -> tuple[RemoteObject, RemoteRanges]:
    location = parse_location(f"{base}/{name}")
    obj = RemoteObject(open_store(location), location, Tally(location.display))
    return obj, RemoteRanges(obj)


def message_of(call: object) -> str:
    try:
        call()  # type: ignore[operator]
    except InputError as exc:
        return str(exc)
    raise AssertionError("no error")


@pytest.mark.parametrize("refusal", ["forbidden", "gone"])
def test_a_batch_meeting_a_refusal_fails_as_one_range_does(tmp_path: Path, refusal: str) -> None:
    (tmp_path / "run.mcap").write_bytes(bytes(range(256)) * 400)
    with range_server(tmp_path) as (base, served):
        obj, reader = reader_of(base, "run.mcap")
        if refusal == "forbidden":
            served.forbidden.add("run.mcap")
        else:
            (tmp_path / "run.mcap").unlink()
        for start in range(0, 60_000, 10_000):
            reader.will_need(start, 1_000)
        with reader:
            batch = message_of(lambda: reader.read(10_000, 500))
        single = message_of(lambda: obj.fetch(10_000, 10_500))
    assert batch == single
    problem = "access denied (HTTP 403)" if refusal == "forbidden" else "not found (HTTP 404)"
    assert batch == f"{base}/run.mcap: {problem}"


def test_a_batch_with_a_dropped_connection_is_asked_again(tmp_path: Path) -> None:
    data = bytes(range(256)) * 400
    (tmp_path / "run.mcap").write_bytes(data)
    with range_server(tmp_path) as (base, served):
        _, reader = reader_of(base, "run.mcap")
        served.drop_next = 2
        starts = range(0, 90_000, 9_000)
        for start in starts:
            reader.will_need(start, 4_000)
        with reader:
            assert [reader.read(start, 4_000) for start in starts] == [
                data[start : start + 4_000] for start in starts
            ]
        assert served.drop_next == 0
        _, reader = reader_of(base, "run.mcap")
        served.drop_next = 10**6
        for start in starts:
            reader.will_need(start, 4_000)
        with reader:
            line = message_of(lambda: reader.read(9_000, 100))
    assert line == f"{base}/run.mcap: connection failed; gave up after 5 tries"


def test_a_batch_still_asking_again_stops_when_told(tmp_path: Path) -> None:
    # The reader sets its stop event when closed (Ctrl-C, an error): a batch between tries
    # then tries no more.
    (tmp_path / "run.mcap").write_bytes(bytes(range(256)) * 400)
    stop = threading.Event()
    with range_server(tmp_path) as (base, served):
        obj, _ = reader_of(base, "run.mcap")
        served.drop_next = 10**6
        timer = threading.Timer(0.15, stop.set)  # during the wait before the second or third try
        timer.start()
        line = message_of(lambda: obj.fetch_many([0, 9_000], [4_000, 13_000], stop))
        timer.join()
    assert line == f"{base}/run.mcap: reading stopped"


def test_an_object_cut_short_while_it_is_read_fails_in_one_line(tmp_path: Path) -> None:
    data = bytes(range(256)) * 400
    (tmp_path / "run.mcap").write_bytes(data)
    with range_server(tmp_path) as (base, _served):
        obj, reader = reader_of(base, "run.mcap")
        for start in (0, 50_000, 100_000):
            reader.will_need(start, 1_000)
        (tmp_path / "run.mcap").write_bytes(data[:100_500])  # replaced by a shorter upload
        with reader:
            batch = message_of(lambda: reader.read(100_000, 1_000))
        single = message_of(lambda: obj.fetch(100_000, 101_000))
    assert batch == single
    assert batch == f"{base}/run.mcap: the server sent 500 of 1000 bytes; gave up after 5 tries"


def test_what_is_asked_ahead_stays_within_its_bound(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    bag = camera_and_logs_bag(tmp_path)
    limit = 48 * 1024  # less than the window asks for: the oldest blocks go unread
    monkeypatch.setattr(remote, "READ_AHEAD_LIMIT", limit)
    held: list[int] = []
    send = RemoteRanges._send

    def watched(self: RemoteRanges) -> None:
        send(self)
        held.append(self._held)

    monkeypatch.setattr(RemoteRanges, "_send", watched)
    with range_server(tmp_path) as (base, _served):
        same_as_local(f"{base}/logs_bag/", bag, [])
        assert held and max(held) <= limit
        # with the limit out of reach, what is held is what the window asks for: the reader
        # lets blocks go once it is past them
        monkeypatch.setattr(remote, "READ_AHEAD_LIMIT", 10**9)
        held.clear()
        same_as_local(f"{base}/logs_bag/", bag, [])
        whole = max(held)  # the window spans the file
        monkeypatch.setattr(mcap_plan, "PIECES_AHEAD", 2)
        monkeypatch.setattr(mcap_plan, "HEADS_AHEAD", 2)
        held.clear()
        same_as_local(f"{base}/logs_bag/", bag, [])
    assert max(held) < whole / 2
