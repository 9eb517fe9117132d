"""Reading uncompressed MCAP chunks through their message indexes, against reading them whole.

The index route reads only the wanted records and the headers of the records it skips; on an
intact file it must deliver exactly what the whole-chunk route delivers, and on a damaged one
(any byte flipped, the file cut anywhere) the same messages and the same warnings.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import pytest

from medkit_replay.errors import InputError
from medkit_replay.inputs import open_recording
from medkit_replay.inputs.mcap.reader import McapFile
from tests.inputs.builders import (
    TS,
    Rec,
    diag,
    flipped,
    log,
    stamp,
    storage_file,
    truncated,
    write_bag,
)
from tests.speed.support import SAMPLES, plain

if TYPE_CHECKING:
    from pathlib import Path

SEC = 1_000_000_000
SAMPLE_FILES = [
    p
    for sample in SAMPLES
    for p in ([sample] if sample.is_file() else sample.iterdir())
    if p.suffix == ".mcap"
]


def image(t_ns: int, size: int = 20_000) -> Rec:
    header: Any = TS.types["std_msgs/msg/Header"](stamp=stamp(t_ns), frame_id="camera")  # type: ignore[arg-type]
    msg = TS.types["sensor_msgs/msg/CompressedImage"](
        header=header, format="jpeg", data=np.full(size, 7, dtype=np.uint8)
    )
    return Rec("/camera/compressed", "sensor_msgs/msg/CompressedImage", t_ns, msg)


def mixed_bag(tmp_path: Path, frames: int = 24) -> Path:
    """Diagnostics and logs between large camera frames, two frames per chunk."""
    recs: list[Rec] = []
    for k in range(frames):
        t_ns = SEC + k * SEC // 10
        recs.append(image(t_ns))
        recs.append(diag(t_ns + 1, f"s{k}", k % 3))
        recs.append(log(t_ns + 2, 30 + 10 * (k % 2), f"line {k}"))
        recs.append(diag(t_ns + 3, f"t{k}", 0))
    return storage_file(write_bag(tmp_path / "bag", recs, chunk_every=8))


def read(path: Path, *, use_index: bool) -> object:
    try:
        with open_recording([path], rosout=True, use_index=use_index) as recording:
            messages = [(m.t_ns, m.topic, plain(m.msg)) for m in recording.messages()]
            return messages, list(recording.warnings), recording.inputs
    except InputError as exc:
        return str(exc)


def test_the_index_route_is_taken_and_reads_the_same(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = mixed_bag(tmp_path)
    taken: list[int] = []
    by_index = McapFile._by_index

    def spy(self: McapFile, *args: object) -> object:
        result = by_index(self, *args)  # type: ignore[arg-type]
        if result is not None:
            taken.append(len(result))
        return result

    monkeypatch.setattr(McapFile, "_by_index", spy)
    fast = read(path, use_index=True)
    assert taken  # chunks were read through their message indexes
    assert sum(taken) >= 60  # of 72: a chunk with little to skip is read whole
    assert fast == read(path, use_index=False)


def test_flipped_bytes_read_the_same_both_ways(tmp_path: Path) -> None:
    source = mixed_bag(tmp_path, frames=8)
    data = source.read_bytes()
    # Every third byte outside the camera frames' filler (all the structure), a few inside.
    offsets = [i for i in range(len(data)) if data[i] != 7][::3] + list(range(0, len(data), 4001))
    for offset in offsets:
        path = flipped(source, tmp_path / "flip.mcap", offset)
        assert read(path, use_index=True) == read(path, use_index=False), offset


def test_cuts_read_the_same_both_ways(tmp_path: Path) -> None:
    source = mixed_bag(tmp_path, frames=8)
    size = source.stat().st_size
    for cut in range(0, size, 97):
        path = truncated(source, tmp_path / "cut.mcap", cut)
        assert read(path, use_index=True) == read(path, use_index=False), cut


@pytest.mark.parametrize("damage", ["none", "flip", "cut"])
def test_the_quick_chunk_parser_reads_as_the_careful_one(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, damage: str
) -> None:
    # Whole chunks go through a quick parser that hands anything irregular to the careful
    # one; with the quick one switched off, every recording must read the same.
    paths = [mixed_bag(tmp_path, frames=8), *SAMPLE_FILES]
    if damage != "none":
        source = paths[0]
        middle = source.stat().st_size // 2
        paths = [
            flipped(source, tmp_path / "d.mcap", middle + 3)
            if damage == "flip"
            else truncated(source, tmp_path / "d.mcap", middle)
        ]
    quick = [read(path, use_index=False) for path in paths]
    monkeypatch.setattr(McapFile, "_plain_records", lambda *_: None)
    assert [read(path, use_index=False) for path in paths] == quick
