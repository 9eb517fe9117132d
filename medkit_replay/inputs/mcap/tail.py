"""An MCAP file still being written, read to its end and waited for until it is finished.

The scan of :class:`~medkit_replay.inputs.mcap.reader.McapFile` with a wait where its data ends.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.inputs.mcap.reader import McapFile
from medkit_replay.inputs.mcap.records import (
    MAGIC,
    NO_FOOTER,
    OP_CHANNEL,
    OP_HEADER,
)
from medkit_replay.inputs.ranges import LocalSource
from medkit_replay.inputs.storage import RECORD_SIZE_LIMIT, NotABagError

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator
    from pathlib import Path

    from medkit_replay.inputs.follow import Growing
    from medkit_replay.inputs.merge import Bound, Timed
    from medkit_replay.inputs.ranges import RangeReader
    from medkit_replay.inputs.source import Warn
    from medkit_replay.inputs.storage import Connection, Raw


class McapTail(McapFile):
    """A growing MCAP file: a record cut off at its end is waited for, not damage.

    The file is scanned from its start (a summary, if present, is not used: the scan stops at
    the Data End record). It is finished when that record is reached or, once ``done`` says the
    recording moved on (a later split file, metadata.yaml), at the end of its bytes; a record
    cut off then follows the damage rules of a finished file. Every look at its size and
    every opening checks it is still the file first seen (``watched``).
    """

    def __init__(self, path: Path, file_no: int, warn: Warn, *, growing: Growing) -> None:
        self._follow, self._done, self._watched = growing
        self._unfinished = False  # the writer moved on before the file's Data End record
        super().__init__(path, file_no, warn, source=LocalSource(path, self._watched.check_open))

    def _probe(self, reader: RangeReader) -> None:
        """Wait for the magic and the header record; nothing else is known before reading."""
        head_size = len(MAGIC) + 9
        while True:
            moved_on = self._done()
            self._size = self._watched.look()
            if self._size >= head_size:
                head = reader.read(0, head_size)
                if head[: len(MAGIC)] != MAGIC:
                    raise NotABagError("not an MCAP file (bad magic)")
                if head[len(MAGIC)] != OP_HEADER:
                    raise NotABagError("MCAP file without its header record")
                length = int.from_bytes(head[len(MAGIC) + 1 :], "little")
                if length > RECORD_SIZE_LIMIT:
                    raise NotABagError("MCAP header record is damaged")
                self._data_start = head_size + length
                if self._data_start <= self._size:
                    body = reader.read(head_size, self._data_start - head_size)
                    break
            if moved_on:
                raise NotABagError("MCAP file cut off before its header record ends")
            self._follow.wait()
        self._data_end = self._size
        self._header_body(body)

    def read(
        self, wants: Callable[[Connection], bool], cap_ns: int | None
    ) -> Iterator[Bound | Timed[Raw] | list[Timed[Raw]]]:
        """Yield bounds and wanted messages as they are written (see ``StorageFile.read``)."""
        yield from super().read(wants, cap_ns)
        if not self._unfinished:
            self._await_footer()

    def _await_footer(self) -> None:
        """After the Data End record come the summary and the footer: wait for them, then take
        the counts and the span from them as for a finished file (and say what a finished file
        without them would say)."""
        while True:
            moved_on = self._done()
            self._watched.look()
            with self._source.ranges() as reader:
                size = reader.size
                tail_at = max(self._data_start, size - len(MAGIC))
                if reader.read(tail_at, size - tail_at) == MAGIC or moved_on:
                    self._size = size
                    counted = (dict(self.counts), self.start_ns, self.end_ns)
                    problem = self._read_footer_and_summary(reader)
                    for cid in sorted(self.connections):
                        self._wants(cid)  # a channel declared in the summary alone, too
                    if self._chunks is None:  # read without an index, as analyze would
                        self.counts, self.start_ns, self.end_ns = counted
                        if problem:
                            self.summary_problem(problem)
                    return
            self._follow.wait()

    def _grow(self, need: int) -> bool:
        while True:
            moved_on = self._done()  # before the size: bytes written before it are seen
            size = self._watched.look()
            if size > self._size:
                self._size = self._data_end = size
                self._follow.saw_data()
            if need <= self._data_end:
                return True
            if moved_on:
                if not self._unfinished:  # said as a finished file without its end says it
                    self._unfinished = True
                    self.summary_problem(NO_FOOTER)
                return False
            self._follow.wait()

    def _parse_records(self, body: bytes, op: int) -> None:
        """A channel is classified when declared, as a summary's channels are before reading."""
        known = set(self.connections) if op == OP_CHANNEL else None
        super()._parse_records(body, op)
        if known is not None:
            for cid in sorted(set(self.connections) - known):
                self._wants(cid)
