"""rosbag2's metadata.yaml, read leniently: the storage files it lists, their start times, what
each holds and the compression; every unusable entry is one warning at its line, then ignored.
"""

from __future__ import annotations

import posixpath
from dataclasses import dataclass, field
from pathlib import PurePosixPath
from typing import TYPE_CHECKING

import yaml

from medkit_replay.files import read_limited_text
from medkit_replay.model import Loss
from medkit_replay.text import one_line
from medkit_replay.yaml_bounds import YamlBoundsError, compose_bounded

if TYPE_CHECKING:
    from collections.abc import Callable
    from pathlib import Path

_FAST_LOADER: type[yaml.SafeLoader] = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


@dataclass(slots=True)
class Metadata:
    """What the replay uses of metadata.yaml (rosbag2 versions 1 to 9)."""

    storage: str | None = None
    files: list[str] = field(default_factory=list)
    starts: dict[str, int] = field(default_factory=dict)
    listed: dict[str, Loss] = field(default_factory=dict)
    """What losing each file costs, as its ``files`` entry says (messages, span)."""
    compression_format: str = ""
    compression_mode: str = ""


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


def read_metadata(directory: Path, warn: Callable[[str], None]) -> Metadata | None:
    """Parse metadata.yaml leniently; None (with a warning) when it is missing or unusable."""
    path = directory / "metadata.yaml"
    if not path.exists():
        return None
    try:
        document, root = _load_metadata(path)
    except (OSError, UnicodeDecodeError, yaml.YAMLError, ValueError) as exc:
        # ValueError: an integer of thousands of digits, refused by Python's int().
        warn(f"{path}: cannot be read ({one_line(exc)})")
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
    meta = Metadata(storage=storage if isinstance(storage, str) and storage else None)
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


def _add_file(meta: Metadata, seen: dict[str, list[str]], name: str) -> str | None:
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
