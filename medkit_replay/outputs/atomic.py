"""Writing an output safely: never over an input, and never a partial file at its target.

Each file is written to a temporary file beside its target and renamed into place only when
complete; on any failure or signal the temporary file is removed and the old target stays.
"""

from __future__ import annotations

import io
import os
import stat
import tempfile
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import IO, TYPE_CHECKING

from medkit_replay.errors import MedkitReplayError

if TYPE_CHECKING:
    from collections.abc import Iterable, Iterator

# How deep a bag folder is walked to learn its files' identities (hard links into it).
_MAX_WALK = 100_000


class OutputOverlapError(MedkitReplayError):
    """An output would be written over (or into) an input; nothing has been written."""


def _umask() -> int:
    current = os.umask(0)
    os.umask(current)
    return current


def _new_file_mode(target: Path) -> int:
    """The existing target's permission bits, or what ``open`` would give a new file."""
    try:
        return stat.S_IMODE(target.stat().st_mode)
    except OSError:
        return 0o666 & ~_umask()


def _is_special(target: Path) -> bool:
    """A device or FIFO (/dev/null, /dev/stdout, a pipe): written in place, never replaced."""
    try:
        mode = target.stat().st_mode
    except OSError:
        return False
    return stat.S_ISCHR(mode) or stat.S_ISFIFO(mode) or stat.S_ISSOCK(mode)


_PARTIAL = ".partial"


def _partial_prefix(target: Path, pid: int) -> str:
    """How the temporary files process ``pid`` writes for ``target`` begin (a hidden name)."""
    return f".{target.name}.{pid}."


def remove_partials(targets: Iterable[Path], pid: int) -> None:
    """Remove the temporary files process ``pid`` left beside ``targets`` (it was killed while
    writing them: nothing of its own could remove them). Only that process's files go."""
    for target in targets:
        prefix = _partial_prefix(Path(target), pid)
        with suppress(OSError), os.scandir(Path(target).parent) as entries:
            for entry in entries:
                if entry.name.startswith(prefix) and entry.name.endswith(_PARTIAL):
                    with suppress(OSError):
                        Path(entry.path).unlink()


@contextmanager
def atomic_binary(target: Path) -> Iterator[IO[bytes]]:
    """Open ``target`` for binary writing through a temporary file renamed into place on success.

    A device or FIFO target (/dev/null, /dev/stdout) is written in place; a file's folder is
    made (with its parents) when missing. On any exception, Ctrl-C or termination signal, the
    temporary file is removed and the old target is kept.
    """
    target = Path(target)
    if _is_special(target):
        with target.open("wb") as stream:
            yield stream
        return
    if target.is_dir():
        raise IsADirectoryError(21, "Is a directory", str(target))
    target.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(
        prefix=_partial_prefix(target, os.getpid()), suffix=_PARTIAL, dir=target.parent
    )
    try:
        with os.fdopen(handle, "wb") as stream:
            yield stream
            stream.flush()
            os.fsync(stream.fileno())
        Path(temporary).chmod(_new_file_mode(target))
        Path(temporary).replace(target)
    except BaseException:
        with suppress(OSError):
            Path(temporary).unlink()
        raise


@contextmanager
def atomic_text(target: Path, *, newline: str | None = "\n") -> Iterator[IO[str]]:
    """``atomic_binary`` for UTF-8 text."""
    with atomic_binary(target) as raw:
        stream = io.TextIOWrapper(raw, encoding="utf-8", newline=newline)
        try:
            yield stream
            stream.flush()
        finally:
            stream.detach()


def write_bytes_atomic(target: Path, data: bytes) -> None:
    """Write a whole file atomically."""
    with atomic_binary(target) as stream:
        stream.write(data)


def write_text_atomic(target: Path, text: str) -> None:
    """Write a whole UTF-8 text file atomically (newlines as given)."""
    with atomic_text(target) as stream:
        stream.write(text)


def _resolved(path: Path) -> Path:
    return Path(os.path.realpath(path))


def _identities(path: Path) -> set[tuple[int, int]]:
    """(device, inode) of a file, or of every file under a directory (bounded walk)."""
    found: set[tuple[int, int]] = set()
    try:
        info = path.stat()
    except OSError:
        return found
    found.add((info.st_dev, info.st_ino))
    if stat.S_ISDIR(info.st_mode):
        for count, (root, _dirs, files) in enumerate(os.walk(path)):
            if count > _MAX_WALK:
                break
            for name in files:
                with suppress(OSError):
                    child = Path(root, name).stat()
                    found.add((child.st_dev, child.st_ino))
    return found


def refuse_overlap(inputs: Iterable[Path], outputs: Iterable[tuple[str, Path]]) -> None:
    """Refuse, before anything is written, an output that is, or is inside, an input.

    ``outputs`` pairs an option name (``--json``) with its path. Symbolic links and hard links
    are seen through. Two outputs naming the same file are refused too.

    Raises:
        OutputOverlapError: naming the option, the output and the input it would destroy.
    """
    protected = [(path, _resolved(path)) for path in inputs]
    identities: dict[tuple[int, int], Path] = {}
    for shown, _real in protected:
        for identity in _identities(shown):
            identities.setdefault(identity, shown)
    seen: dict[Path, str] = {}
    for option, output in outputs:
        real = _resolved(output)
        for shown, real_input in protected:
            if real == real_input or real.is_relative_to(real_input):
                what = "is" if real == real_input else "is inside"
                raise OutputOverlapError(
                    f"the {option} output {what} the input {shown}; refusing to write over a "
                    "recording or config (nothing was written)",
                    path=str(output),
                )
        with suppress(OSError):
            info = output.stat()
            if not stat.S_ISCHR(info.st_mode) and (info.st_dev, info.st_ino) in identities:
                source = identities[(info.st_dev, info.st_ino)]
                raise OutputOverlapError(
                    f"the {option} output is the same file as the input {source}; refusing "
                    "to write over a recording or config (nothing was written)",
                    path=str(output),
                )
        if real in seen and not _is_special(output):
            raise OutputOverlapError(
                f"{option} and {seen[real]} name the same file; give each output its own path",
                path=str(output),
            )
        seen[real] = option
