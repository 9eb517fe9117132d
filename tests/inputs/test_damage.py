"""Damaged inputs: truncated and bit-flipped MCAP and sqlite3 files, broken compression, non-bags.

The rule under test: read everything readable, warn with the file and the loss, never a traceback;
InputError (one line naming the path) only when nothing at all can be read.
"""

from __future__ import annotations

import random
from typing import TYPE_CHECKING

import pytest

from medkit_replay.errors import InputError
from medkit_replay.inputs import Message, open_recording
from tests.inputs.builders import (
    Compression,
    Storage,
    chunks,
    diag,
    flipped,
    storage_file,
    truncated,
    write_bag,
)

if TYPE_CHECKING:
    from pathlib import Path

COUNT = 40
CHUNK = 5


def attempt(path: Path) -> tuple[list[Message], list[str]] | InputError:
    """Read a damaged input; an InputError is returned, any other exception fails the test."""
    try:
        with open_recording([path], rosout=True) as recording:
            return list(recording.messages()), list(recording.warnings)
    except InputError as exc:
        assert "\n" not in str(exc)
        assert str(exc).startswith(f"{path}: ")
        return exc


def good_bag(tmp_path: Path, storage: Storage, compression: Compression = "none") -> Path:
    recs = [diag(1_000 + t, f"s{t}") for t in range(COUNT)]
    bag = write_bag(
        tmp_path / "good", recs, storage=storage, compression=compression, chunk_every=CHUNK
    )
    return storage_file(bag)


def chunk_ends(mcap: Path) -> list[int]:
    return [end for _, end in chunks(mcap)]


def names(messages: list[Message]) -> list[str]:
    return [m.msg.status[0].name for m in messages]  # type: ignore[attr-defined]


EVERYTHING = [f"s{t}" for t in range(COUNT)]


@pytest.mark.parametrize("compression", ["none", "chunk"])
def test_truncated_mcap_keeps_every_complete_chunk(
    tmp_path: Path, compression: Compression
) -> None:
    source = good_bag(tmp_path, "mcap", compression)
    ends = chunk_ends(source)
    assert len(ends) == COUNT // CHUNK
    size = source.stat().st_size
    for cut in sorted({*range(0, size, 53), *ends, *(e - 1 for e in ends), size - 1}):
        result = attempt(truncated(source, tmp_path / "cut.mcap", cut))
        if isinstance(result, InputError):
            assert cut < 30  # only a file cut inside its magic or header record
            continue
        messages, warnings = result
        got = names(messages)
        assert got == EVERYTHING[: len(got)]  # a prefix, in order
        assert len(got) >= CHUNK * sum(1 for end in ends if end <= cut)
        if cut < ends[-1]:
            assert any("truncated" in w or "cut off" in w for w in warnings)
            assert all(w.startswith(f"{tmp_path / 'cut.mcap'}: ") for w in warnings)


def test_truncated_mcap_names_what_was_lost(tmp_path: Path) -> None:
    source = good_bag(tmp_path, "mcap", "chunk")
    start = chunks(source)[3][0]
    cut = start + 80
    result = attempt(truncated(source, tmp_path / "cut.mcap", cut))
    assert not isinstance(result, InputError)
    messages, warnings = result
    assert names(messages) == EVERYTHING[:15]
    path = tmp_path / "cut.mcap"
    no_footer = "no footer (the recorder did not close the file); scanning the file from the start"
    assert warnings[0] == f"{path}: {no_footer}; how much was lost is unknown"
    assert warnings[1] == (
        f"{path}: chunk at byte {start} (log times 1015..1019) is cut off and zstd-compressed; "
        "it is lost"
    )
    assert warnings[2].startswith(f"{path}: file ends inside a record (opcode 0x06) of ")
    assert warnings[2].endswith(
        f"at byte {start} of {cut} (truncated: recorder stopped mid-write?); the last 80 bytes "
        "are lost; an unknown number of messages (80 bytes) from bag time 0.000 s to 0.000 s "
        "skipped"
    )


@pytest.mark.parametrize("compression", ["none", "chunk"])
def test_flipped_bytes_in_mcap_never_raise(tmp_path: Path, compression: Compression) -> None:
    source = good_bag(tmp_path, "mcap", compression)
    size = source.stat().st_size
    for offset in range(0, size, 7):
        result = attempt(flipped(source, tmp_path / "flip.mcap", offset))
        if isinstance(result, InputError):
            assert offset < 30
            continue
        messages = result[0]
        assert [m.t_ns for m in messages] == sorted(m.t_ns for m in messages)


def test_a_damaged_chunk_costs_only_its_own_messages(tmp_path: Path) -> None:
    source = good_bag(tmp_path, "mcap", "chunk")
    ends = chunk_ends(source)
    result = attempt(flipped(source, tmp_path / "flip.mcap", ends[3] - 10))
    assert not isinstance(result, InputError)
    messages, warnings = result
    assert names(messages) == EVERYTHING[:15] + EVERYTHING[20:]
    assert len(warnings) == 1
    assert "cannot be decompressed" in warnings[0]
    assert warnings[0].endswith("; 5 messages (171 bytes) from bag time 0.000 s to 0.000 s skipped")


def test_a_damaged_summary_falls_back_to_scanning(tmp_path: Path) -> None:
    source = good_bag(tmp_path, "mcap")
    data = bytearray(source.read_bytes())
    summary_start = int.from_bytes(data[-37 + 9 : -37 + 17], "little")
    data[summary_start + 1] ^= 0xFF  # the first summary record's length
    path = tmp_path / "flip.mcap"
    path.write_bytes(bytes(data))
    result = attempt(path)
    assert not isinstance(result, InputError)
    messages, warnings = result
    assert names(messages) == EVERYTHING
    assert warnings[0].startswith(f"{path}: summary section is damaged (")


@pytest.mark.parametrize("mode", ["truncate", "flip"])
def test_damaged_sqlite_never_raises_and_keeps_order(tmp_path: Path, mode: str) -> None:
    source = good_bag(tmp_path, "sqlite3")
    size = source.stat().st_size
    rng = random.Random(4)
    offsets = range(0, size, 512) if mode == "truncate" else rng.sample(range(size), 120)
    delivered = 0
    for offset in offsets:
        target = tmp_path / "bad.db3"
        damage = truncated if mode == "truncate" else flipped
        result = attempt(damage(source, target, offset))
        if isinstance(result, InputError):
            continue
        messages = result[0]
        assert [m.t_ns for m in messages] == sorted(m.t_ns for m in messages)
        assert set(names(messages)) <= set(EVERYTHING) | {""}
        delivered += len(messages)
    assert delivered > 0


def test_truncated_sqlite_keeps_the_rows_before_the_damage(tmp_path: Path) -> None:
    recs = [diag(1_000 + t, f"s{t}", 1, "x" * 300) for t in range(300)]
    source = storage_file(write_bag(tmp_path / "good", recs, storage="sqlite3"))
    size = source.stat().st_size
    result = attempt(truncated(source, tmp_path / "cut.db3", size - 4096))
    assert not isinstance(result, InputError)
    messages, warnings = result
    got = [m.t_ns for m in messages]
    assert got == list(range(1_000, 1_000 + len(got)))
    assert 250 < len(got) < 300
    assert any("damaged database" in w for w in warnings)


def test_file_compressed_bag_cut_short_keeps_what_decompresses(tmp_path: Path) -> None:
    # zstd hands out whole blocks of 128 KiB: make a file of several
    recs = [diag(1_000 + t, f"s{t}", 1, f"{t}" * 1000) for t in range(400)]
    bag = write_bag(tmp_path / "bag", recs, compression="file", chunk_every=CHUNK)
    compressed = storage_file(bag)
    assert compressed.name.endswith(".mcap.zstd")
    compressed.write_bytes(compressed.read_bytes()[: compressed.stat().st_size // 2])
    result = attempt(bag)
    assert not isinstance(result, InputError)
    messages, warnings = result
    got = [m.t_ns for m in messages]
    assert 0 < len(got) < 400
    assert got == list(range(1_000, 1_000 + len(got)))
    assert warnings[0].startswith(f"{compressed}: compressed data is damaged (")


def test_corrupt_payloads_are_skipped_and_counted(tmp_path: Path) -> None:
    recs = [diag(1_000 + t, f"s{t}") for t in range(4)]
    bag = write_bag(tmp_path / "bag", recs, compression="message")
    data = bytearray(storage_file(bag).read_bytes())
    first = data.find(b"\x28\xb5\x2f\xfd")  # the first message's zstd frame
    data[first + 6 : first + 12] = b"\xff" * 6
    storage_file(bag).write_bytes(bytes(data))
    result = attempt(bag)
    assert not isinstance(result, InputError)
    messages, warnings = result
    assert names(messages) == ["s1", "s2", "s3"]
    assert len(warnings) == 1
    assert warnings[0].startswith(
        f"{bag}: 1 messages on /diagnostics cannot be decoded and were skipped (first at t=1000: "
    )
    assert warnings[0].endswith(
        "; 1 message (size unknown) from bag time 0.000 s to 0.000 s skipped"
    )


@pytest.mark.parametrize("content", [b"", b"\x89MCAP0\r", b"\x89MCAP0\r\n", b"garbage" * 100])
def test_not_a_bag_raises_input_error(tmp_path: Path, content: bytes) -> None:
    for suffix in (".mcap", ".db3"):
        path = tmp_path / f"x{suffix}"
        path.write_bytes(content)
        assert isinstance(attempt(path), InputError)


def test_directory_with_one_bad_file_keeps_the_other(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "bag", [diag(1)])
    (bag / "metadata.yaml").unlink()
    (bag / "zz_broken.mcap").write_bytes(b"not an mcap")
    result = attempt(bag)
    assert not isinstance(result, InputError)
    messages, warnings = result
    assert len(messages) == 1
    assert warnings[-1] == (
        f"{bag / 'zz_broken.mcap'}: not an MCAP file (bad magic); an unknown number of messages "
        "(11 bytes) at unknown bag times skipped"
    )
