"""Reads a JSON report from a file, strictly and within bounds, for a diff to compare.

The only diffing module that touches a file: one refusal, one line, naming the file.
"""

from __future__ import annotations

import gzip
import json
import os
import re
import sys
import zlib
from typing import IO, TYPE_CHECKING

from medkit_replay.errors import InputError
from medkit_replay.files import (
    FileRefusedError,
    max_report_bytes,
    open_regular,
    report_limit_text,
)
from medkit_replay.jsonio import JsonRefusedError, loads_strict, locate_refusal
from medkit_replay.text import one_line

if TYPE_CHECKING:
    from collections.abc import Iterator
    from pathlib import Path


def read_report(path: Path, limit: int | None = None) -> dict[str, object]:
    """A JSON report from a file (checked by the diff, which names the file when it is not one).

    Strict and bounded: a regular file of at most ``limit`` bytes (default: files.py's
    max_report_bytes), plain or once decompressed, UTF-8, strict JSON (no NaN or Infinity, no
    number too long, no lone surrogate); each refusal is one line.
    """
    shown = str(path)
    data = report_bytes(path, report_size_limit(limit))
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise InputError(
            f"not a JSON report (not UTF-8 text at byte {err.start:,})",
            path=shown,
            line=data.count(b"\n", 0, err.start) + 1,
        ) from None
    except MemoryError:
        raise InputError(_TOO_BIG.format(len(data)), path=shown) from None
    del data
    try:
        report = loads_strict(text)
    except json.JSONDecodeError as err:
        raise InputError(f"not valid JSON: {err.msg}", path=shown, line=err.lineno) from None
    except JsonRefusedError as err:
        where, problem = locate_refusal(text, sys.get_int_max_str_digits())
        raise InputError(f"not valid JSON: {problem or err}", path=shown, line=where) from None
    except MemoryError:
        raise InputError(_TOO_BIG.format(len(text)), path=shown) from None
    if not isinstance(report, dict):
        raise InputError("not a medkit-replay report (not a JSON object)", path=shown)
    if _MAYBE_SURROGATE.search(text) is not None:
        where, problem = locate_refusal(text, sys.get_int_max_str_digits())
        if problem is not None:
            raise InputError(f"not valid text: {problem}", path=shown, line=where)
    return report


def report_size_limit(limit: int | None = None) -> int:
    """``limit``, or the default limit (MEDKIT_REPLAY_MAX_REPORT_MB, else MAX_REPORT_MB);
    a bad variable is an input error."""
    if limit is not None:
        return limit
    try:
        return max_report_bytes()
    except ValueError as err:
        raise InputError(str(err)) from None


_TOO_BIG = "a report of {:,} bytes is too large to load in the memory available"
_MAYBE_SURROGATE = re.compile(r"\\u[dD][89a-fA-F]")


def report_bytes(path: Path, limit: int) -> bytes | bytearray:
    """The report file's text as bytes, decompressed if it is gzip or zstd (by its first bytes):
    a regular file of at most ``limit`` bytes, refused at once when it cannot be a report (it
    does not start with '{'), so a huge or endless file is never read whole. Decompressed, it
    gets the same bound, checked as it expands: a decompression bomb is refused, never held."""
    try:
        with open_regular(path) as stream:
            magic = stream.read(len(_ZSTD_MAGIC))
            stream.seek(0)
            if magic.startswith(_GZIP_MAGIC) or magic == _ZSTD_MAGIC:
                compression = "gzip" if magic.startswith(_GZIP_MAGIC) else "zstd"
                # Read twice: first counting, holding nothing, so that a bomb costs the time
                # to expand ``limit`` bytes and no memory; then kept (checked again: the file
                # may have changed in between).
                _expand(stream, path, compression, limit, None)
                stream.seek(0)
                data = bytearray()  # no second copy of a large report
                _expand(stream, path, compression, limit, data)
                return data
            size = os.fstat(stream.fileno()).st_size
            if size > limit:
                raise InputError(
                    f"a report of {size:,} bytes is larger than {report_limit_text(limit)}",
                    path=str(path),
                )
            head = stream.read(_HEAD_BYTES)
            if head.lstrip(_BLANK)[:1] not in (b"{", b""):
                raise InputError(
                    "not a JSON report (it does not start with '{')", path=str(path), line=1
                )
            try:
                # read(n) allocates n bytes first: ask for what the file holds, plus one byte
                # to notice a file that grew past the bound.
                wanted = min(size, limit) + 1 - len(head)
                data_read = head + stream.read(max(wanted, 1))
            except MemoryError:
                raise InputError(_TOO_BIG.format(size), path=str(path)) from None
            if len(data_read) > limit:  # it grew while being read
                raise InputError(f"a report larger than {report_limit_text(limit)}", path=str(path))
            return data_read
    except FileNotFoundError:
        raise InputError("no such report", path=str(path)) from None
    except IsADirectoryError:
        raise InputError("is a directory, not a JSON report", path=str(path)) from None
    except FileRefusedError as err:
        raise InputError(f"cannot read report: {err}", path=str(path)) from None
    except OSError as err:
        raise InputError(f"cannot read report: {err.strerror}", path=str(path)) from None


_HEAD_BYTES = 64 * 1024
_BLANK = b" \t\r\n"
_GZIP_MAGIC = b"\x1f\x8b"
_ZSTD_MAGIC = b"\x28\xb5\x2f\xfd"
_PIECE = 1024 * 1024
# Compressed bytes fed to zstd at a time: one feed expands to at most 8 MiB (RLE blocks).
_ZSTD_FEED = 256
MAX_EXPANSION = 1000
"""How many times its compressed size a report may expand to once past EXPANSION_FLOOR bytes.
Real reports compress 66x (gzip) to 140x (zstd, 200,000 reports of one flapping code); a bomb
thousands of times. The counting read already makes a bomb cost no memory: this makes it cost
no time either. A report past it can still be read once decompressed by hand (``zstd -d``)."""
EXPANSION_FLOOR = 64 * 1024 * 1024
"""Below this many bytes of text no ratio is checked (a small report of repeated texts)."""


def _pieces(stream: IO[bytes], compression: str) -> Iterator[bytes]:
    """The decompressed text a piece at a time, over every gzip member or zstd frame (as
    ``gzip -d`` and ``zstd -d`` read what ``cat`` or ``pzstd`` made); damage raises."""
    if compression == "gzip":
        reader = gzip.GzipFile(fileobj=stream, mode="rb")  # a cut stream ends in EOFError
        while piece := reader.read(_PIECE):
            yield piece
        return
    import zstandard  # noqa: PLC0415  # only for zstd reports

    decompressor = zstandard.ZstdDecompressor().decompressobj()
    while fed := stream.read(_ZSTD_FEED):
        while fed:
            if decompressor.eof:  # the next frame starts here (or a skippable one)
                decompressor = zstandard.ZstdDecompressor().decompressobj()
            yield decompressor.decompress(fed)
            fed = decompressor.unused_data if decompressor.eof else b""
    if not decompressor.eof:
        raise EOFError("the zstd frame is cut short")


def _expand(
    stream: IO[bytes], path: Path, compression: str, limit: int, keep: bytearray | None
) -> None:
    """Decompress the report a piece at a time (into ``keep`` when given), refused as soon as
    it passes ``limit`` bytes or shows it is no report."""
    # gzip.BadGzipFile is an OSError; a cut stream ends in EOFError.
    failures: tuple[type[BaseException], ...] = (OSError, EOFError, zlib.error)
    if compression == "zstd":
        import zstandard  # noqa: PLC0415  # only for zstd reports

        failures = (*failures, zstandard.ZstdError)
    total = 0
    started = False
    packed = os.fstat(stream.fileno()).st_size
    ceiling = min(limit, max(EXPANSION_FLOOR, MAX_EXPANSION * packed))
    try:
        for piece in _pieces(stream, compression):
            if not started and (text := piece.lstrip(_BLANK)):
                if text[:1] != b"{":
                    raise InputError(
                        f"not a JSON report (its {compression} content does not start with '{{')",
                        path=str(path),
                        line=1,
                    )
                started = True
            total += len(piece)
            if total > ceiling:
                raise InputError(
                    f"a {compression} report that expands past {report_limit_text(limit)}"
                    if total > limit
                    else f"a {compression} report of {packed:,} bytes that expands more than "
                    f"{MAX_EXPANSION:,} times its size (no real report does: a decompression "
                    "bomb)",
                    path=str(path),
                )
            if keep is not None:
                keep += piece
    except failures as err:
        raise InputError(
            f"cannot decompress the {compression} report: {_why(err)}", path=str(path)
        ) from None
    except MemoryError:
        raise InputError(_TOO_BIG.format(total), path=str(path)) from None


def _why(err: BaseException) -> str:
    return one_line(err, or_name=True)
