"""Whether a followed file is still the one first seen: the same device and inode, never shorter.

A file renamed over, swapped behind a symlink or cut is a :class:`FollowRestart`: its replay
starts again from the new file's start, never reading the new bytes at the old offsets.
"""

from __future__ import annotations

import os
import stat
from typing import TYPE_CHECKING

from medkit_replay.files import FileRefusedError, kind_of

if TYPE_CHECKING:
    from pathlib import Path


class FollowRestart(BaseException):  # not an Exception: no reader's last-resort handler takes it
    """The followed recording is no longer the file read so far: replay it again from its start."""

    def __init__(self, reason: str) -> None:
        self.reason = reason
        super().__init__(reason)


class Watched:
    """A followed file (or bag folder) and what it was when first seen: identity and size.

    Raises:
        FileNotFoundError, OSError: the path cannot be looked up.
        FileRefusedError: the path is a FIFO, device or socket (a folder, unless ``folder``):
            it is never opened, so nothing blocks on it.
    """

    def __init__(self, path: Path, *, folder: bool = False) -> None:
        info = path.stat()
        expected = stat.S_ISDIR if folder else stat.S_ISREG
        if not expected(info.st_mode):
            raise FileRefusedError(f"{kind_of(info.st_mode)}, not a regular file")
        self.path = path
        self.identity = (info.st_dev, info.st_ino)
        self.size = 0 if folder else info.st_size
        self._folder = folder

    def look(self) -> int:
        """The file's size now (never less than before); a removed file keeps its last size
        (rosbag2 removes a split file it compressed; what was open stays readable).

        Raises:
            FollowRestart: the path names another file now, or the file shrank.
        """
        try:
            info = self.path.stat()
        except FileNotFoundError:
            return self.size
        if (info.st_dev, info.st_ino) != self.identity:
            raise FollowRestart(f"{self.path} was replaced by another file")
        if not self._folder:
            if info.st_size < self.size:
                raise FollowRestart(
                    f"{self.path} was cut from {self.size:,} to {info.st_size:,} bytes"
                )
            self.size = info.st_size
        return self.size

    def check_open(self, fd: int) -> None:
        """Check that a descriptor just opened by the path is of this file.

        Raises:
            FollowRestart: it is another file (the path was replaced meanwhile).
        """
        info = os.fstat(fd)
        if (info.st_dev, info.st_ino) != self.identity:
            raise FollowRestart(f"{self.path} was replaced by another file")
