"""A remote object read from the start (a file without an index): the stream over its
RangeReader reads every byte, hints the next block, and closes the reader through close()."""

from __future__ import annotations

import io

from medkit_replay.inputs.remote import ranges as remote


class _Memory:
    """A RangeReader over bytes in memory that notes the hints and the close it is given."""

    always_ahead = True

    def __init__(self, data: bytes) -> None:
        self.data = data
        self.size = len(data)
        self.hints: list[tuple[str, int]] = []
        self.closed = 0

    def read_into(self, offset: int, view: memoryview) -> int:
        got = self.data[offset : offset + len(view)]
        view[: len(got)] = got
        return len(got)

    def forget(self, before: int) -> None:
        self.hints.append(("forget", before))

    def will_need(self, offset: int, length: int) -> None:
        self.hints.append(("will_need", offset))

    def close(self) -> None:
        self.closed += 1


def test_the_stream_reads_all_hints_ahead_and_closes_its_reader_once() -> None:
    data = bytes(range(256)) * 40
    reader = _Memory(data)
    stream = remote._AheadStream(reader)  # type: ignore[arg-type]  # a RangeReader in kind
    with io.BufferedReader(stream, 1000) as buffered:
        assert buffered.read(10) == data[:10]
        assert buffered.read() == data[10:]
        buffered.seek(-5, io.SEEK_END)
        assert buffered.read() == data[-5:]
    assert reader.closed == 1
    assert ("forget", 0) in reader.hints
    assert ("will_need", 1000) in reader.hints
    assert remote.STREAM_BLOCK == 8 * 1024 * 1024
