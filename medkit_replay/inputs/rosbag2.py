"""rosbag2 inputs: a bag directory (metadata.yaml, split files, compression) or one bare file.

Chains an input's storage files, restores time order, selects topics and decodes them; never writes.
"""

from __future__ import annotations

import os
import posixpath
import re
import stat
import sys
from dataclasses import dataclass, field, replace
from pathlib import Path, PurePath, PurePosixPath
from tempfile import TemporaryDirectory
from typing import TYPE_CHECKING

import yaml

from medkit_replay.errors import InputError
from medkit_replay.files import open_regular, read_limited_text
from medkit_replay.inputs.mcap.reader import MAGIC as MCAP_MAGIC, McapFile
from medkit_replay.inputs.merge import Timed, reorder_batches
from medkit_replay.inputs.skipped import report_skipped
from medkit_replay.inputs.source import Message
from medkit_replay.inputs.sqlite.db3 import SQLITE_MAGIC, Db3File
from medkit_replay.inputs.storage import RECORD_SIZE_LIMIT, TEMP_MARGIN, NotABagError, temp_room
from medkit_replay.inputs.typestore import DecodeError, Decoder, make_decoder, other_release
from medkit_replay.model import InputSummary, Loss, TopicSummary
from medkit_replay.msgdefs import DefinitionError
from medkit_replay.releases import default_release
from medkit_replay.yaml_bounds import YamlBoundsError, compose_bounded

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

_FAST_LOADER: type[yaml.SafeLoader] = getattr(yaml, "CSafeLoader", yaml.SafeLoader)

ZSTD_MAGIC = b"\x28\xb5\x2f\xfd"  # a CDR payload starts with 00 0x instead, so this cannot clash
MAX_HELD = 100_000
"""Most messages held to restore time order; beyond it the oldest leaves, later ones may be late."""


@dataclass(slots=True)
class _Metadata:
    """What the replay uses of metadata.yaml (rosbag2 versions 1 to 9)."""

    storage: str | None = None
    files: list[str] = field(default_factory=list)
    starts: dict[str, int] = field(default_factory=dict)
    listed: dict[str, Loss] = field(default_factory=dict)
    """What losing each file costs, as its ``files`` entry says (messages, span)."""
    compression_format: str = ""
    compression_mode: str = ""


def _one_line(exc: BaseException | str) -> str:
    return " ".join(str(exc).split())


def _load_metadata(path: Path) -> tuple[object, yaml.Node | None]:
    """The document in metadata.yaml and its YAML nodes (for lines): a regular file, bounded in
    size and in YAML nodes.

    Raises:
        OSError, UnicodeDecodeError, yaml.YAMLError, YamlBoundsError, ValueError.
    """
    text = read_limited_text(path)
    try:  # libyaml's parser when present: the same documents, several times faster
        return _bounded_load(text, _FAST_LOADER)
    except yaml.YAMLError:
        return _bounded_load(text, yaml.SafeLoader)  # says what is wrong as it does


def _bounded_load(
    text: str, loader_class: type[yaml.SafeLoader]
) -> tuple[object, yaml.Node | None]:
    loader = loader_class(text)
    try:
        root = compose_bounded(loader.get_single_node)
        return (None if root is None else loader.construct_document(root)), root
    finally:
        loader.dispose()


def _entry_lines(root: yaml.Node | None, key: str, count: int) -> list[int | None]:
    """The line of each of the ``count`` entries of ``rosbag2_bagfile_information.<key>``
    (None each when the nodes do not match the document, as after a merge key)."""
    node = _child(_child(root, "rosbag2_bagfile_information"), key)
    if isinstance(node, yaml.SequenceNode) and len(node.value) == count:
        return [item.start_mark.line + 1 for item in node.value]
    return [None] * count


def _child(node: yaml.Node | None, key: str) -> yaml.Node | None:
    """The value node of ``key`` in a mapping node (the last one, as the document keeps)."""
    found = None
    if isinstance(node, yaml.MappingNode):
        for name, value in node.value:
            if isinstance(name, yaml.ScalarNode) and name.value == key:
                found = value
    return found


def _brief(value: object) -> str:
    """A listed value shown in a warning, short whatever it holds."""
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 64:
        return "a number past int64"
    if value is None or isinstance(value, bool | int | float):
        return repr(value)
    if isinstance(value, str):
        return repr(value[:60])
    if isinstance(value, dict) and "nanoseconds_since_epoch" in value:
        return f"{{nanoseconds_since_epoch: {_brief(value['nanoseconds_since_epoch'])}}}"
    return "a list" if isinstance(value, list) else "a mapping"


def _unusable(
    path: Path,
    key: str,
    lines: list[int | None],
    bad: list[tuple[int, str]],
    what: str,
    outcome: str = "ignored",
) -> str:
    """One warning for the unusable entries ``bad`` (index, shown) of a list in metadata.yaml,
    at the first one's line."""
    first = lines[bad[0][0]]
    where = f"{path}:{first}" if first is not None else str(path)
    shown = ", ".join(text for _, text in bad[:3]) + (", ..." if len(bad) > 3 else "")
    count = f"{len(bad)} entr{'y' if len(bad) == 1 else 'ies'}"
    return f"{where}: {key}: {count} {what} ({shown}); {outcome}"


def _read_metadata(directory: Path, warn: Callable[[str], None]) -> _Metadata | None:
    """Parse metadata.yaml leniently; None (with a warning) when it is missing or unusable."""
    path = directory / "metadata.yaml"
    if not path.exists():
        return None
    try:
        document, root = _load_metadata(path)
    except (OSError, UnicodeDecodeError, yaml.YAMLError, ValueError) as exc:
        # ValueError: an integer of thousands of digits, refused by Python's int().
        warn(f"{path}: cannot be read ({_one_line(exc)})")
        return None
    except YamlBoundsError as exc:
        warn(f"{path}: cannot be read ({exc.message})")
        return None
    info = document.get("rosbag2_bagfile_information") if isinstance(document, dict) else None
    if not isinstance(info, dict):
        warn(f"{path}: has no rosbag2_bagfile_information")
        return None
    version = info.get("version")
    if isinstance(version, int) and version > 9:
        shown = str(version) if version < 10**6 else "far"
        warn(f"{path}: metadata version {shown} is newer than 9, the newest known; read as 9")
    storage = info.get("storage_identifier")
    meta = _Metadata(storage=storage if isinstance(storage, str) and storage else None)
    names: dict[str, list[str]] = {}
    listed = _listed(path, info, "relative_file_paths", warn)
    not_names = [(k, _brief(n)) for k, n in enumerate(listed) if not isinstance(n, str)]
    for name in listed:
        if isinstance(name, str):
            _add_file(meta, names, name)
    if not_names:
        lines = _entry_lines(root, "relative_file_paths", len(listed))
        warn(_unusable(path, "relative_file_paths", lines, not_names, "not naming a file"))
    entries: dict[str, list[str]] = {}
    listed = _listed(path, info, "files", warn)
    no_path: list[tuple[int, str]] = []
    bad_start: list[tuple[int, str]] = []
    for k, entry in enumerate(listed):
        name = entry.get("path") if isinstance(entry, dict) else None
        if not isinstance(entry, dict) or not isinstance(name, str):
            no_path.append((k, _brief(name if isinstance(entry, dict) else entry)))
            continue
        base = _add_file(meta, entries, name)
        written = entry.get("starting_time")
        start = written.get("nanoseconds_since_epoch") if isinstance(written, dict) else None
        if base and isinstance(start, int) and 0 <= start < 2**63:
            meta.starts.setdefault(base, start)
        elif written is not None:
            bad_start.append((k, f"{_brief(name)}: {_brief(written)}"))
        if base:
            meta.listed.setdefault(base, _listed_loss(entry, start))
    lines = _entry_lines(root, "files", len(listed)) if no_path or bad_start else []
    if no_path:
        warn(_unusable(path, "files", lines, no_path, "without a file path"))
    if bad_start:
        warn(
            _unusable(
                path,
                "files",
                lines,
                bad_start,
                "with a starting_time that is not {nanoseconds_since_epoch: N} in int64",
                "ignored (the file's own first message time is used)",
            )
        )
    for key, found in (("relative_file_paths", names), ("files", entries)):
        for base, spelled in found.items():
            if len(spelled) > 1:
                shown = ", ".join(repr(name) for name in spelled[:5])
                warn(f"{path}: {key} names {base} more than once ({shown}); read once")
    outside = {name for spelled in (*names.values(), *entries.values()) for name in spelled}
    for name in sorted(n for n in outside if _outside(n))[:5]:
        base = PurePosixPath(name.replace("\\", "/")).name
        warn(f"{path}: {name!r} points outside the bag folder; {base} in it is read")
    meta.compression_format = str(info.get("compression_format") or "").lower()
    mode = str(info.get("compression_mode") or "").lower()
    meta.compression_mode = "" if mode == "none" else mode
    return meta


def _listed_loss(entry: dict[object, object], start: object) -> Loss:
    """What a ``files`` entry says its file holds: messages and span, where it says so."""
    count = entry.get("message_count")
    duration = entry.get("duration")
    duration = duration.get("nanoseconds") if isinstance(duration, dict) else None
    known = isinstance(start, int) and isinstance(duration, int) and 0 <= start <= start + duration
    return Loss(
        messages=count if isinstance(count, int) and count >= 0 else None,
        start_ns=start if known and isinstance(start, int) else None,
        end_ns=start + duration
        if known and isinstance(start, int) and isinstance(duration, int)
        else None,
    )


def _listed(
    path: Path, info: dict[object, object], key: str, warn: Callable[[str], None]
) -> list[object]:
    value = info.get(key)
    if value is None:
        return []
    if not isinstance(value, list):
        warn(f"{path}: {key} is not a list; ignored")
        return []
    return value


def _add_file(meta: _Metadata, seen: dict[str, list[str]], name: str) -> str | None:
    """Add a listed file by its name alone (before version 4 the bag folder is included)."""
    base = PurePosixPath(name.replace("\\", "/")).name
    if base in {"", ".", ".."} or "\x00" in base:
        return None
    seen.setdefault(base, []).append(name)
    if base not in meta.files:
        meta.files.append(base)
    return base


def _outside(name: str) -> bool:
    """Whether a listed path leaves the folder it is relative to."""
    normal = posixpath.normpath(name.replace("\\", "/"))
    return normal.startswith(("/", "../")) or normal == ".."


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
    return open_folder(path, ctx, _read_metadata(path, ctx.warn), _storage_files(path), Path.exists)


def open_folder(
    path: Path,
    ctx: InputContext,
    meta: _Metadata | None,
    found: list[Path],
    exists: Callable[[Path], bool],
    bag: Callable[[Path, InputContext, list[Path], _Metadata], Rosbag2Input] | None = None,
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
        return build(path, ctx, found, _Metadata())
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
    return Rosbag2Input(path, ctx, [path], _Metadata())


class Rosbag2Input:
    """The storage files of one input chained into one stream sorted by (log time, position)."""

    def __init__(self, path: Path, ctx: InputContext, paths: list[Path], meta: _Metadata) -> None:
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
                raise InputError(_one_line(problems[0]), path=str(path))
            detail = _one_line("; ".join(problems))
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
                raise NotABagError(f"cannot be decompressed ({_one_line(exc)})") from None
            self.ctx.warn(
                f"{path}: compressed data is damaged ({_one_line(exc)}); read the rest", Loss()
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
        count, first, _, reason = self._failures.get(topic, (0, t_ns, t_ns, _one_line(exc)))
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
