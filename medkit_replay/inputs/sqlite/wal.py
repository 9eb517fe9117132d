"""SQLite ``-wal`` files applied to private copies, never beside the database: a finished bag's
checkpointed copy, and the copy of a database a writer is still changing, kept current.

Only committed frames of the ``-wal`` are applied, to our copy; nothing beside the database is
opened for writing, locked or created (no ``-shm``): the writer never waits for us.
"""

from __future__ import annotations

import shutil
import sqlite3
import struct
from contextlib import closing
from pathlib import Path
from tempfile import TemporaryDirectory
from typing import TYPE_CHECKING

from medkit_replay.files import FileRefusedError, open_regular
from medkit_replay.inputs.storage import temp_room
from medkit_replay.model import Loss

if TYPE_CHECKING:
    from typing import BinaryIO

    from medkit_replay.inputs.source import Warn

_WAL_MAGICS = (0x377F0682, 0x377F0683)  # checksums in little- or big-endian words
_WAL_VERSION = 3007000
_HEADER = 32
_FRAME_HEADER = 24
_MASK = 0xFFFFFFFF
RESYNC_ATTEMPTS = 3
"""Copies of the database tried per refresh while the writer restarts its WAL under us."""


def _checksum(data: bytes, sums: tuple[int, int], big: bool) -> tuple[int, int]:
    """SQLite's WAL checksum of ``data`` (a multiple of 8 bytes), continued from ``sums``."""
    words = struct.unpack(f"{'>' if big else '<'}{len(data) // 4}I", data)
    s1, s2 = sums
    for k in range(0, len(words), 2):
        s1 = (s1 + words[k] + s2) & _MASK
        s2 = (s2 + words[k + 1] + s1) & _MASK
    return s1, s2


class _Header:
    """A WAL header as SQLite reads it: its byte order, page size, salts and checksum."""

    __slots__ = ("big", "page_size", "salts", "sums")

    def __init__(
        self, big: bool, page_size: int, salts: tuple[int, int], sums: tuple[int, int]
    ) -> None:
        self.big = big
        self.page_size = page_size
        self.salts = salts
        self.sums = sums

    @staticmethod
    def parse(raw: bytes) -> _Header | None:
        """The header ``raw`` (a WAL's first bytes) holds; None when SQLite would not read it
        as one (too short, another magic or version, an impossible page size)."""
        if len(raw) < _HEADER:
            return None
        magic, version, size, _, salt1, salt2, c1, c2 = struct.unpack(">8I", raw[:_HEADER])
        size = 65536 if size == 1 else size
        if magic not in _WAL_MAGICS or version != _WAL_VERSION or not 512 <= size <= 65536:
            return None
        if size & (size - 1):
            return None
        return _Header(bool(magic & 1), size, (salt1, salt2), (c1, c2))

    @staticmethod
    def read(wal: Path) -> _Header | None:
        """The header of ``wal`` when it passes its own checksum; None when there is none (no
        file, empty, not yet written)."""
        try:
            with open_regular(wal) as stream:
                raw = stream.read(_HEADER)
        except OSError:
            return None
        header = _Header.parse(raw)
        if header is None or _checksum(raw[:24], (0, 0), header.big) != header.sums:
            return None
        return header

    def same(self, other: _Header | None) -> bool:
        return other is not None and other.salts == self.salts and other.sums == self.sums


def _committed_wal_bytes(wal: Path) -> int:
    """Bytes of a ``-wal`` SQLite would apply: its header and frames up to the last commit.

    SQLite stops at the first frame whose salts differ from the header's (as every hole of
    a sparse file does), so nothing after it needs copying; 0 when no transaction is there.
    """
    with open_regular(wal) as stream:
        header = _Header.parse(stream.read(_HEADER))
        if header is None:
            return 0
        salts = list(header.salts)
        frame = _FRAME_HEADER + header.page_size
        position = end = _HEADER
        while True:
            stream.seek(position)
            head = stream.read(16)
            _, commit, *frame_salts = struct.unpack(">4I", head) if len(head) == 16 else (0, 0)
            if frame_salts != salts or len(stream.read(frame - 16)) != frame - 16:
                break
            position += frame
            if commit:
                end = position
        return end if end > _HEADER else 0


def _copy_prefix(source: Path, target: Path, size: int) -> None:
    with open_regular(source) as stream, target.open("wb") as sink:
        while size > 0:
            block = stream.read(min(size, 1 << 20))
            if not block:
                break
            sink.write(block)
            size -= len(block)


def checkpointed_copy(path: Path, warn: Warn) -> tuple[TemporaryDirectory[str], Path] | None:
    """A temporary copy of ``path`` with its ``-wal`` applied, when the wal holds data.

    ``immutable`` would ignore the wal; applying it in place would write beside the recording.
    Only the wal's committed frames are copied, and only when they fit the temporary folder.
    """
    wal = path.with_name(path.name + "-wal")
    journal = path.with_name(path.name + "-journal")
    try:
        if journal.is_file() and journal.stat().st_size:
            warn(f"{path}: an unfinished transaction in {journal.name} is not read", Loss())
        if not wal.exists():
            return None
        size = _committed_wal_bytes(wal)
        database = path.stat().st_size
    except (OSError, FileRefusedError) as exc:
        warn(f"{path}: {wal.name} cannot be read ({exc}); its data is not read", Loss())
        return None
    if not size:
        return None
    if database + size > temp_room():
        warn(
            f"{path}: {wal.name} holds data not yet checkpointed, but applying it needs a "
            f"{database + size:,}-byte copy, more than the temporary folder has room for; "
            "its data is not read",
            Loss(bytes=size),
        )
        return None
    folder = TemporaryDirectory(prefix="medkit-replay-")
    try:
        copy = Path(folder.name, path.name)
        shutil.copyfile(path, copy)
        _copy_prefix(wal, copy.with_name(wal.name), size)
        with closing(sqlite3.connect(copy)) as db:
            db.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    except (OSError, sqlite3.Error) as exc:
        folder.cleanup()
        warn(
            f"{path}: {wal.name} cannot be applied ({exc}); its data is not read", Loss(bytes=size)
        )
        return None
    except BaseException:
        folder.cleanup()
        raise
    warn(f"{path}: {wal.name} holds data not yet checkpointed; read from a copy")
    return folder, copy


def is_wal_mode(path: Path) -> bool:
    """Whether the database's header says WAL mode (file format versions 2)."""
    try:
        with open_regular(path) as stream:
            head = stream.read(20)
    except OSError:
        return False
    return len(head) == 20 and head[18] == 2 and head[19] == 2


class WalMirror:
    """Our copy of a live WAL-mode database, brought up to its last commit by :meth:`refresh`.

    While the writer's WAL keeps its salts, only the frames added since the last refresh are
    read and applied. When the writer restarts the WAL (after a checkpoint), the database
    file is copied again and the new WAL applied to the copy; the copy counts only if the WAL
    header stayed the same across it, so a checkpoint writing into the database meanwhile is
    overwritten by the frames it copied. Frames are applied one transaction at a time.
    """

    def __init__(self, path: Path, folder: Path) -> None:
        self.source = path
        self.wal = path.with_name(path.name + "-wal")
        self.copy = folder / path.name
        self._header: _Header | None = None
        self._wal_pos = _HEADER
        self._sums = (0, 0)
        self._synced = False

    def needs_copy(self) -> bool:
        """Whether the next refresh copies the database again (the WAL restarted, or first)."""
        header = _Header.read(self.wal)
        return not (
            self._synced
            and header is not None
            and self._header is not None
            and header.salts == self._header.salts
        )

    def refresh(self) -> bool:
        """Bring the copy up to the writer's last commit; whether it changed.

        Raises:
            OSError: the database cannot be read.
        """
        header = _Header.read(self.wal)
        if (
            self._synced
            and header is not None
            and self._header is not None
            and header.salts == self._header.salts
        ):
            return self._apply_new(self.copy, header)
        for _ in range(RESYNC_ATTEMPTS):
            if self._resync(header):
                return True
            header = _Header.read(self.wal)
        return False

    def _resync(self, header: _Header | None) -> bool:
        """Copy the database afresh and apply the whole WAL; False if the WAL changed meanwhile."""
        fresh = self.copy.with_name(self.copy.name + ".new")
        with open_regular(self.source) as stream, fresh.open("wb") as sink:
            shutil.copyfileobj(stream, sink, 1 << 20)
        self._wal_pos, self._sums = _HEADER, header.sums if header is not None else (0, 0)
        if header is not None:
            self._apply_new(fresh, header)
        after = _Header.read(self.wal)
        if not (header.same(after) if header is not None else after is None):
            fresh.unlink()
            self._synced = False  # the copy in place stays as it was; its state is gone
            return False
        fresh.replace(self.copy)
        self._header = header
        self._synced = True
        return True

    def _apply_new(self, target: Path, header: _Header) -> bool:
        """Apply the committed frames after the last applied one to ``target``."""
        frame = _FRAME_HEADER + header.page_size
        pos, sums = self._wal_pos, self._sums
        pending: list[tuple[int, bytes]] = []
        changed = False
        try:
            stream = open_regular(self.wal)
        except OSError:
            return False
        with stream, target.open("r+b") as sink:
            stream.seek(pos)
            while True:
                raw = stream.read(frame)
                if len(raw) < frame:
                    break
                pgno, pages, salt1, salt2, c1, c2 = struct.unpack(">6I", raw[:_FRAME_HEADER])
                if (salt1, salt2) != header.salts or not pgno:
                    break
                sums = _checksum(raw[:8] + raw[_FRAME_HEADER:], sums, header.big)
                if sums != (c1, c2):
                    break
                pending.append((pgno, raw[_FRAME_HEADER:]))
                pos += frame
                if pages:  # a commit frame: the transaction is whole
                    _write_pages(sink, pending, header.page_size, pages)
                    pending.clear()
                    self._wal_pos, self._sums = pos, sums
                    changed = True
        return changed


def _write_pages(
    sink: BinaryIO, pages: list[tuple[int, bytes]], page_size: int, db_pages: int
) -> None:
    for pgno, data in pages:
        sink.seek((pgno - 1) * page_size)
        sink.write(data)
    sink.truncate(db_pages * page_size)
