"""rosbag2 inputs: a bag directory (metadata.yaml, split files, compression) or one bare file.

Chains an input's storage files, restores time order, selects topics and decodes them; never writes.
"""

from __future__ import annotations

import os
import re
import stat
import sys
from dataclasses import replace
from pathlib import Path, PurePath
from tempfile import TemporaryDirectory
from typing import TYPE_CHECKING

from medkit_replay.errors import InputError
from medkit_replay.files import open_regular
from medkit_replay.inputs.mcap.reader import McapFile
from medkit_replay.inputs.mcap.records import MAGIC as MCAP_MAGIC
from medkit_replay.inputs.merge import Timed, reorder_batches
from medkit_replay.inputs.metadata import Metadata, read_metadata
from medkit_replay.inputs.skipped import report_skipped
from medkit_replay.inputs.source import Message
from medkit_replay.inputs.sqlite.db3 import SQLITE_MAGIC, Db3File
from medkit_replay.inputs.storage import RECORD_SIZE_LIMIT, TEMP_MARGIN, NotABagError, temp_room
from medkit_replay.inputs.typestore import DecodeError, Decoder, make_decoder, other_release
from medkit_replay.model import InputSummary, Loss, TopicSummary
from medkit_replay.msgdefs import DefinitionError
from medkit_replay.releases import default_release
from medkit_replay.text import one_line

if sys.version_info >= (3, 14):
    from compression import zstd
else:  # the zstd binding rosbags itself depends on
    from backports import zstd

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator

    from medkit_replay.inputs.merge import Bound
    from medkit_replay.inputs.selection import Role
    from medkit_replay.inputs.source import InputContext, Warn
    from medkit_replay.inputs.storage import Connection, Raw, StorageFile

STORAGE_FILES: dict[str, Callable[[Path, int, Warn], StorageFile]] = {
    ".mcap": McapFile,
    ".db3": Db3File,
}
"""Storage file readers by suffix (after a ``.zstd`` file-compression suffix is removed)."""

ZSTD_MAGIC = b"\x28\xb5\x2f\xfd"  # a CDR payload starts with 00 0x instead, so this cannot clash
MAX_HELD = 100_000
"""Most messages held to restore time order; beyond it the oldest leaves, later ones may be late."""


def _natural_key(path: Path) -> list[int | str]:
    return [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", path.name)]


def _storage_files(directory: Path) -> list[Path]:
    found = [
        p
        for p in directory.iterdir()
        if p.is_file() and PurePath(p.name.removesuffix(".zstd")).suffix in STORAGE_FILES
    ]
    return sorted(found, key=_natural_key)


def open_directory(path: Path, ctx: InputContext) -> Rosbag2Input:
    """Open a rosbag2 directory; without a usable metadata.yaml, read the storage files in it.

    Raises:
        InputError: no storage file in it can be read at all.
    """
    return open_folder(path, ctx, read_metadata(path, ctx.warn), _storage_files(path), Path.exists)


def open_folder(
    path: Path,
    ctx: InputContext,
    meta: Metadata | None,
    found: list[Path],
    exists: Callable[[Path], bool],
    bag: Callable[[Path, InputContext, list[Path], Metadata], Rosbag2Input] | None = None,
) -> Rosbag2Input:
    """Open a bag folder from its metadata and listing: local, or a remote prefix's.

    Args:
        meta: its metadata.yaml (None: missing or unusable).
        found: its storage files in name order.
        exists: whether a file named in the metadata is there.
        bag: builds the input (default :class:`Rosbag2Input`).

    Raises:
        InputError: no storage file in it can be read at all.
    """
    build = bag if bag is not None else Rosbag2Input
    if meta is None:
        if not found:
            raise InputError("no metadata.yaml and no .mcap or .db3 file in it", path=str(path))
        names = ", ".join(p.name for p in found)
        ctx.warn(
            f"{path}: no usable metadata.yaml; reading the storage files in name order: {names}"
        )
        return build(path, ctx, found, Metadata())
    listed = [path / name for name in meta.files]
    present = {p: exists(p) for p in listed}
    for missing in (p for p in listed if not present[p]):
        ctx.warn(
            f"{missing}: listed in metadata.yaml but missing", meta.listed.get(missing.name, Loss())
        )
    unlisted = [p for p in found if p not in listed]
    if unlisted:
        names = ", ".join(p.name for p in unlisted)
        ctx.warn(f"{path}: {names} not listed in metadata.yaml; read after the listed files")
    files = [p for p in listed if present[p]] + unlisted
    if not files:
        raise InputError("metadata.yaml lists no storage file that exists", path=str(path))
    return build(path, ctx, files, meta)


def open_file(path: Path, ctx: InputContext) -> Rosbag2Input:
    """Open one bare ``.mcap`` or ``.db3`` file (no metadata.yaml), e.g. a medkit download.

    Raises:
        InputError: the file is not a readable bag.
    """
    return Rosbag2Input(path, ctx, [path], Metadata())


class Rosbag2Input:
    """The storage files of one input chained into one stream sorted by (log time, position)."""

    def __init__(self, path: Path, ctx: InputContext, paths: list[Path], meta: Metadata) -> None:
        self.path = path
        self.ctx = ctx
        self._meta = meta
        self._warned: set[str] = set()
        self._temp: TemporaryDirectory[str] | None = None
        self._files: list[StorageFile] = []
        self._readers: dict[tuple[int, int], tuple[Role, Decoder]] = {}
        self._by_connection: dict[int, tuple[Role, Decoder]] = {}
        self._connections: list[Connection] = []
        self._failures: dict[str, tuple[int, int, int, str]] = {}
        self._late: tuple[int, int] = (0, 0)  # how many, first time
        self._used = False
        self._message_zstd = meta.compression_mode == "message"
        if meta.compression_mode and meta.compression_format != "zstd":
            self._warn(f"compression {meta.compression_format!r} is not supported")
        problems = []
        try:
            for file_no, file_path in enumerate(paths):
                try:
                    self._files.append(self._open_file(file_path, file_no))
                except NotABagError as exc:
                    problems.append(str(exc) if file_path == path else f"{file_path.name}: {exc}")
                    if len(paths) > 1:
                        self.ctx.warn(f"{file_path}: {exc}", self._file_loss(file_path))
        except BaseException:
            self.close()
            raise
        if not self._files and paths:  # no paths: a followed input, its files yet to come
            self.close()
            if paths == [path]:
                raise InputError(one_line(problems[0]), path=str(path))
            detail = one_line("; ".join(problems))
            raise InputError(f"nothing readable ({detail})", path=str(path))
        self.storage = meta.storage or (self._files[0].storage if self._files else "")
        # No bound of file k may pass the start of a later file: split files can overlap a little.
        starts = [meta.starts.get(f.path.name, f.start_ns) for f in self._files]
        self._caps = [
            min((s for s in starts[k + 1 :] if s is not None), default=None)
            for k in range(len(starts))
        ]

    def _file_loss(self, path: Path) -> Loss:
        """What skipping a whole storage file costs: its bytes, and what metadata.yaml says."""
        listed = self._meta.listed.get(path.name, Loss())
        try:
            info = path.stat()
        except OSError:
            return listed
        # A FIFO or device has no size that says what it held.
        return replace(listed, bytes=info.st_size) if stat.S_ISREG(info.st_mode) else listed

    def _open_file(self, path: Path, file_no: int) -> StorageFile:
        name = path.name
        if name.endswith(".zstd"):
            path = self._decompress(path)
            name = name.removesuffix(".zstd")
        opener = STORAGE_FILES.get(PurePath(name).suffix)
        if opener is None:
            opener = McapFile if self._meta.storage == "mcap" else Db3File
        opened = opener(path, file_no, self.ctx.warn)
        if isinstance(opened, McapFile):
            opened.indexed = self.ctx.use_index
        return opened

    def _decompress(self, path: Path) -> Path:
        """Stream a file-compressed storage file into a temporary directory (kept until close).

        Writes as it decompresses, so a file cut short still yields everything before the cut.
        The first bytes must be the storage's magic, and the output may not pass
        :func:`_decompressed_limit`; past it, the rest is not read (with a warning).
        """
        if self._temp is None:
            self._temp = TemporaryDirectory(prefix="medkit-replay-")
        target = Path(self._temp.name, path.name.removesuffix(".zstd"))
        magics = self._magics(target.name)
        decompressor = zstd.ZstdDecompressor()
        written = 0
        try:
            with open_regular(path) as source, target.open("wb") as sink:
                limit = _decompressed_limit(os.fstat(source.fileno()).st_size)
                head = b""
                while not decompressor.eof:
                    block = source.read(1 << 20) if decompressor.needs_input else b""
                    if decompressor.needs_input and not block:
                        raise EOFError("compressed file ends before its end-of-stream marker")
                    out = decompressor.decompress(block, max_length=1 << 20)
                    if len(head) < _MAGIC_BYTES:
                        head += out[: _MAGIC_BYTES - len(head)]
                        if not any(m.startswith(head[: len(m)]) for m in magics):
                            raise NotABagError(f"decompressed data is not {_kind(magics)}")
                    if written + len(out) > limit:
                        sink.write(out[: limit - written])
                        self.ctx.warn(
                            f"{path}: decompresses to more than {limit:,} bytes "
                            f"({_LIMIT_RULE}); only the first {limit:,} are read",
                            Loss(),
                        )
                        break
                    sink.write(out)
                    written += len(out)
            if decompressor.eof and len(head) < _MAGIC_BYTES:
                raise NotABagError(f"decompressed data is not {_kind(magics)}")
        except NotABagError:
            target.unlink(missing_ok=True)
            raise
        except (OSError, EOFError, zstd.ZstdError) as exc:
            if not written:
                target.unlink(missing_ok=True)
                raise NotABagError(f"cannot be decompressed ({one_line(exc)})") from None
            self.ctx.warn(
                f"{path}: compressed data is damaged ({one_line(exc)}); read the rest", Loss()
            )
        return target

    def _magics(self, name: str) -> tuple[bytes, ...]:
        """The magic numbers a decompressed storage file called ``name`` may start with."""
        suffix = PurePath(name).suffix
        storage = {".mcap": "mcap", ".db3": "sqlite3"}.get(suffix, self._meta.storage)
        if storage in _MAGICS:
            return (_MAGICS[storage],)
        return tuple(_MAGICS.values())

    def _warn(self, text: str, loss: Loss | None = None, /) -> None:
        text = f"{self.path}: {text}"
        if text not in self._warned:
            self._warned.add(text)
            self.ctx.warn(text, loss)

    def _accepts(self, file_no: int) -> Callable[[Connection], bool]:
        def accept(connection: Connection) -> bool:
            topic, msgtype = connection.topic, connection.msgtype
            role, reason = self.ctx.selection.classify(topic, msgtype)
            if role is None:
                if reason:
                    self._warn(reason)
                return False
            if connection.serialization != "cdr":
                fmt = connection.serialization
                self._warn(f"topic {topic} is serialized as {fmt!r}, not CDR; not read")
                return False
            release = self.ctx.release or default_release()
            try:
                decoder, problem = make_decoder(
                    msgtype,
                    connection.definition,
                    lambda note: self._warn(f"{topic}: {note}"),
                    release.msg_definitions,
                )
            except DefinitionError as exc:
                self._warn(f"topic {topic} cannot be decoded: {exc}; not read")
                return False
            if problem:
                self._warn(f"{topic}: recorded definition unusable ({problem}); using the bundled")
            elif role == "fault_events":
                mismatch = other_release(connection.definition, release)
                if mismatch:
                    self._warn(f"{topic}: {mismatch}")
            self._readers[(file_no, connection.id)] = (role, decoder)
            # The storage file hands this very object back with each of its messages.
            self._by_connection[id(connection)] = (role, decoder)
            self._connections.append(connection)  # keeps every id above unique
            return True

        return accept

    def _raw(self) -> Iterator[Bound | Timed[Raw] | list[Timed[Raw]]]:
        for file_no, file in enumerate(self._files):
            try:
                yield from file.read(self._accepts(file_no), self._caps[file_no])
            except Exception as exc:  # last resort: no reader failure may end the replay
                self.ctx.warn(f"{file.path}: reading stopped ({type(exc).__name__}: {exc})", Loss())

    def messages(self) -> Iterator[Timed[Message]]:
        """Yield the selected, decoded messages once, sorted by (log time, position)."""
        return self._stream(timed=True)  # type: ignore[return-value]  # Timed items

    def plain_messages(self) -> Iterator[Message]:
        """:meth:`messages` without their positions (a recording of one input needs none)."""
        return self._stream(timed=False)  # type: ignore[return-value]  # Message items

    def message_tuples(self) -> Iterator[tuple[int, int, str, str, Role, object]]:
        """:meth:`plain_messages` as plain tuples laid out as Message (cheaper to build)."""
        return self._stream(timed=False, plain=True)  # type: ignore[return-value]  # tuples

    def _stream(
        self, *, timed: bool, plain: bool = False
    ) -> Iterator[Timed[Message] | Message | tuple[int, int, str, str, Role, object]]:
        if self._used:
            raise RuntimeError(f"{self.path}: messages() can be read only once")
        self._used = True
        readers, input_index, every_zstd = (
            self._by_connection,
            self.ctx.input_index,
            self._message_zstd,
        )
        try:
            for batch in reorder_batches(self._raw(), self._on_late, MAX_HELD):
                for t_ns, position, raw in batch:
                    connection = raw.connection
                    role, decoder = readers[id(connection)]
                    data = raw.data
                    try:
                        if every_zstd or data[:4] == ZSTD_MAGIC:
                            data = _unzstd(data)
                        msg = decoder.decode(data)
                    except (DecodeError, ValueError, zstd.ZstdError) as exc:
                        self._failed(connection.topic, t_ns, exc)
                        continue
                    topic, msgtype = connection.topic, connection.msgtype
                    if plain:
                        yield (t_ns, input_index, topic, msgtype, role, msg)
                    elif timed:
                        yield Timed(
                            t_ns, position, Message(t_ns, input_index, topic, msgtype, role, msg)
                        )
                    else:
                        yield Message(t_ns, input_index, topic, msgtype, role, msg)
        finally:
            self._report_losses()

    def _on_late(self, item: Timed[Raw]) -> None:
        count, first = self._late
        self._late = (count + 1, first if count else item.t_ns)

    def _failed(self, topic: str, t_ns: int, exc: Exception) -> None:
        count, first, _, reason = self._failures.get(topic, (0, t_ns, t_ns, one_line(exc)))
        self._failures[topic] = (count + 1, first, t_ns, reason)

    def _report_losses(self) -> None:
        report_skipped(self._warn, self._failures, self._late)

    def summary(self) -> InputSummary:
        """Topics (all of them, with role where read), counts and time span of this input."""
        counts: dict[tuple[str, str], int] = {}
        roles: dict[tuple[str, str], Role] = {}
        for file_no, file in enumerate(self._files):
            for cid, connection in file.connections.items():
                key = (connection.topic, connection.msgtype)
                counts[key] = counts.get(key, 0) + file.counts.get(cid, 0)
                if (file_no, cid) in self._readers:
                    roles[key] = self._readers[(file_no, cid)][0]
        starts = [f.start_ns for f in self._files if f.start_ns is not None]
        ends = [f.end_ns for f in self._files if f.end_ns is not None]
        return InputSummary(
            path=str(self.path),
            storage=self.storage,
            start_ns=min(starts, default=None),
            end_ns=max(ends, default=None),
            message_count=sum(sum(f.counts.values()) for f in self._files),
            topics=tuple(
                TopicSummary(topic=topic, type=msgtype, role=roles.get(key), messages=count)
                for key, count in sorted(counts.items())
                for topic, msgtype in (key,)
            ),
        )

    def close(self) -> None:
        """Delete temporary copies; safe to call twice."""
        for file in self._files:
            file.close()
        if self._temp is not None:
            self._temp.cleanup()
            self._temp = None


_MAGICS = {"mcap": MCAP_MAGIC, "sqlite3": SQLITE_MAGIC}
_MAGIC_BYTES = max(len(m) for m in _MAGICS.values())
MAX_EXPANSION = 1000
"""Largest ratio of a file-compressed storage file's decompressed size to its own.

rosbag2's zstd leaves recorded traffic (timestamps, headers, sensor noise) well below 100:1;
only a file of nothing but blank frames could pass this, and then its start is still read.
"""
MIN_DECOMPRESSED_ALLOWANCE = 64 * 1024 * 1024
"""Output always allowed to a small compressed file, whatever its ratio."""
_LIMIT_RULE = (
    f"at most {MAX_EXPANSION}x its compressed size, and the temporary folder's free space "
    f"less {TEMP_MARGIN // (1024 * 1024)} MiB"
)


def _decompressed_limit(compressed: int) -> int:
    """Bytes a compressed storage file may decompress to in the temporary folder."""
    return min(temp_room(), max(MIN_DECOMPRESSED_ALLOWANCE, compressed * MAX_EXPANSION))


def _kind(magics: tuple[bytes, ...]) -> str:
    names = {MCAP_MAGIC: "an MCAP file", SQLITE_MAGIC: "an SQLite database"}
    return " or ".join(names[m] for m in magics)


def _unzstd(data: bytes | memoryview) -> bytes:
    """Undo rosbag2's per-message compression, allocating at most RECORD_SIZE_LIMIT bytes."""
    decompressor = zstd.ZstdDecompressor()
    out = decompressor.decompress(bytes(data), max_length=RECORD_SIZE_LIMIT)
    if not decompressor.eof:
        raise ValueError("compressed payload is cut off or larger than the size limit")
    return out
