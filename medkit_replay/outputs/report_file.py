"""The JSON report as a file: plain, or compressed by its suffix (``.gz``: gzip, ``.zst``: zstd).

Written atomically (outputs/atomic.py) and reproducibly: the gzip header holds no file name and
no time, and a zstd frame holds neither, so the same Result gives the same bytes.
"""

from __future__ import annotations

import gzip
import sys
from contextlib import contextmanager
from typing import IO, TYPE_CHECKING

from medkit_replay.files import report_compression
from medkit_replay.outputs.atomic import atomic_binary
from medkit_replay.outputs.json_report import write_json, write_json_bytes

if TYPE_CHECKING:
    from collections.abc import Iterator
    from pathlib import Path

    from medkit_replay.outputs.json_report import EncodedAhead
    from medkit_replay.result import Result

GZIP_LEVEL = 6
"""zlib's default: a mission's report in a few seconds at most; level 9 takes three times
longer for 3 % less."""
ZSTD_LEVEL = 3
"""zstd's default: faster than writing the plain report, and smaller than gzip -9."""


@contextmanager
def compressed(raw: IO[bytes], compression: str | None) -> Iterator[IO[bytes]]:
    """A binary stream over ``raw`` that compresses what is written (``None``: as it is)."""
    if compression is None:
        yield raw
    elif compression == "gzip":
        # No file name and mtime 0: the header is the same for every run.
        with gzip.GzipFile(
            filename="", mode="wb", fileobj=raw, compresslevel=GZIP_LEVEL, mtime=0
        ) as stream:
            yield stream  # type: ignore[misc]  # a GzipFile is a binary stream
    else:
        import zstandard  # noqa: PLC0415  # only for .zst

        compressor = zstandard.ZstdCompressor(level=ZSTD_LEVEL, write_checksum=True)
        with compressor.stream_writer(raw, closefd=False) as stream:
            yield stream


def write_report(result: Result, target: Path, ahead: EncodedAhead | None = None) -> None:
    """Write the report to ``target`` (compressed when its suffix says so), atomically;
    ``ahead`` may hold batches of its long lists already encoded."""
    with atomic_binary(target) as raw, compressed(raw, report_compression(target)) as stream:
        write_json_bytes(result, stream, ahead)


def write_report_stdout(result: Result, ahead: EncodedAhead | None = None) -> None:
    """Write the report (plain) to standard output."""
    out = sys.stdout
    binary = getattr(out, "buffer", None)
    if binary is None:  # a text-only stream (a test's StringIO)
        write_json(result, out)
        return
    out.flush()
    write_json_bytes(result, binary, ahead)
    binary.flush()
