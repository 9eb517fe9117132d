"""The JSON report's long lists encoded by a helper process while the replay still runs.

Every chunk of rows a spool spills is handed, as the bytes it pickled, to a child process that
writes it as report lines (``json_report.encode_batch``, the one encoder) into an unnamed file;
the report then copies those lines. Whatever the child does not deliver is encoded here.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import pickle
import subprocess
import sys
import tempfile
import threading
from collections import deque
from struct import Struct
from typing import IO, TYPE_CHECKING, Any

from medkit_replay.closing import Closing
from medkit_replay.outputs.json_report import SPOOLED_LISTS, encode_batch
from medkit_replay.outputs.json_rows import ROW_SEPARATOR

if TYPE_CHECKING:
    from medkit_replay.spool import Spool

_FRAME = Struct("<I32sIQ")  # list number, record class, chunk index, length of the pickled rows
_DONE = Struct("<IIQQ")  # list number, chunk index, offset and length of its lines in the file
QUEUE_LIMIT = 64 * 1024 * 1024
"""Pickled bytes waiting for the child at most; chunks beyond it are encoded here instead."""
PIPE_SIZE = 1024 * 1024
"""Bytes the pipe to the child holds, asked of the system (Linux allows up to 1 MiB by default)."""
FRAME_LIMIT = 1 << 31
"""The largest chunk the child takes (a spool chunk pickles to a few MB)."""


class JsonAhead(Closing):
    """A :class:`~medkit_replay.spool.SpillListener` that has a child process encode spilled
    chunks, and an ``EncodedAhead`` for ``json_report.write_json_bytes``.

    The child starts at the first spill (a short recording never spills: no process). A chunk
    is sent by a writer thread, so the replay never waits for the child; should the child fall
    behind by QUEUE_LIMIT, die or fail, the chunks it did not finish are encoded by the report
    as usual: the bytes are the same either way.
    """

    def __init__(self) -> None:
        # id(spool) -> (list number, the spool, its record class's name); the spool is held
        # so that ids stay unique
        self._lists: dict[int, tuple[int, Spool[Any], bytes]] = {}
        self._child: subprocess.Popen[bytes] | None = None
        self._file: IO[bytes] | None = None
        self._queue: deque[bytes] = deque()
        self._queued = 0
        self._lock = threading.Condition()
        self._closing = False
        self._thread: threading.Thread | None = None
        self._failed = False
        self._sent: set[tuple[int, int]] = set()  # chunks handed to the writer thread
        self._done: dict[tuple[int, int], tuple[int, int]] = {}  # answered: (offset, length)
        self._finished = False  # nothing more is sent
        self._ended = False  # the child's answers are all read

    # -- while the replay runs -----------------------------------------------------------

    def spilled(self, spool: Spool[Any], index: int, data: bytes, /) -> None:
        """Send a spilled chunk of one of the report's long lists to the child."""
        if self._failed or self._finished:
            return
        known = self._lists.get(id(spool))
        if known is None:
            name = getattr(getattr(spool.codec, "cls", None), "__name__", "")
            if name not in SPOOLED_LISTS:
                return
            known = self._lists[id(spool)] = (len(self._lists), spool, name.encode("ascii"))
        if self._child is None and not self._start():
            return
        frame = _FRAME.pack(known[0], known[2], index, len(data)) + data
        with self._lock:
            if self._queued + len(frame) > QUEUE_LIMIT:
                return  # the child is behind: this chunk is encoded at the end instead
            self._queue.append(frame)
            self._queued += len(frame)
            self._sent.add((known[0], index))
            self._lock.notify()

    def _start(self) -> bool:
        try:
            self._file = tempfile.TemporaryFile(prefix="medkit-replay-json-")  # noqa: SIM115  # closed in close()
            fd = self._file.fileno()
            self._child = subprocess.Popen(  # our own module, by our interpreter
                [sys.executable, "-m", __name__, str(fd)],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=subprocess.DEVNULL,
                pass_fds=(fd,),
            )
        except OSError:
            self._failed = True
            self.close()
            return False
        if hasattr(fcntl, "F_SETPIPE_SZ") and self._child.stdin is not None:
            # A chunk in one write where the system allows: the writer thread then seldom
            # waits for the child, nor takes the interpreter lock back and forth meanwhile.
            with contextlib.suppress(OSError):
                fcntl.fcntl(self._child.stdin.fileno(), fcntl.F_SETPIPE_SZ, PIPE_SIZE)
        thread = threading.Thread(target=self._send, name="medkit-replay-json", daemon=True)
        try:
            thread.start()
        except RuntimeError:  # no thread to be had: everything is encoded at the end
            self._failed = True
            self.close()
            return False
        self._thread = thread
        return True

    def _send(self) -> None:
        """The writer thread: frames to the child's stdin, in order, until closing."""
        child = self._child
        assert child is not None and child.stdin is not None
        while True:
            with self._lock:
                while not self._queue and not self._closing:
                    self._lock.wait()
                if not self._queue:
                    break
                frame = self._queue.popleft()
                self._queued -= len(frame)
            try:
                child.stdin.write(frame)
            except OSError:  # the child is gone: the rest is encoded by the report
                self._failed = True
                break
        with contextlib.suppress(OSError):
            child.stdin.close()

    # -- when the report is written --------------------------------------------------------

    def encoded(self, spool: Spool[Any], index: int, /) -> bytes | None:
        """Chunk ``index`` of ``spool`` as report lines, or None when the child has not it.

        Waits for that chunk only: the child may still be encoding later ones meanwhile.
        """
        self.finish()
        known = self._lists.get(id(spool))
        if known is None or known[1] is not spool or self._file is None:
            return None
        key = (known[0], index)
        while key not in self._done and key in self._sent and self._answer():
            pass
        where = self._done.get(key)
        if where is None:
            return None
        offset, length = where
        data = os.pread(self._file.fileno(), length, offset)
        return data if len(data) == length else None

    def finish(self) -> None:
        """Send nothing more: the child encodes what it has and ends. Call it before forking
        (the child's stdin must be closed here alone for it to see its end)."""
        if self._finished:
            return
        self._finished = True
        with self._lock:
            self._closing = True
            self._lock.notify()
        if self._thread is not None:
            self._thread.join()

    def delivered(self) -> dict[tuple[int, int], tuple[int, int]]:
        """Every chunk the child encoded, (list number, index) -> (offset, length), once it
        has ended."""
        self.finish()
        while self._answer():
            pass
        return dict(self._done)

    def _answer(self) -> bool:
        """Take the child's next answer; False at its end (then it is waited for).

        An answer is written only once its lines are whole in the file, so each one holds
        even if the child fails later.
        """
        child = self._child
        if child is None or child.stdout is None or self._ended:
            return False
        data = child.stdout.read(_DONE.size)
        if len(data) == _DONE.size:
            number, index, offset, length = _DONE.unpack(data)
            self._done[(number, index)] = (offset, length)
            return True
        self._ended = True
        child.wait()
        return False

    def close(self) -> None:
        """Stop the child (if still running) and release the file."""
        with self._lock:
            self._closing = True
            self._queue.clear()
            self._lock.notify()
        child = self._child
        if child is not None and child.poll() is None:
            child.kill()
            child.wait()
        if child is not None:
            for stream in (child.stdin, child.stdout):
                if stream is not None:
                    with contextlib.suppress(OSError):
                        stream.close()
        if self._file is not None:
            self._file.close()
            self._file = None


def _read_exactly(stream: IO[bytes], size: int) -> bytes | None:
    data = stream.read(size)
    return data if len(data) == size else None


def _child(fd: int) -> int:
    """The child: frames from stdin, report lines into ``fd``, one answer per chunk."""
    source, answers = sys.stdin.buffer, sys.stdout.buffer
    offset = 0
    while (head := _read_exactly(source, _FRAME.size)) is not None:
        number, name, index, length = _FRAME.unpack(head)
        spooled = SPOOLED_LISTS.get(name.rstrip(b"\0").decode("ascii", "replace"))
        if length > FRAME_LIMIT or spooled is None:
            return 2
        data = _read_exactly(source, length)
        if data is None:
            return 2
        rows = pickle.loads(data)  # written by our parent, from its own spool
        lines = ROW_SEPARATOR.join(encode_batch(*spooled, rows))
        written = os.pwrite(fd, lines, offset)
        if written != len(lines):
            return 2
        answers.write(_DONE.pack(number, index, offset, len(lines)))
        answers.flush()  # the parent may be waiting for this very chunk
        offset += len(lines)
    answers.flush()
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 2 or not sys.argv[1].isdigit():
        sys.exit("medkit-replay: the report's encoding helper, started by analyze itself")
    sys.exit(_child(int(sys.argv[1])))
