"""Bounded decompression of MCAP and ROS 1 bag chunks: never more output than declared, plus 1 byte.

A chunk that expands past or short of its declared size, or fails its checksum, is damage.
"""

from __future__ import annotations

import bz2
import sys
from binascii import crc32
from typing import TYPE_CHECKING, Protocol

import lz4.frame  # type: ignore[import-untyped]

if sys.version_info >= (3, 14):
    from compression import zstd
else:  # the zstd binding rosbags itself depends on
    from backports import zstd

from medkit_replay.text import one_line

if TYPE_CHECKING:
    from collections.abc import Callable

MAX_RATIO = {"zstd": 32 * 1024, "lz4": 256, "bz2": 64 * 1024 * 1024}
"""Most output bytes one input byte can give: a zstd RLE block (4 bytes for 128 KiB), an LZ4
match-length byte (255 more bytes), bzip2's two run-length stages (tens of millions for a run
of one byte). A declared size beyond it cannot be honest."""
RATIO_SLACK = 128 * 1024
"""Output a few header bytes may give on their own (one zstd block, a short LZ4 frame)."""
STEP = 16 * 1024 * 1024
"""Output taken from the codec per call."""


class ChunkDamageError(Exception):
    """A chunk's compressed bytes do not give what its header declares."""


class _Streaming(Protocol):
    @property
    def eof(self) -> bool: ...

    @property
    def needs_input(self) -> bool: ...

    @property
    def unused_data(self) -> bytes: ...

    def decompress(self, data: bytes, /, max_length: int = -1) -> bytes: ...


_ERRORS: tuple[type[Exception], ...] = (
    zstd.ZstdError,
    RuntimeError,
    ValueError,
    EOFError,
    OSError,  # bz2: invalid data
)
_STREAMS: dict[str, Callable[[], _Streaming]] = {
    "zstd": zstd.ZstdDecompressor,
    "lz4": lz4.frame.LZ4FrameDecompressor,
    "bz2": bz2.BZ2Decompressor,
}


def decompress_chunk(data: bytes, compression: str, size: int, crc: int) -> bytes | bytearray:
    """The ``size`` bytes ``data`` decompresses to, checked against ``crc`` (0: no checksum).

    At most ``size + 1`` bytes are ever produced, whatever the frames claim.

    Raises:
        ChunkDamageError: unknown compression, an implausible size, more or fewer bytes than
            declared, a damaged frame, a checksum that does not match.
    """
    if not compression:
        if len(data) != size:
            raise ChunkDamageError(f"holds {len(data)} bytes but declares {size}")
        out: bytes | bytearray = data
    else:
        stream = _STREAMS.get(compression)
        if stream is None:
            raise ChunkDamageError(f"unsupported compression {compression!r}")
        if size > MAX_RATIO[compression] * len(data) + RATIO_SLACK:
            raise ChunkDamageError(
                f"declares {size} bytes uncompressed, more than {len(data)} {compression} "
                "bytes can give"
            )
        out = _frames(stream, data, size, compression)
    if crc and crc32(out) != crc:
        raise ChunkDamageError("fails its checksum")
    return out


def _frames(
    stream: Callable[[], _Streaming], data: bytes, size: int, compression: str
) -> bytearray:
    """Decompress concatenated frames, stopping one byte past ``size``.

    Output is taken in steps into one growing buffer: the peak is the output, not twice it.
    """
    out = bytearray()
    rest = data
    stalled = 0
    try:
        while rest:
            claimed = _claimed_size(compression, rest)
            if claimed is not None and claimed > size - len(out):
                raise ChunkDamageError(f"holds a frame of {claimed} bytes; declares {size} in all")
            decompressor = stream()
            while True:
                want = min(STEP, size + 1 - len(out))
                piece = decompressor.decompress(rest, max_length=want)
                rest = b""
                out += piece
                if len(out) > size:
                    raise ChunkDamageError(f"expands past its declared {size} bytes")
                if decompressor.eof:
                    break
                if decompressor.needs_input:
                    raise ChunkDamageError(f"{compression} data ends inside a frame")
                stalled = 0 if piece else stalled + 1
                if stalled > 2:
                    raise ChunkDamageError(f"{compression} data gives no output")
            rest = decompressor.unused_data
    except _ERRORS as exc:
        reason = one_line(exc, 200, or_name=True)
        raise ChunkDamageError(f"{compression} data is damaged ({reason})") from None
    if len(out) != size:
        raise ChunkDamageError(f"expands to {len(out)} bytes, not the declared {size}")
    return out


def _claimed_size(compression: str, frame: bytes) -> int | None:
    """The content size a frame's header states, if it states one: refused before decoding."""
    try:
        if compression == "zstd":
            return zstd.get_frame_info(frame).decompressed_size
        if compression == "bz2":
            return None  # a bzip2 stream does not state its size
        return int(lz4.frame.get_frame_info(frame)["content_size"]) or None  # 0: not stated
    except Exception:  # a damaged header: the decompressor says what is wrong
        return None
