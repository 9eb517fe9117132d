"""An append-only record sequence that spills full chunks to an anonymous temporary file.

Keeps a replay's memory bounded by the chunk size however many records a recording yields.
With a row codec, records may also be appended as flat tuples (cheap to build, pickle and
count), as the replay's hot path does: a row becomes its record when first read, and stays that
record while it is held in memory, as an appended record does.
"""

from __future__ import annotations

import errno
import itertools
import os
import pickle
import tempfile
from bisect import bisect_right
from collections.abc import Callable, Iterator, Sequence
from typing import IO, Any, Generic, Protocol, TypeVar, overload

from medkit_replay.errors import MedkitReplayError

T = TypeVar("T")
DEFAULT_CHUNK = 16384

Row = tuple[object, ...]


class SpoolError(MedkitReplayError):
    """The temporary file could not be written (a full disk, a file size limit): exit 2."""

    def __init__(self, err: OSError) -> None:
        cause = err.strerror or str(err)
        if err.errno is not None and err.errno in errno.errorcode:
            cause = f"{cause} ({errno.errorcode[err.errno]})"
        super().__init__(
            f"cannot spool records to the temporary directory {tempfile.gettempdir()}: {cause}; "
            "free space there or set TMPDIR to a directory with room"
        )


class RowCodec(Protocol[T]):
    """A record type's flat form: ``decode(encode(record)) == record``."""

    def encode(self, item: T, /) -> Row:
        """The record as a tuple."""
        ...

    def decode(self, row: Row, /) -> T:
        """The record a tuple stands for."""
        ...


class SpillListener(Protocol):
    """Told of every chunk a spool spills, with the pickled rows it wrote (to work on them
    elsewhere while the replay goes on: ``outputs/json_ahead.py``)."""

    def spilled(self, spool: Spool[Any], index: int, data: bytes, /) -> None:
        """Chunk ``index`` of ``spool`` is on disk; ``data`` is its pickled list of rows."""
        ...


class Spool(Sequence[T], Generic[T]):
    """A list-like sequence of records; all but the newest chunk live on disk.

    The temporary file is unnamed (deleted as soon as it is created on POSIX) and lives in
    the system's temporary directory, never beside an input. Not to be read while records
    are still being appended.
    """

    def __init__(
        self,
        chunk_size: int | None = None,
        *,
        codec: RowCodec[T] | None = None,
        listener: SpillListener | None = None,
    ) -> None:
        self._chunk_size = max(chunk_size or DEFAULT_CHUNK, 1)
        self._codec = codec
        self._listener = listener if codec is not None else None  # rows only
        self._tail: list[object] = []  # records, and rows with a codec; never replaced
        self._chunks: list[tuple[int, int]] = []  # (file offset, byte length) per spilled chunk
        self._starts: list[int] = []  # index of each spilled chunk's first record
        self._spilled = 0
        self._file: IO[bytes] | None = None
        self._cache: tuple[int, list[object]] | None = None

    @property
    def codec(self) -> RowCodec[T] | None:
        """How records are kept as rows (None: kept as records)."""
        return self._codec

    def append(self, item: T) -> None:
        """Add a record at the end."""
        self._tail.append(item)
        if len(self._tail) >= self._chunk_size:
            self._spill()

    def append_row(self, row: Row) -> None:
        """Add a record given in its row form (only with a codec)."""
        assert self._codec is not None
        self._tail.append(row)
        if len(self._tail) >= self._chunk_size:
            self._spill()

    def row_sink(self) -> Callable[[Row], None]:
        """The fastest way to add rows: the tail's own ``append``, with no size check.

        Whoever appends through it calls :meth:`settle` now and then, which spills what has
        piled up; memory stays bounded by how often it does.
        """
        assert self._codec is not None
        return self._tail.append

    def settle(self) -> None:
        """Spill the records in memory if they fill a chunk."""
        if len(self._tail) >= self._chunk_size:
            self._spill()

    def spill(self) -> None:
        """Spill the records in memory now, however few (a listener then has every record)."""
        if self._tail:
            self._spill()

    def _spill(self) -> None:
        tail = self._tail
        if self._codec is not None:
            encode = self._codec.encode
            tail = [x if type(x) is tuple else encode(x) for x in tail]  # type: ignore[arg-type]
        data = pickle.dumps(tail, protocol=pickle.HIGHEST_PROTOCOL)
        try:
            if self._file is None:
                self._file = tempfile.TemporaryFile(prefix="medkit-replay-")  # noqa: SIM115  # closed in close()
            self._file.seek(0, 2)
            offset = self._file.tell()
            self._file.write(data)
            self._file.flush()  # a full disk shows here, not at some later read
        except OSError as err:
            self.close()
            raise SpoolError(err) from None
        self._chunks.append((offset, len(data)))
        self._starts.append(self._spilled)
        self._spilled += len(self._tail)
        self._tail.clear()  # in place: row_sink() hands out its append
        if self._listener is not None:
            self._listener.spilled(self, len(self._chunks) - 1, data)

    def _chunk(self, index: int) -> list[object]:
        if self._cache is not None and self._cache[0] == index:
            return self._cache[1]
        assert self._file is not None
        offset, size = self._chunks[index]
        # Positional: a forked writer reading the same file shares no file offset with us.
        chunk: list[object] = pickle.loads(os.pread(self._file.fileno(), size, offset))  # ours
        self._cache = (index, chunk)
        return chunk

    def _records(self, items: list[object], start: int = 0) -> Iterator[T]:
        """The records of a chunk or the tail from ``start``; rows are replaced by their
        records as read."""
        codec = self._codec
        if codec is None:
            yield from itertools.islice(items, start, None)  # records, without a codec
            return
        for index in range(start, len(items)):
            item = items[index]
            if type(item) is tuple:
                item = items[index] = codec.decode(item)
            yield item  # type: ignore[misc]  # a record

    def rows(self) -> Iterator[Row]:
        """The records in their row form, in order (only with a codec)."""
        codec = self._codec
        assert codec is not None
        for index in range(len(self._chunks)):
            for item in self._chunk(index):
                yield item if type(item) is tuple else codec.encode(item)  # type: ignore[arg-type]
        for item in self._tail:
            yield item if type(item) is tuple else codec.encode(item)  # type: ignore[arg-type]

    def row_batches(self) -> Iterator[list[Row]]:
        """The records in their row form, in order, a chunk at a time (only with a codec)."""
        for index in range(self.batch_count):
            if items := self.row_batch(index):
                yield items

    @property
    def batch_count(self) -> int:
        """How many batches :meth:`row_batch` has: the spilled chunks, then the tail."""
        return len(self._chunks) + 1

    def row_batch(self, index: int) -> list[Row]:
        """Spilled chunk ``index`` (the tail after the last) in row form (only with a codec)."""
        codec = self._codec
        assert codec is not None
        items = self._chunk(index) if index < len(self._chunks) else self._tail
        if set(map(type, items)) - {tuple}:  # some were read back as records
            items = [x if type(x) is tuple else codec.encode(x) for x in items]  # type: ignore[arg-type]
        return items  # type: ignore[return-value]  # rows only now

    def __len__(self) -> int:
        return self._spilled + len(self._tail)

    def __iter__(self) -> Iterator[T]:
        return self.iter_from(0)

    def iter_from(self, start: int) -> Iterator[T]:
        """The records from index ``start`` on, in order (none past the end): the chunks
        before the one holding ``start`` are neither read nor decoded."""
        if start < 0:
            raise ValueError(f"a spool is read from index 0 or more, not {start}")
        return self._iter_from(start)

    def _iter_from(self, start: int) -> Iterator[T]:
        first = bisect_right(self._starts, start) - 1 if start < self._spilled else None
        if first is not None:
            yield from self._records(self._chunk(first), start - self._starts[first])
            for index in range(first + 1, len(self._chunks)):
                yield from self._records(self._chunk(index))
        yield from self._records(self._tail, max(start - self._spilled, 0))

    @overload
    def __getitem__(self, index: int) -> T: ...
    @overload
    def __getitem__(self, index: slice) -> Sequence[T]: ...
    def __getitem__(self, index: int | slice) -> T | Sequence[T]:
        length = len(self)
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(length))]
        if index < 0:
            index += length
        if not 0 <= index < length:
            raise IndexError(index)
        if index >= self._spilled:
            items, at = self._tail, index - self._spilled
        else:
            chunk = bisect_right(self._starts, index) - 1
            items, at = self._chunk(chunk), index - self._starts[chunk]
        item = items[at]
        if self._codec is not None and type(item) is tuple:
            item = items[at] = self._codec.decode(item)
        return item  # type: ignore[return-value]  # a record

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Sequence) and not isinstance(other, str):
            return len(self) == len(other) and all(a == b for a, b in zip(self, other, strict=True))
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]  # mutable, like list

    def __del__(self) -> None:
        self.close()

    def close(self) -> None:
        """Release the temporary file (the records on disk are gone afterwards)."""
        if self._file is not None:
            self._file.close()
            self._file = None
