"""Opening the files a user names: regular files only, and never more bytes than a bound.

Configs, budgets, reports, metadata, scripts and recordings are opened here, so that a FIFO,
a device or /dev/zero is refused at once instead of blocking or being read forever.
"""

from __future__ import annotations

import errno
import os
import re
import stat
from pathlib import Path
from typing import IO

_REMOTE = re.compile(r"(?i)(s3|gs|https?)://")


def is_remote(text: str | os.PathLike[str]) -> bool:
    """Whether an input names a remote object: ``s3://``, ``gs://``, ``http(s)://`` (a URL is
    kept as a string; a Path would fold its ``//``)."""
    return isinstance(text, str) and _REMOTE.match(text) is not None


# A parameter file, correlation file, budget or metadata.yaml is a few KB. Anything past this
# is not what the user meant to give.
MIB = 1024 * 1024
MAX_TEXT_FILE_BYTES = 64 * MIB
MAX_REPORT_MB = 1024
"""The largest JSON report read back (``diff``, golden reports), in MiB of text: plain, or once
decompressed. The report grows with the recording (about 80 MB for the 10-minute sample mission,
591 MB for the one-hour one), so this holds some 100 minutes of a dense mission; ``diff
--max-report-mb`` (or MEDKIT_REPLAY_MAX_REPORT_MB) and pytest's ``--golden-max-report-mb``
raise it."""
MAX_REPORT_ENV = "MEDKIT_REPLAY_MAX_REPORT_MB"

_KINDS = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


class FileRefusedError(OSError):
    """A path that exists but is not a regular file, or holds more than the bound allows."""

    def __init__(self, reason: str) -> None:
        super().__init__(errno.EINVAL, reason)

    def __str__(self) -> str:
        return str(self.strerror)


def kind_of(mode: int) -> str:
    """What a non-regular file is, in words."""
    for test, name in _KINDS:
        if test(mode):
            return name
    return "not a regular file"


def open_regular(path: Path | str) -> IO[bytes]:
    """Open a regular file for reading, without blocking on a FIFO or following it forever.

    Raises:
        FileNotFoundError, PermissionError, OSError: as ``open`` would.
        FileRefusedError: the path is a FIFO, device, socket or directory.
    """
    # O_NONBLOCK makes opening a FIFO return at once (it has no effect on regular files);
    # the check then runs on the descriptor itself, so nothing can be swapped in between.
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            raise FileRefusedError(f"{kind_of(mode)}, not a regular file")
        os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def check_regular(path: Path | str) -> None:
    """Refuse a path that is not a regular file (for readers that open by name, like sqlite).

    Raises:
        FileNotFoundError, OSError: the path cannot be looked up.
        FileRefusedError: the path is a FIFO, device, socket or directory.
    """
    mode = Path(path).stat().st_mode
    if not stat.S_ISREG(mode):
        raise FileRefusedError(f"{kind_of(mode)}, not a regular file")


def read_limited(path: Path | str, limit: int = MAX_TEXT_FILE_BYTES) -> bytes:
    """The whole content of a regular file of at most ``limit`` bytes.

    Raises:
        FileNotFoundError, PermissionError, OSError: as ``open`` would.
        FileRefusedError: not a regular file, or larger than ``limit``.
    """
    with open_regular(path) as stream:
        # Ask for what the file holds (plus one byte, to see it grow past the limit): read(n)
        # reserves n bytes up front, and a config is a few KB, not the 64 MiB bound.
        size = os.fstat(stream.fileno()).st_size
        data = stream.read(min(size, limit) + 1)
        if len(data) <= limit and len(data) > size:  # grew while read: take the rest, bounded
            data += stream.read(limit + 1 - len(data))
    if len(data) > limit:
        raise FileRefusedError(f"larger than {limit:,} bytes, too large for this kind of file")
    return data


def read_limited_text(path: Path | str, limit: int = MAX_TEXT_FILE_BYTES) -> str:
    """``read_limited`` decoded as UTF-8 (UnicodeDecodeError when it is not)."""
    return read_limited(path, limit).decode("utf-8")


def max_report_bytes() -> int:
    """The report size limit in bytes: MEDKIT_REPLAY_MAX_REPORT_MB MiB when set, else
    MAX_REPORT_MB.

    Raises:
        ValueError: the variable is not a whole number of MiB, at least 1 (said in one line).
    """
    text = os.environ.get(MAX_REPORT_ENV, "").strip()
    if not text:
        return MAX_REPORT_MB * MIB
    if not text.isdigit() or int(text) < 1:
        raise ValueError(f"{MAX_REPORT_ENV}={text[:40]!r} is not a whole number of MiB, 1 or more")
    return int(text) * MIB


def report_limit_text(limit: int) -> str:
    """A report size limit as the user sets it (MiB), with how to raise it."""
    return f"{limit / MIB:,.0f} MiB (raise it with --max-report-mb or {MAX_REPORT_ENV})"


REPORT_COMPRESSIONS = {".gz": "gzip", ".zst": "zstd"}
"""A JSON report's file-name suffix and the compression it stands for."""


def report_compression(path: Path | str) -> str | None:
    """How a report file is compressed, by its name: ``gzip``, ``zstd`` or None (plain)."""
    return REPORT_COMPRESSIONS.get(Path(path).suffix.lower())
