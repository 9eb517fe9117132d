"""The evidence folder's rules: never one that overlaps a file the run reads, each clip a folder
name of its own within the run, and nothing replaced there but a clip carrying this tool's marker.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.errors import MedkitReplayError

if TYPE_CHECKING:
    from collections.abc import Iterable, Sequence

MARKER = ".medkit-replay-clip"
"""The file in every clip folder this tool writes: the proof that lets a later run replace it.
Not listed in metadata.yaml, so the folder stays a rosbag2 bag as any reader sees it."""
MARKER_TEXT = (
    "Written by medkit-replay analyze --evidence. A later run writing the same clip into this\n"
    "folder replaces it; remove this file to keep the clip from being replaced.\n"
)
STAGING_PREFIX = ".medkit-replay-partial-"
"""Clips are written in a fresh folder of this prefix inside the evidence folder, then moved."""


def refuse_folder_overlap(directory: Path, protected: Iterable[Path]) -> None:
    """Refuse an evidence folder that is, holds or lies inside a file or folder the run reads.

    Symbolic links are resolved on both sides.

    Raises:
        MedkitReplayError: naming the folder and what it overlaps (exit 2).
    """
    target = Path(os.path.realpath(directory))
    for path in protected:
        real = Path(os.path.realpath(path))
        if target == real:
            relation = "is"
        elif real.is_relative_to(target):
            relation = "holds"
        elif target.is_relative_to(real):
            relation = "is inside"
        else:
            continue
        raise MedkitReplayError(
            f"the --evidence folder {relation} {path}, which this run reads; write the clips to "
            "another folder (nothing was written)",
            path=str(directory),
        )


def folder_names(names: Sequence[str]) -> list[str]:
    """Each recording's folder name, in plan order: its name (upstream's ``fault_<CODE>_<ms>``),
    or, for a name taken earlier in the run, the name with the first free suffix ``-2``, ``-3``...

    Names are compared case-folded, as a case-insensitive disk would, so that every disk gets
    the same folders.
    """
    taken: set[str] = set()
    next_suffix: dict[str, int] = {}
    folders: list[str] = []
    for name in names:
        key = name.casefold()
        folder = name
        suffix = next_suffix.get(key, 1)
        while folder.casefold() in taken:
            suffix += 1
            folder = f"{name}-{suffix}"
        next_suffix[key] = suffix
        taken.add(folder.casefold())
        folders.append(folder)
    return folders


def is_ours(path: Path) -> bool:
    """Whether ``path`` is a folder (not a link) holding the marker as a regular file."""
    try:
        folder = path.lstat()
        marker = (path / MARKER).lstat()
    except OSError:
        return False
    return stat.S_ISDIR(folder.st_mode) and stat.S_ISREG(marker.st_mode)


def foreign(targets: Iterable[Path]) -> list[Path]:
    """The targets that exist and are not a clip this tool wrote (a link or a file included)."""
    found: list[Path] = []
    for target in targets:
        try:
            target.lstat()
        except (FileNotFoundError, NotADirectoryError):
            continue  # nothing there (the folder is made, or refused, when clips are written)
        except OSError:
            found.append(target)  # cannot be looked at: not provably ours
            continue
        if not is_ours(target):
            found.append(target)
    return found
