"""A recording followed while it is written: its storage files read as they grow and appear.

A rosbag2 input whose files are found by polling; it ends when the recording is finished.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.errors import InputError
from medkit_replay.files import FileRefusedError
from medkit_replay.inputs.follow import FollowStopped, Growing
from medkit_replay.inputs.mcap.tail import McapTail
from medkit_replay.inputs.metadata import Metadata
from medkit_replay.inputs.rosbag2 import Rosbag2Input, _natural_key
from medkit_replay.inputs.sqlite.tail import Db3Tail
from medkit_replay.inputs.sqlite.wal import is_wal_mode
from medkit_replay.inputs.storage import NotABagError
from medkit_replay.model import Loss

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator
    from pathlib import Path

    from medkit_replay.inputs.follow import Follow
    from medkit_replay.inputs.merge import Bound, Timed
    from medkit_replay.inputs.source import InputContext
    from medkit_replay.inputs.storage import Raw, StorageFile
    from medkit_replay.inputs.watch import Watched

FOLLOWED_SUFFIXES = (".mcap", ".db3")
"""Storage files that can be followed (a file-compressed ``.zstd`` one is written whole)."""


def open_tail(path: Path, ctx: InputContext, follow: Follow) -> TailInput:
    """Open a rosbag2 directory, ``.mcap`` or ``.db3`` file to be followed while written.

    Raises:
        InputError: the path is of a kind that cannot be followed.
        OSError: the path is not a regular file (a FIFO, a device) or cannot be looked up.
    """
    if not path.is_dir() and path.suffix.lower() not in FOLLOWED_SUFFIXES:
        raise InputError(
            "cannot be followed (a rosbag2 directory, an .mcap or a .db3 file can)",
            path=str(path),
        )
    return TailInput(path, ctx, follow)


class TailInput(Rosbag2Input):
    """A rosbag2 input read while written.

    A directory is finished when its metadata.yaml exists (rosbag2 writes it when recording
    ends); its storage files are taken in name order as they appear, each read until it is
    finished (an MCAP file's Data End record; a closed database; or, if neither comes, a later
    file or metadata.yaml present for SETTLE_S). A bare ``.mcap`` is finished at its Data End
    record, a bare ``.db3`` once no ``-wal`` is beside it. Until then every look at the files
    is one poll of the :class:`Follow`.

    The folder and every file read are watched (:class:`~medkit_replay.inputs.watch.Watched`):
    one replaced or cut ends the replay with a ``FollowRestart``, to start again. A new split
    file is read after the ones read so far; a storage file that is not a regular file (a FIFO,
    a device) is refused.
    """

    def __init__(self, path: Path, ctx: InputContext, follow: Follow) -> None:
        self._directory = path.is_dir()
        self._bare = None if self._directory else follow.watch(path)  # refuses a FIFO at once
        super().__init__(path, ctx, [], Metadata())
        self._follow = follow
        self._read: set[Path] = set()  # storage files taken so far
        if self._directory:
            follow.watch(path, folder=True)

    def _finished(self) -> bool:
        return self._directory and (self.path / "metadata.yaml").exists()

    def _listing(self) -> list[Path]:
        """The followed storage files in name order; any kind of file but a folder, so that one
        that is not a regular file is refused rather than passed over."""
        found = (
            p
            for p in self.path.iterdir()
            if p.suffix.lower() in FOLLOWED_SUFFIXES and not p.is_dir()
        )
        return sorted(found, key=_natural_key)

    def _moved_on(self, index: int, path: Path) -> Callable[[], bool]:
        """Whether the writer is done with ``path``, the ``index``-th file taken.

        In a directory: once metadata.yaml or a file not taken yet exists and, as rosbag2
        writes them just before closing the file, a database has closed (its WAL gone) or that
        has lasted SETTLE_S. A bare ``.db3`` once its WAL is gone; a bare MCAP only by its Data
        End record.
        """
        wal = path.with_name(path.name + "-wal")
        closed = path.suffix.lower() == ".db3"  # a closed WAL-mode database has no -wal

        def done() -> bool:
            later = self._finished() or any(p not in self._read for p in self._listing())
            if closed and later and not wal.exists() and is_wal_mode(path):
                return True
            return self._follow.lasting((self.path, index), later)

        if self._directory:
            return done
        if closed:
            return lambda: not wal.exists()
        return lambda: False

    def _next_path(self, index: int) -> Path | None:
        """The first storage file in name order not taken yet, once there is one; None when the
        recording has no more. (Taken files that go, as rosbag2 removes a split file it
        compressed, shift nothing.)"""
        if not self._directory:
            return self.path if index == 0 else None
        while True:
            finished = self._finished()  # before listing: files written before it are seen
            fresh = [p for p in self._listing() if p not in self._read]
            if fresh:
                self._follow.saw_data()
                self._read.add(fresh[0])
                return fresh[0]
            if finished:
                return None
            self._follow.wait()

    def _open_tail(self, path: Path, index: int) -> StorageFile:
        kind = McapTail if path.suffix.lower() == ".mcap" else Db3Tail
        growing = Growing(self._follow, self._moved_on(index, path), self._watch(path))
        return kind(path, index, self.ctx.warn, growing=growing)

    def _watch(self, path: Path) -> Watched:
        """Watch a storage file from now on.

        Raises:
            InputError: it is not a regular file (never opened, so nothing blocks on it).
            NotABagError: it cannot be looked up (then skipped).
        """
        if self._bare is not None:
            return self._bare
        try:
            return self._follow.watch(path)
        except FileRefusedError as exc:
            raise InputError(f"cannot be followed ({exc})", path=str(path)) from None
        except OSError as exc:
            raise NotABagError(f"cannot read: {exc.strerror or exc}") from None

    def _raw(self) -> Iterator[Bound | Timed[Raw] | list[Timed[Raw]]]:
        index = 0
        try:
            while (path := self._next_path(index)) is not None:
                try:
                    file = self._open_tail(path, index)
                except NotABagError as exc:
                    self.ctx.warn(f"{path}: {exc}", self._file_loss(path))
                    index += 1
                    continue
                self._files.append(file)
                self._caps.append(None)
                self.storage = self.storage or file.storage
                try:
                    for item in file.read(self._accepts(len(self._files) - 1), None):
                        yield item
                        self._follow.check()  # a stop is heard while data keeps coming
                        self._follow.saw_data()  # a backlog read is not idle time
                except Exception as exc:  # as for a finished file: no reader failure ends it
                    self.ctx.warn(f"{path}: reading stopped ({type(exc).__name__}: {exc})", Loss())
                index += 1
            self._follow.finished = True
        except FollowStopped as stop:
            self._follow.stopped = stop.reason
            self.ctx.warn(
                f"{self.path}: following stopped ({stop.reason}) before the recording was "
                "finished; the report covers what was read until then"
            )
