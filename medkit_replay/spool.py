"""An append-only record sequence that spills full chunks to an anonymous temporary file.

Keeps a replay's memory bounded by the chunk size however many records a recording yields.
"""

from __future__ import annotations

import pickle
import tempfile
from collections.abc import Iterator, Sequence
from typing import IO, Generic, TypeVar, overload

T = TypeVar("T")
DEFAULT_CHUNK = 16384


class Spool(Sequence[T], Generic[T]):
    """A list-like sequence of records; all but the newest chunk live on disk.

    The temporary file is unnamed (deleted as soon as it is created on POSIX) and lives in
    the system's temporary directory, never beside an input.
    """

    def __init__(self, chunk_size: int | None = None) -> None:
        self._chunk_size = max(chunk_size or DEFAULT_CHUNK, 1)
        self._tail: list[T] = []
        self._offsets: list[tuple[int, int]] = []  # (file offset, byte length) per chunk
        self._file: IO[bytes] | None = None
        self._length = 0
        self._cache: tuple[int, list[T]] | None = None

    def append(self, item: T) -> None:
        """Add a record at the end."""
        self._tail.append(item)
        self._length += 1
        if len(self._tail) >= self._chunk_size:
            self._spill()

    def _spill(self) -> None:
        if self._file is None:
            self._file = tempfile.TemporaryFile(prefix="medkit-replay-")  # noqa: SIM115  # closed in close()
        data = pickle.dumps(self._tail, protocol=pickle.HIGHEST_PROTOCOL)
        self._file.seek(0, 2)
        self._offsets.append((self._file.tell(), len(data)))
        self._file.write(data)
        self._tail = []

    def _chunk(self, index: int) -> list[T]:
        if self._cache is not None and self._cache[0] == index:
            return self._cache[1]
        assert self._file is not None
        offset, size = self._offsets[index]
        self._file.seek(offset)
        chunk: list[T] = pickle.loads(self._file.read(size))  # our own file
        self._cache = (index, chunk)
        return chunk

    def __len__(self) -> int:
        return self._length

    def __iter__(self) -> Iterator[T]:
        for index in range(len(self._offsets)):
            yield from self._chunk(index)
        yield from self._tail

    @overload
    def __getitem__(self, index: int) -> T: ...
    @overload
    def __getitem__(self, index: slice) -> Sequence[T]: ...
    def __getitem__(self, index: int | slice) -> T | Sequence[T]:
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(self._length))]
        if index < 0:
            index += self._length
        if not 0 <= index < self._length:
            raise IndexError(index)
        spilled = len(self._offsets) * self._chunk_size
        if index >= spilled:
            return self._tail[index - spilled]
        return self._chunk(index // self._chunk_size)[index % self._chunk_size]

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
