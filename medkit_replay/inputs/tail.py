"""A recording followed while it is written: its storage files read as they grow and appear.

A rosbag2 input whose files are found by polling; it ends when the recording is finished.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.errors import InputError
from medkit_replay.inputs.db3_tail import Db3Tail
from medkit_replay.inputs.follow import FollowStopped
from medkit_replay.inputs.mcap_tail import McapTail
from medkit_replay.inputs.rosbag2 import Rosbag2Input, _Metadata, _storage_files
from medkit_replay.inputs.storage import NotABagError
from medkit_replay.inputs.wal import is_wal_mode
from medkit_replay.model import Loss

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator
    from pathlib import Path

    from medkit_replay.inputs.follow import Follow
    from medkit_replay.inputs.merge import Bound, Timed
    from medkit_replay.inputs.source import InputContext
    from medkit_replay.inputs.storage import Raw, StorageFile

FOLLOWED_SUFFIXES = (".mcap", ".db3")
"""Storage files that can be followed (a file-compressed ``.zstd`` one is written whole)."""


def open_tail(path: Path, ctx: InputContext, follow: Follow) -> TailInput:
    """Open a rosbag2 directory, ``.mcap`` or ``.db3`` file to be followed while written.

    Raises:
        InputError: the path is of a kind that cannot be followed.
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
    """

    def __init__(self, path: Path, ctx: InputContext, follow: Follow) -> None:
        super().__init__(path, ctx, [], _Metadata())
        self._follow = follow
        self._directory = path.is_dir()

    def _finished(self) -> bool:
        return self._directory and (self.path / "metadata.yaml").exists()

    def _listing(self) -> list[Path]:
        return [p for p in _storage_files(self.path) if p.suffix.lower() in FOLLOWED_SUFFIXES]

    def _moved_on(self, index: int, path: Path) -> Callable[[], bool]:
        """Whether the writer is done with the file at ``index`` of the listing.

        In a directory: once metadata.yaml or a later file exists and, as rosbag2 writes them
        just before closing the file, a database has closed (its WAL gone) or that has lasted
        SETTLE_S. A bare ``.db3`` once its WAL is gone; a bare MCAP only by its Data End record.
        """
        wal = path.with_name(path.name + "-wal")
        closed = path.suffix.lower() == ".db3"  # a closed WAL-mode database has no -wal

        def done() -> bool:
            later = self._finished() or len(self._listing()) > index + 1
            if closed and later and not wal.exists() and is_wal_mode(path):
                return True
            return self._follow.lasting((self.path, index), later)

        if self._directory:
            return done
        if closed:
            return lambda: not wal.exists()
        return lambda: False

    def _next_path(self, index: int) -> Path | None:
        """The storage file at ``index`` once it exists; None when the recording has no more."""
        if not self._directory:
            return self.path if index == 0 else None
        while True:
            finished = self._finished()  # before listing: files written before it are seen
            files = self._listing()
            if index < len(files):
                self._follow.saw_data()
                return files[index]
            if finished:
                return None
            self._follow.wait()

    def _open_tail(self, path: Path, index: int) -> StorageFile:
        kind = McapTail if path.suffix.lower() == ".mcap" else Db3Tail
        return kind(
            path, index, self.ctx.warn, follow=self._follow, done=self._moved_on(index, path)
        )

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
