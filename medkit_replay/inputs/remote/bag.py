"""Remote inputs: a bare MCAP, ``.db3`` or a rosbag2 folder in S3, GCS or on an HTTP server.

An indexed MCAP is read by ranges through the one MCAP reader (footer, summary, then only
what the replay reads, hints turned into concurrent, coalesced, bounded requests); any other
storage file is downloaded into a temporary folder, bounded by its free space and removed on
close. Reports name the input by its URL, never a temporary path.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path, PurePosixPath
from tempfile import TemporaryDirectory
from typing import TYPE_CHECKING

from medkit_replay.errors import InputError
from medkit_replay.files import MAX_TEXT_FILE_BYTES
from medkit_replay.inputs.mcap.reader import McapFile
from medkit_replay.inputs.metadata import Metadata, read_metadata
from medkit_replay.inputs.remote.ranges import RemoteSource
from medkit_replay.inputs.remote.store import (
    RemoteObject,
    Tally,
    list_objects,
    open_store,
    parse_location,
)
from medkit_replay.inputs.rosbag2 import STORAGE_FILES, Rosbag2Input, _natural_key, open_folder
from medkit_replay.inputs.storage import NotABagError, temp_room

if TYPE_CHECKING:
    from medkit_replay.inputs.remote.store import Location
    from medkit_replay.inputs.source import InputContext
    from medkit_replay.inputs.storage import StorageFile
    from medkit_replay.model import InputSummary, Loss

DOWNLOAD_BLOCK = 8 * 1024 * 1024
"""Bytes per request when a storage file is downloaded."""


def _download(remote: RemoteObject, target: Path) -> None:
    """Copy a remote object to ``target`` in blocks, bounded by the temporary folder's room.

    Raises:
        NotABagError: it does not fit in the temporary folder.
        RemoteError: it cannot be fetched.
    """
    room = temp_room()
    if remote.size > room:
        raise NotABagError(
            f"needs a temporary copy of {remote.size:,} bytes, more than the {room:,} bytes "
            "the temporary folder has free"
        )
    with target.open("wb") as sink:
        for start in range(0, remote.size, DOWNLOAD_BLOCK):
            sink.write(remote.fetch(start, min(remote.size, start + DOWNLOAD_BLOCK)))


def _is_mcap(name: str, meta: Metadata) -> bool:
    """Whether a storage file is read by ranges (an MCAP file, not file-compressed)."""
    suffix = PurePosixPath(name).suffix
    if suffix == ".zstd":
        return False
    return suffix == ".mcap" or (suffix not in STORAGE_FILES and meta.storage == "mcap")


class RemoteBag(Rosbag2Input):
    """A rosbag2 input whose storage files are remote objects.

    Its files are named by paths in a private temporary folder (where downloaded files are
    put); every warning and the summary name them by URL instead.
    """

    def __init__(
        self,
        path: Path,
        ctx: InputContext,
        paths: list[Path],
        meta: Metadata,
        *,
        remote: RemoteFolder,
    ) -> None:
        self._remote = remote
        self._remote_meta = meta
        super().__init__(path, ctx, paths, meta)

    def _open_file(self, path: Path, file_no: int) -> StorageFile:
        obj = self._remote.object(path.name)
        if _is_mcap(path.name, self._remote_meta):
            opened = McapFile(path, file_no, self.ctx.warn, source=RemoteSource(obj))
            opened.indexed = self.ctx.use_index
            return opened
        _download(obj, path)
        return super()._open_file(path, file_no)

    def summary(self) -> InputSummary:
        return replace(super().summary(), path=self._remote.location.display.rstrip("/"))

    def close(self) -> None:
        try:
            super().close()
        finally:
            self._remote.close()


class RemoteFolder:
    """The objects of one remote input, and the temporary folder that stands for it."""

    def __init__(
        self, location: Location, store: object, tally: Tally, *, single: bool = False
    ) -> None:
        self.location = location
        self.store = store
        self.tally = tally
        self.single = single  # a bare storage file: the URL itself is its only object
        self.sizes: dict[str, int] = {}  # listed objects by name (empty for HTTP)
        self._objects: dict[str, RemoteObject] = {}
        self._temp = TemporaryDirectory(prefix="medkit-replay-remote-")
        name = PurePosixPath(location.key.rstrip("/")).name or location.bucket.replace(":", "_")
        self.mirror = Path(self._temp.name, name)

    def translate(self, text: str) -> str:
        """A message about the temporary folder, said of the URL instead."""
        return text.replace(str(self.mirror), self.location.display.rstrip("/"))

    def object(self, name: str) -> RemoteObject:
        """The object called ``name`` in the folder (its size asked for once).

        Raises:
            RemoteError: it is not there, or access is denied.
        """
        if name not in self._objects:
            location = self.location if self.single else self.location.child(name)
            self._objects[name] = RemoteObject(self.store, location, self.tally)
        return self._objects[name]

    def close(self) -> None:
        self._temp.cleanup()


def open_remote(text: str, ctx: InputContext, tallies: dict[str, Tally] | None = None) -> RemoteBag:
    """Open a remote input: a bare ``.mcap`` / ``.db3`` object, or a rosbag2 folder (a prefix
    holding ``metadata.yaml``, or storage files only).

    Args:
        tallies: where bytes fetched are counted, by URL (shared by passes over one input).

    Raises:
        InputError: the extra is missing, the URL is refused, nothing is found there, access
            is denied, or nothing in it can be read.
    """
    location = parse_location(text)
    store = open_store(location)
    single = not location.key.endswith("/") and _storage_suffix(PurePosixPath(location.key).name)
    name = location.display.rstrip("/")  # as the summary names the input
    tally = (tallies if tallies is not None else {}).setdefault(name, Tally(name))
    folder = RemoteFolder(location, store, tally, single=single)
    warn = ctx.warn

    def translated(message: str, loss: Loss | None = None, /) -> None:
        warn(folder.translate(message), loss)

    ctx = ctx._replace(warn=translated)
    try:
        if single:
            return RemoteBag(folder.mirror, ctx, [folder.mirror], Metadata(), remote=folder)
        return _open_prefix(folder, ctx)
    except InputError as exc:  # said of the URL, not of the temporary folder
        folder.close()
        where = folder.translate(exc.path) if exc.path is not None else None
        raise type(exc)(folder.translate(exc.problem), path=where) from None
    except BaseException:
        folder.close()
        raise


def _storage_suffix(name: str) -> bool:
    return PurePosixPath(name.removesuffix(".zstd")).suffix in STORAGE_FILES


def _open_prefix(folder: RemoteFolder, ctx: InputContext) -> RemoteBag:
    location = folder.location
    folder.mirror.mkdir()
    listed = location.scheme in ("s3", "gs")
    if listed:
        prefix = location.key.rstrip("/") + "/" if location.key.strip("/") else ""
        for key, size in list_objects(folder.store, location):
            rest = key[len(prefix) :] if key.startswith(prefix) else ""
            if rest and "/" not in rest:
                folder.sizes[rest] = size
    meta = None
    if not listed or "metadata.yaml" in folder.sizes:
        try:
            metadata = folder.object("metadata.yaml")
        except InputError:
            if listed:
                raise
            metadata = None  # over HTTP: no metadata.yaml there
        if metadata is not None:
            if metadata.size > MAX_TEXT_FILE_BYTES:
                raise InputError(
                    f"metadata.yaml holds {metadata.size:,} bytes; not a rosbag2 metadata file",
                    path=location.child("metadata.yaml").display,
                )
            _download(metadata, folder.mirror / "metadata.yaml")
            meta = read_metadata(folder.mirror, ctx.warn)
    found = sorted(
        (folder.mirror / name for name in folder.sizes if _storage_suffix(name)),
        key=_natural_key,
    )
    if meta is None and not found:
        problem = "no metadata.yaml and no .mcap or .db3 object under it"
        raise InputError(problem if listed else "no metadata.yaml there", path=location.display)

    def exists(path: Path) -> bool:
        if listed:
            return path.name in folder.sizes
        try:
            folder.object(path.name)
        except InputError:
            return False
        return True

    def bag(path: Path, ctx: InputContext, paths: list[Path], meta: Metadata) -> RemoteBag:
        return RemoteBag(path, ctx, paths, meta, remote=folder)

    opened = open_folder(folder.mirror, ctx, meta, found, exists, bag)
    assert isinstance(opened, RemoteBag)  # built by ``bag``
    return opened
