"""An MCAP file's header record read by one method (McapSummary._header_body) for a finished
file and a growing one: the same damage error and the same word about a profile not ros2."""

from __future__ import annotations

import struct
from typing import TYPE_CHECKING, Any

import pytest
from mcap.writer import Writer

from medkit_replay.inputs.follow import Growing
from medkit_replay.inputs.mcap.reader import McapFile
from medkit_replay.inputs.mcap.records import MAGIC, OP_HEADER
from medkit_replay.inputs.mcap.summary import McapSummary
from medkit_replay.inputs.mcap.tail import McapTail
from medkit_replay.inputs.storage import NotABagError

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.model import Loss


class _Seen:
    """A finished file as a growing one sees it: its size, the writer gone, nothing to wait."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def look(self) -> int:
        return self.path.stat().st_size

    def check_open(self, fd: int) -> None:
        """Always the file first seen."""

    def wait(self) -> None:
        raise AssertionError("a finished file is never waited for")


def _open(path: Path, growing: bool, lines: list[str]) -> McapFile:
    """The file as a finished one (McapFile) or as a growing one (McapTail), its words kept."""

    def warn(text: str, loss: Loss | None = None, /) -> None:
        lines.append(text)

    if not growing:
        return McapFile(path, 0, warn)
    seen: Any = _Seen(path)
    return McapTail(path, 0, warn, growing=Growing(seen, lambda: True, seen))


def _write_profile(path: Path, profile: str) -> Path:
    with path.open("wb") as stream:
        writer = Writer(stream)
        writer.start(profile=profile, library="test")
        writer.finish()  # type: ignore[no-untyped-call]  # mcap ships it untyped
    return path


@pytest.mark.parametrize("growing", [False, True])
def test_a_profile_not_ros2_is_said_alike_by_a_finished_and_a_growing_file(
    tmp_path: Path, growing: bool
) -> None:
    path = _write_profile(tmp_path / "other.mcap", "ros1")
    lines: list[str] = []
    _open(path, growing, lines)
    assert lines == [f"{path}: MCAP profile 'ros1', not 'ros2'; reading it anyway"]


@pytest.mark.parametrize("growing", [False, True])
def test_a_damaged_header_record_is_refused_alike(tmp_path: Path, growing: bool) -> None:
    path = tmp_path / "damaged.mcap"
    body = struct.pack("<I", 1000) + b"ros2"  # a profile longer than the record
    path.write_bytes(MAGIC + bytes([OP_HEADER]) + struct.pack("<Q", len(body)) + body + MAGIC)
    with pytest.raises(NotABagError, match=r"^MCAP header record is damaged$"):
        _open(path, growing, [])


@pytest.mark.parametrize("growing", [False, True])
def test_both_read_the_header_through_one_method(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, growing: bool
) -> None:
    path = _write_profile(tmp_path / "plain.mcap", "ros2")
    bodies: list[bytes] = []
    read = McapSummary._header_body

    def noted(self: McapSummary, body: bytes) -> None:
        bodies.append(bytes(body))
        read(self, body)

    monkeypatch.setattr(McapSummary, "_header_body", noted)
    _open(path, growing, [])
    assert len(bodies) == 1
    assert bodies[0].startswith(struct.pack("<I", 4) + b"ros2")
