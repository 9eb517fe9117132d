"""A ``-wal`` header read once (wal._Header.parse) for both of its readers: the follower's
checksummed header and the count of committed bytes a finished bag's copy takes."""

from __future__ import annotations

import struct
from typing import TYPE_CHECKING

import pytest

from medkit_replay.inputs.sqlite import wal

if TYPE_CHECKING:
    from pathlib import Path

SALTS = (0x1234, 0x5678)


def header(page_field: int, magic: int = 0x377F0682, version: int = 3007000) -> bytes:
    head = struct.pack(">6I", magic, version, page_field, 0, *SALTS)
    return head + struct.pack(">2I", *wal._checksum(head, (0, 0), bool(magic & 1)))


def frame(page_size: int, commit: int, salts: tuple[int, int] = SALTS) -> bytes:
    return struct.pack(">6I", 1, commit, *salts, 0, 0) + bytes(page_size)


def test_a_page_size_field_of_one_means_64_kib_pages_for_both_readers(tmp_path: Path) -> None:
    path = tmp_path / "bag.db3-wal"
    path.write_bytes(header(1) + frame(65536, 0) + frame(65536, 2) + frame(65536, 0))
    parsed = wal._Header.parse(path.read_bytes())
    assert parsed is not None
    assert (parsed.page_size, parsed.salts, parsed.big) == (65536, SALTS, False)
    read = wal._Header.read(path)
    assert read is not None and read.same(parsed)
    assert wal._committed_wal_bytes(path) == 32 + 2 * (24 + 65536)


@pytest.mark.parametrize(
    "raw",
    [
        header(4096)[:31],  # cut short
        header(4096, magic=0x377F0684),
        header(4096, version=3007001),
        header(256),
        header(3000),  # not a power of two
    ],
)
def test_a_header_sqlite_would_not_read_gives_no_header_and_no_bytes(
    tmp_path: Path, raw: bytes
) -> None:
    path = tmp_path / "bag.db3-wal"
    path.write_bytes(raw + frame(4096, 2))
    assert wal._Header.parse(raw) is None
    assert wal._Header.read(path) is None
    assert wal._committed_wal_bytes(path) == 0


def test_only_the_follower_checks_the_header_checksum(tmp_path: Path) -> None:
    path = tmp_path / "bag.db3-wal"
    raw = header(4096)[:28] + b"\0\0\0\0"
    path.write_bytes(raw + frame(4096, 2) + frame(4096, 3, salts=(0, 0)))
    assert wal._Header.parse(raw) is not None
    assert wal._Header.read(path) is None
    assert wal._committed_wal_bytes(path) == 32 + 24 + 4096


def test_an_unreadable_wal_is_an_error_for_the_copy_and_none_for_the_follower(
    tmp_path: Path,
) -> None:
    missing = tmp_path / "gone.db3-wal"
    assert wal._Header.read(missing) is None
    with pytest.raises(OSError):
        wal._committed_wal_bytes(missing)
