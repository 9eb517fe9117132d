"""Where a storage file's bytes come from: reads at offsets, with hints of what is read next.

The MCAP reader reads through a RangeReader, so a local file (the page cache takes the hints)
and a remote object (the hints become concurrent range requests) share one reading code.
"""

from __future__ import annotations

import os
from contextlib import suppress
from typing import TYPE_CHECKING, BinaryIO, Protocol

from medkit_replay.closing import Closing
from medkit_replay.files import open_regular

if TYPE_CHECKING:
    from collections.abc import Callable
    from pathlib import Path
    from types import TracebackType
    from typing import Self

_fadvise = getattr(os, "posix_fadvise", None)  # not on every platform
_WILLNEED = getattr(os, "POSIX_FADV_WILLNEED", 3)
_NOWAIT = getattr(os, "RWF_NOWAIT", 0)
_preadv = getattr(os, "preadv", None) if _NOWAIT else None


class RangeReader(Protocol):
    """Random access to one file's bytes; a context manager that releases what it holds."""

    size: int
    always_ahead: bool
    """Whether every read waits unless asked ahead (a network), so a reader should keep asking
    ahead even when the last bytes were at hand; False: only when they were not (a disk)."""

    def read(self, offset: int, length: int) -> bytes:
        """``length`` bytes at ``offset``; fewer only where the file ends."""
        ...

    def read_into(self, offset: int, view: memoryview) -> int:
        """Fill ``view`` with the bytes at ``offset``; returns how many (fewer at the end)."""
        ...

    def cached(self, offset: int, length: int) -> bytes | None:
        """The bytes if they can be had without waiting, else None (then :meth:`will_need`)."""
        ...

    def will_need(self, offset: int, length: int) -> None:
        """A hint: these bytes will be read soon (ranges outside the file are ignored)."""
        ...

    def forget(self, before: int) -> None:
        """A hint: bytes before this offset will not be read again (what is held may go)."""
        ...

    def close(self) -> None:
        """Release what is held (a file, connections, fetched bytes)."""
        ...

    def __enter__(self) -> Self: ...

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None: ...


class ByteSource(Protocol):
    """A storage file's bytes, opened for random access or for reading from the start."""

    def ranges(self) -> RangeReader:
        """Open for reads at offsets."""
        ...

    def stream(self) -> BinaryIO:
        """Open for sequential reading from the first byte (seekable)."""
        ...


class LocalSource:
    """A local file: positioned reads, and the kernel's page cache for read-ahead.

    ``check`` is given each descriptor opened (a followed file checks it is still the one
    read so far); what it raises propagates, the descriptor closed.
    """

    def __init__(self, path: Path, check: Callable[[int], None] | None = None) -> None:
        self.path = path
        self._check = check

    def ranges(self) -> LocalRanges:
        return LocalRanges(self.path, self._check)

    def stream(self) -> BinaryIO:
        stream = open_regular(self.path)
        try:
            if self._check is not None:
                self._check(stream.fileno())
        except BaseException:
            stream.close()
            raise
        return stream  # type: ignore[return-value]  # a BufferedReader


class LocalRanges(Closing):
    """:class:`RangeReader` over an open local file."""

    always_ahead = False

    def __init__(self, path: Path, check: Callable[[int], None] | None = None) -> None:
        self._file = open_regular(path)  # a FIFO or device is refused, never waited on
        self._fd = self._file.fileno()
        try:
            if check is not None:
                check(self._fd)
            self.size = os.fstat(self._fd).st_size
        except BaseException:
            self._file.close()
            raise

    def read(self, offset: int, length: int) -> bytes:
        if length <= 0:
            return b""
        data = os.pread(self._fd, length, offset)
        if len(data) == length or not data:
            return data
        buffer = bytearray(length)
        return bytes(buffer[: self.read_into(offset, memoryview(buffer))])

    def read_into(self, offset: int, view: memoryview) -> int:
        done = 0
        while done < len(view):
            got = os.preadv(self._fd, [view[done:]], offset + done)
            if not got:
                break
            done += got
        return done

    def cached(self, offset: int, length: int) -> bytes | None:
        """None also where the system cannot tell (no RWF_NOWAIT): the caller then hints."""
        if _preadv is None or _fadvise is None:
            return None
        buffer = bytearray(length)
        try:
            got = _preadv(self._fd, [buffer], offset, _NOWAIT)
        except OSError:  # BlockingIOError: not cached; others: not supported here
            return None
        if got != length and offset + got < self.size:
            return None  # partly cached: read it as usual
        return bytes(buffer[:got])

    def will_need(self, offset: int, length: int) -> None:
        if _fadvise is not None and offset >= 0 and 0 < length <= self.size - offset:
            with suppress(OSError):
                _fadvise(self._fd, offset, length, _WILLNEED)

    def forget(self, before: int) -> None:
        """Nothing held: the page cache keeps what it will."""

    def close(self) -> None:
        self._file.close()
