"""The fault_manager's capture parameters (``snapshots.*``, ``snapshots.rosbag.*``) and the
snapshot config file they may name, read with upstream's defaults, sanitising and warnings.
"""

from __future__ import annotations

import math
import re
from dataclasses import replace
from typing import TYPE_CHECKING

from yaml.constructor import ConstructorError, SafeConstructor

from medkit_replay.config.file_keys import unknown_map_keys
from medkit_replay.config.nodes import located, located_warnings, values
from medkit_replay.config.reader import ParameterReader
from medkit_replay.errors import ConfigError, ConfigWarning
from medkit_replay.evidence.rules import RosbagConfig, SnapshotConfig
from medkit_replay.files import read_limited_text
from medkit_replay.releases import default_release
from medkit_replay.yaml_bounds import compose_config

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.config.params import NodeParams
    from medkit_replay.releases import Release

_P = "snapshots."
_R = "snapshots.rosbag."
_FILE_KEYS = ("fault_specific", "patterns", "default_topics")


def snapshot_config(
    params: NodeParams, release: Release | None = None
) -> tuple[SnapshotConfig, list[str]]:
    """Build the capture config from the fault_manager node's parameters as ``release``
    declares them (the newest when None): a parameter it does not have is not read.

    Raises:
        ConfigError: a parameter of the wrong type, with its file and line.
    """
    chosen = release or default_release()
    config, warnings = located(params, lambda: _build(params, chosen))
    return config, located_warnings(params, warnings)


def _build(params: NodeParams, release: Release) -> tuple[SnapshotConfig, list[str]]:
    reader = ParameterReader("fault_manager", values(params))
    cooldown = reader.double(_P + "recapture_cooldown_sec", 60.0)
    if cooldown < 0 or math.isnan(cooldown):
        cooldown = reader.replaced(
            _P + "recapture_cooldown_sec",
            f"snapshots.recapture_cooldown_sec {cooldown} should be >= 0; disabling it",
            0.0,
        )
    max_per_fault = reader.integer(_P + "max_per_fault", 10)
    if max_per_fault < 0:
        max_per_fault = reader.replaced(
            _P + "max_per_fault",
            f"snapshots.max_per_fault {max_per_fault} should be >= 0; no limit",
            0,
        )
    timeout = reader.double(_P + "timeout_sec", 1.0)
    if not timeout > 0:
        timeout = reader.replaced(
            _P + "timeout_sec", f"snapshots.timeout_sec {timeout} must be positive; using 1.0", 1.0
        )
    max_size = reader.integer(_P + "max_message_size", 65536)
    if max_size <= 0:
        max_size = reader.replaced(
            _P + "max_message_size",
            f"snapshots.max_message_size {max_size} must be positive; using 65536",
            65536,
        )
    defaults = reader.strings(_P + "default_topics")
    if release.entity_default_snapshots:  # '' is "no defaults" since entity_default came
        defaults = tuple(t for t in defaults if t)
    fault_specific: dict[str, tuple[str, ...]] = {}
    patterns: dict[str, tuple[str, ...]] = {}
    file_param = params.get(_P + "config_file")
    file_name = reader.string(_P + "config_file", "")
    if file_name and file_param is not None:
        path = file_param.path.parent / file_name
        loaded = load_snapshot_file(path, reader)
        if loaded is not None:
            fault_specific, patterns, file_defaults = loaded
            if file_defaults and not defaults:
                defaults = file_defaults
    compiled: list[tuple[str, tuple[str, ...]]] = []
    for pattern in sorted(patterns):
        try:
            re.compile(pattern)
        except re.error as err:
            reader.warn(
                f"snapshot pattern {pattern!r} is not a valid regex and is ignored: {err}",
                parameter=_P + "config_file",
            )
            continue
        compiled.append((pattern, patterns[pattern]))
    config = SnapshotConfig(
        enabled=reader.boolean(_P + "enabled", True),
        background_capture=reader.boolean(_P + "background_capture", False),
        timeout_sec=timeout,
        max_message_size=max_size,
        default_topics=defaults,
        entity_default=release.entity_default_snapshots
        and reader.boolean(_P + "entity_default", True),
        fault_specific=fault_specific,
        patterns=tuple(compiled),
        recapture_cooldown_sec=cooldown,
        retain_on_clear=release.retain_on_clear and reader.boolean(_P + "retain_on_clear", False),
        max_per_fault=max_per_fault,
        freeze_frame_row=release.freeze_frame_row,
        snapshot_sets=release.snapshot_sets,
        rosbag=_rosbag(reader, release),
    )
    return config, reader.warnings


def _rosbag(reader: ParameterReader, release: Release) -> RosbagConfig:
    switches = RosbagConfig(
        bag_history=release.bag_history,
        post_roll_sharing=release.post_roll_sharing,
        post_roll_only=release.post_roll_only_bags,
        cleanup_in_post_roll=release.cleanup_in_post_roll,
    )
    if not reader.boolean(_R + "enabled", False):
        return switches  # upstream declares the rest only when enabled
    before = reader.double(_R + "duration_sec", 5.0)
    if not before > 0:
        before = reader.replaced(
            _R + "duration_sec",
            f"snapshots.rosbag.duration_sec {before} must be positive; using 5.0",
            5.0,
        )
    after = reader.double(_R + "duration_after_sec", 1.0)
    if after < 0:
        after = reader.replaced(
            _R + "duration_after_sec",
            f"snapshots.rosbag.duration_after_sec {after} must be >= 0; using 0.0",
            0.0,
        )
    fmt = reader.string(_R + "format", release.default_bag_format)
    if fmt not in ("mcap", "sqlite3"):
        fmt = reader.replaced(
            _R + "format",
            f"snapshots.rosbag.format {fmt!r} is unknown; using sqlite3 as upstream does",
            "sqlite3",
        )
    size = reader.integer(_R + "max_bag_size_mb", 50)
    if size <= 0:
        size = reader.replaced(
            _R + "max_bag_size_mb",
            "snapshots.rosbag.max_bag_size_mb must be positive; using 50",
            50,
        )
    per_fault = reader.integer(_R + "max_bags_per_fault", 1) if release.bag_history else 1
    if per_fault < 0:
        per_fault = reader.replaced(
            _R + "max_bags_per_fault",
            "snapshots.rosbag.max_bags_per_fault must be >= 0; no limit",
            0,
        )
    return replace(
        switches,
        enabled=True,
        duration_sec=before,
        duration_after_sec=after,
        topics=reader.string(_R + "topics", "entity"),
        include_topics=reader.strings(_R + "include_topics"),
        exclude_topics=reader.strings(_R + "exclude_topics"),
        exclude_sensor_topics=reader.boolean(_R + "exclude_sensor_topics", True),
        lazy_start=reader.boolean(_R + "lazy_start", False),
        format=fmt,
        max_bag_size_mb=size,
        max_bags_per_fault=per_fault,
        auto_cleanup=reader.boolean(_R + "auto_cleanup", True),
    )


Loaded = tuple[dict[str, tuple[str, ...]], dict[str, tuple[str, ...]], tuple[str, ...]]


def load_snapshot_file(path: Path, reader: ParameterReader) -> Loaded | None:
    """fault_specific, patterns and default_topics of a snapshot config file; its warnings go
    to ``reader``.

    Upstream logs and carries on without the file when it is missing or not YAML; so does this,
    with a warning. A file of the wrong shape is refused, naming it. Another key is warned, with
    the closest known one.
    """
    try:
        text = read_limited_text(path)
    except (OSError, UnicodeDecodeError) as err:
        reader.warnings.append(
            ConfigWarning(
                f"{reader.node}: snapshot config file {path} cannot be read ({err}); ignored as "
                "upstream does",
                path=str(path),
                unusable=True,
                shown_at=False,
            )
        )
        return None
    root = compose_config(text, str(path))
    if root is None:
        return {}, {}, ()
    reader.warnings += unknown_map_keys(root, _FILE_KEYS, str(path), "snapshot config file")
    try:
        data = SafeConstructor().construct_document(root)
    except ConstructorError as err:
        raise ConfigError(f"invalid YAML: {err.problem}", path=str(path)) from None
    if not isinstance(data, dict):
        raise ConfigError("a snapshot config is a map (fault_specific, patterns)", path=str(path))

    def topic_map(key: str) -> dict[str, tuple[str, ...]]:
        section = data.get(key) or {}
        if not isinstance(section, dict):
            raise ConfigError(f"{key} must map names to lists of topics", path=str(path))
        out: dict[str, tuple[str, ...]] = {}
        for name, topics in section.items():
            out[str(name)] = _topic_list(topics, path, f"{key}.{name}")
        return out

    defaults = _topic_list(data.get("default_topics") or [], path, "default_topics")
    return topic_map("fault_specific"), topic_map("patterns"), defaults


def _topic_list(value: object, path: Path, where: str) -> tuple[str, ...]:
    if value is None:
        return ()
    if not isinstance(value, list) or not all(isinstance(t, str) for t in value):
        raise ConfigError(f"{where} must be a list of topic names", path=str(path))
    return tuple(value)
