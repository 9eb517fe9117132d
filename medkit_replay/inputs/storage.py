"""Records shared by the storage readers: connections, raw messages, the reader protocol, limits.

Holds no reading code; the MCAP and sqlite3 readers and the rosbag2 layer above them import it.
"""

from __future__ import annotations

import os
import tempfile
from typing import TYPE_CHECKING, NamedTuple, Protocol

from medkit_replay.msgdefs import NO_DEFINITION, Definition

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator
    from pathlib import Path

    from medkit_replay.inputs.merge import Bound, Timed
    from medkit_replay.inputs.source import Warn

RECORD_SIZE_LIMIT = 1 << 30
"""Largest record, chunk or payload (bytes) a length field may make a reader allocate.

A length above it, or above what is left of the file, is treated as damage, not obeyed.
"""

MESSAGE_SIZE_LIMIT = 256 * 1024 * 1024
"""Largest payload one sqlite3 message row may make a reader load (bytes); larger is damage.

No ROS message the replay reads comes near it (a raw 4K camera frame is 25 MB), and SQLite
itself would build a blob up to 1 GB (or a generated column computes one) before we see it.
"""

TEMP_MARGIN = 256 * 1024 * 1024
"""Free space (bytes) a temporary copy or decompressed file must leave in the temporary folder."""


def temp_room() -> int:
    """Bytes a temporary file may take in the temporary folder: its free space less TEMP_MARGIN."""
    try:
        info = os.statvfs(tempfile.gettempdir())
    except OSError:
        return 0
    return max(0, info.f_bavail * info.f_frsize - TEMP_MARGIN)


class Connection(NamedTuple):
    """One topic of one storage file, as the file declares it."""

    id: int
    topic: str
    msgtype: str
    serialization: str
    definition: Definition = NO_DEFINITION


class Raw(NamedTuple):
    """A stored message not yet decoded."""

    connection: Connection
    data: bytes | memoryview


class NotABagError(Exception):
    """A file cannot be read as the storage its name or metadata claims (nothing readable)."""


class StorageFields:
    """What a storage file reader holds from the start (see :class:`StorageFile`): where it is,
    its number in its input, where it warns, and what it declares (empty until probed)."""

    def __init__(self, path: Path, file_no: int, warn: Warn) -> None:
        self.path = path
        self.file_no = file_no
        self.warn = warn
        self.connections: dict[int, Connection] = {}
        self.counts: dict[int, int] = {}
        self.start_ns: int | None = None
        self.end_ns: int | None = None


class StorageFile(Protocol):
    """One storage file (an ``.mcap`` or ``.db3``), probed when constructed, read on demand.

    After construction ``connections``, ``counts``, ``start_ns`` and ``end_ns`` hold what the
    file's index declares (or nothing, for a file without one); reading completes them.
    """

    path: Path
    storage: str
    connections: dict[int, Connection]
    counts: dict[int, int]
    start_ns: int | None
    end_ns: int | None

    def read(
        self, wants: Callable[[Connection], bool], cap_ns: int | None
    ) -> Iterator[Bound | Timed[Raw] | list[Timed[Raw]]]:
        """Yield bounds and the messages of the connections ``wants`` accepts, in file order.

        A list is a batch of messages sorted by ``(t_ns, position)`` with no bound among them
        (see :func:`medkit_replay.inputs.merge.reorder_batches`).

        Args:
            wants: called once per connection, before any of its messages.
            cap_ns: start of the next file of the same input, if known; no bound exceeds it.
        """
        ...

    def close(self) -> None:
        """Release what the file holds between probing and reading (temporary copies)."""
        ...
