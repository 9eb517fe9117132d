"""Finding the recordings under some folders: bag directories, bare storage files, scripts.

Rules (README "Fleets"):

- a folder holding ``metadata.yaml`` is one rosbag2 recording (its split files are read
  together); nothing below it is looked at;
- so is a folder without ``metadata.yaml`` whose storage files are all named after it as
  rosbag2 names them (``run/run_0.mcap``, ``run/run_1.mcap``: a recording cut before its
  metadata was written);
- any other ``.mcap`` or ``.db3`` file is a bare recording of its own, so is a ROS 1 ``.bag``
  file, and a ``.jsonl`` file a script;
- hidden files and folders (``.name``) are skipped; symbolic links are followed once;
- a FIFO, device or socket named like a recording is listed too: its run says why it cannot
  be read (never skipped in silence, never opened).

The order is deterministic: the given folders in order, each one's recordings sorted by path
(numbers in names compared as numbers); a recording reached twice is listed once.

A root may also be an ``s3://`` or ``gs://`` prefix: the same rules apply to the objects under
it (a bag folder is listed as its URL ending in ``/``; scripts are read from local files only).
"""

from __future__ import annotations

import re
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING

from medkit_replay.errors import InputError
from medkit_replay.inputs import is_remote
from medkit_replay.inputs.recording import READERS, input_kind
from medkit_replay.inputs.remote.store import list_objects, open_store, parse_location

if TYPE_CHECKING:
    from collections.abc import Iterable, Sequence
    from pathlib import PurePath

FILE_KINDS = frozenset(kind for kind in READERS if kind != "dir")
"""Suffixes of files replayed on their own: ``.mcap``, ``.db3``, ``.bag``, ``.jsonl``."""
STORAGE_SUFFIXES = frozenset({".mcap", ".db3"})
"""Suffixes of rosbag2 storage files (after a ``.zstd`` file-compression suffix is removed)."""
_NUMBER = re.compile(r"(\d+)")


def natural_key(path: PurePath) -> tuple[tuple[tuple[int, int | str], ...], ...]:
    """A sort key for paths comparing numbers in names as numbers (``run_2`` before ``run_10``;
    ``run_02`` before ``run_2``, so that the order stays total)."""
    return tuple(
        (
            *((1, int(piece)) if piece.isdigit() else (0, piece) for piece in _NUMBER.split(part)),
            (2, part),
        )
        for part in path.parts
    )


def _storage_stem(name: str) -> str | None:
    """The name of a storage file without its suffixes; None for any other file."""
    if name.lower().endswith(".zstd"):
        name = name[: -len(".zstd")]
    stem, dot, suffix = name.rpartition(".")
    if not dot or f".{suffix.lower()}" not in STORAGE_SUFFIXES:
        return None
    return stem


def is_bag_directory(directory: Path, files: Iterable[Path]) -> bool:
    """Whether a folder is one rosbag2 recording (see the module's rules).

    Args:
        directory: the folder.
        files: the files in it (not its subfolders).
    """
    if (directory / "metadata.yaml").is_file():
        return True
    return is_bag_folder(directory.name, [f.name for f in files])


def is_bag_folder(name: str, file_names: Iterable[str]) -> bool:
    """The rule on names alone: a folder (or remote prefix) called ``name`` holding these
    files is one recording."""
    names = list(file_names)
    if "metadata.yaml" in names:
        return True
    stems = [stem for stem in map(_storage_stem, names) if stem is not None]
    if not stems:
        return False
    split = re.compile(re.escape(name) + r"(_\d+)?")
    return all(split.fullmatch(stem) for stem in stems)


def _walk(root: Path) -> list[Path]:
    """The recordings under one folder, in no particular order."""
    found: list[Path] = []
    visited: set[Path] = set()
    pending = [root]
    while pending:
        directory = pending.pop()
        real = directory.resolve()
        if real in visited:
            continue  # a symbolic link back up the tree
        visited.add(real)
        try:
            entries = [e for e in directory.iterdir() if not e.name.startswith(".")]
        except OSError:
            if directory == root:
                raise
            found.append(directory)  # its run says why it cannot be read
            continue
        files = [e for e in entries if e.is_file()]
        if is_bag_directory(directory, files):
            found.append(directory)
            continue
        folders = [e for e in entries if e.is_dir()]
        others = [e for e in entries if e not in files and e not in folders]
        found += [f for f in (*files, *others) if input_kind(f) in FILE_KINDS]
        pending += folders
    return found


def _walk_remote(url: str) -> list[str]:
    """The recordings under a bucket prefix, as URLs, sorted as local ones are.

    Raises:
        InputError: not a bucket URL, the extra is missing, or the prefix cannot be listed.
    """
    location = parse_location(url)
    if location.scheme not in ("s3", "gs"):
        raise InputError("an HTTP server cannot be listed; give the recordings' own URLs", path=url)
    prefix = location.key.rstrip("/") + "/" if location.key.strip("/") else ""
    folders: dict[str, list[str]] = {}  # folder under the prefix -> names of its files
    for key, _size in list_objects(open_store(location), location):
        relative = PurePosixPath(key[len(prefix) :])
        if any(part.startswith(".") for part in relative.parts):
            continue
        folders.setdefault(str(relative.parent), []).append(relative.name)
    root_name = PurePosixPath(prefix).name or location.bucket
    if "." in folders and is_bag_folder(root_name, folders["."]):
        return [location.display.rstrip("/") + "/"]  # the prefix is one recording
    bags = sorted(
        (f for f in folders if f != "." and is_bag_folder(PurePosixPath(f).name, folders[f])),
        key=len,
    )
    kept: list[str] = []  # bag folders, none inside another
    for folder in bags:
        if not any(folder.startswith(f"{outer}/") for outer in kept):
            kept.append(folder)
    found = [PurePosixPath(f"{folder}/") for folder in kept]
    for folder, names in folders.items():
        if folder in kept or any(folder.startswith(f"{outer}/") for outer in kept):
            continue
        found += [PurePosixPath(folder, name) for name in names if _storage_stem(name) is not None]
    base = location.display[: len(location.display) - len(location.key)] + prefix
    return [
        base + str(path) + ("/" if str(path) in kept else "")
        for path in sorted(found, key=natural_key)
    ]


def _remote_roots(url: str) -> list[str]:
    """A URL naming a storage file is that recording, as a local file is; a prefix is walked
    (a bucket's; an HTTP server cannot be listed)."""
    if PurePosixPath(url.rstrip("/")).suffix.lower() in FILE_KINDS:
        return [url]
    return _walk_remote(url)


def discover(roots: Iterable[str | Path]) -> list[Path | str]:
    """Every recording under the given folders, each once, in a deterministic order.

    A root may also be a recording itself (a bag folder, or a file of a kind READERS knows).

    Raises:
        InputError: a root does not exist, cannot be listed, or is a file of no known kind.
    """
    recordings: list[Path | str] = []
    seen: set[Path | str] = set()
    for raw in roots:
        if is_remote(raw):
            for url in _remote_roots(str(raw)):
                if url not in seen:
                    seen.add(url)
                    recordings.append(url)
            continue
        root = Path(raw)
        if not root.exists():
            raise InputError("input folder not found", path=str(root))
        if root.is_dir():
            try:
                found = sorted(_walk(root), key=lambda p: natural_key(p.relative_to(root)))
            except OSError as err:
                raise InputError(
                    f"cannot be listed ({err.strerror or err})", path=str(root)
                ) from None
        elif input_kind(root) in FILE_KINDS:
            found = [root]
        else:
            kinds = ", ".join(sorted(FILE_KINDS))
            raise InputError(
                f"not a folder nor a recording (expected a folder or a {kinds} file)",
                path=str(root),
            )
        for path in found:
            key = path.resolve()
            if key not in seen:
                seen.add(key)
                recordings.append(path)
    return recordings


def discover_some(roots: Sequence[str | Path]) -> list[Path | str]:
    """:func:`discover`, for a command that needs at least one recording.

    Raises:
        InputError: as :func:`discover`, or no recording was found under any root.
    """
    recordings = discover(roots)
    if not recordings:
        raise InputError(
            "no recording found (rosbag2 folders, .mcap, .db3, .bag or .jsonl files)",
            path=", ".join(str(root) for root in roots),
        )
    return recordings
