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
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.errors import InputError
from medkit_replay.inputs.recording import READERS, input_kind

if TYPE_CHECKING:
    from collections.abc import Iterable

FILE_KINDS = frozenset(kind for kind in READERS if kind != "dir")
"""Suffixes of files replayed on their own: ``.mcap``, ``.db3``, ``.bag``, ``.jsonl``."""
STORAGE_SUFFIXES = frozenset({".mcap", ".db3"})
"""Suffixes of rosbag2 storage files (after a ``.zstd`` file-compression suffix is removed)."""
_NUMBER = re.compile(r"(\d+)")


def natural_key(path: Path) -> tuple[tuple[tuple[int, int | str], ...], ...]:
    """A sort key for paths comparing numbers in names as numbers (``run_2`` before ``run_10``;
    ``run_02`` before ``run_2``, so that the order stays total)."""
    return tuple(
        (
            *((1, int(piece)) if piece.isdigit() else (0, piece) for piece in _NUMBER.split(part)),
            (2, part),
        )
        for part in path.parts
    )


def _storage_stem(path: Path) -> str | None:
    """The name of a storage file without its suffixes; None for any other file."""
    name = path.name
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
    stems = [stem for stem in map(_storage_stem, files) if stem is not None]
    if not stems:
        return False
    split = re.compile(re.escape(directory.name) + r"(_\d+)?")
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


def discover(roots: Iterable[str | Path]) -> list[Path]:
    """Every recording under the given folders, each once, in a deterministic order.

    A root may also be a recording itself (a bag folder, or a file of a kind READERS knows).

    Raises:
        InputError: a root does not exist, cannot be listed, or is a file of no known kind.
    """
    recordings: list[Path] = []
    seen: set[Path] = set()
    for raw in roots:
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
