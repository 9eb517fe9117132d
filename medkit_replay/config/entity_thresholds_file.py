"""The entity_thresholds YAML read as upstream's EntityThresholdResolver::load_from_yaml reads it.

Per-prefix debounce overrides with the load-time fix-ups only (fault-manager.md §1.12).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.config.file_keys import unknown_map_keys
from medkit_replay.config.yamlcpp import (
    MAX_FILE_BYTES,
    YamlCppError,
    as_bool,
    as_int32,
    as_string,
    compose,
    is_map,
    kind_name,
    line_of,
    map_items,
    subscript,
)
from medkit_replay.engine.thresholds import EntityOverride
from medkit_replay.errors import ConfigWarning
from medkit_replay.files import read_limited
from medkit_replay.yaml_bounds import shown_text

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.config.yamlcpp import Node

_NONE = "no per-entity overrides for this run"
_FIELDS = ("confirmation_threshold", "healing_enabled", "healing_threshold")


def _wrap_int32(value: int) -> int:
    # static_cast<int32_t> of an int: negating INT_MIN wraps to itself.
    return (value + 2**31) % 2**32 - 2**31


def _entry(prefix: str, node: Node, where: str, warnings: list[str]) -> EntityOverride:
    warnings += unknown_map_keys(node, _FIELDS, where, f"entity '{shown_text(prefix)}'")
    confirmation: int | None = None
    healing_enabled: bool | None = None
    healing: int | None = None
    value = subscript(node, "confirmation_threshold")
    if value is not None:  # present, even null: a null then fails to convert
        confirmation = as_int32(value)
        if confirmation > 0:
            warnings.append(
                ConfigWarning(
                    f"confirmation_threshold for '{shown_text(prefix)}' should be <= 0, "
                    f"got {confirmation}. Using {-confirmation}.",
                    path=where,
                    line=line_of(value),
                )
            )
            confirmation = -confirmation
    value = subscript(node, "healing_enabled")
    if value is not None:
        healing_enabled = as_bool(value)
    value = subscript(node, "healing_threshold")
    if value is not None:
        healing = as_int32(value)
        if healing < 0:
            fixed = _wrap_int32(-healing)
            warnings.append(
                ConfigWarning(
                    f"healing_threshold for '{shown_text(prefix)}' should be >= 0, "
                    f"got {healing}. Using {fixed}.",
                    path=where,
                    line=line_of(value),
                )
            )
            healing = fixed
    return EntityOverride(
        prefix=prefix,
        confirmation_threshold=confirmation,
        healing_enabled=healing_enabled,
        healing_threshold=healing,
    )


def _unusable(path: str, message: str, line: int | None = None) -> tuple[ConfigWarning]:
    """The one warning of a file upstream reads no entry of."""
    return (ConfigWarning(f"{message}; {_NONE}", path=path, line=line, unusable=True),)


def load_entity_thresholds(
    path: Path,
) -> tuple[tuple[EntityOverride, ...], tuple[str, ...]]:
    """Entries in file order, and what upstream would have logged (each prefixed with the path).

    Missing file, unparsable YAML or a non-map root → no entries. A non-map value skips its
    prefix; a field it does not know is warned, with the closest known one. A value that
    does not convert stops the reading: that entry and every later one
    are dropped, the earlier ones kept. Positive confirmation_threshold and negative
    healing_threshold are negated; nothing is sanitised here.
    """
    where = f"{path}"
    try:
        root = compose(read_limited(path, MAX_FILE_BYTES))
    except FileNotFoundError:
        return (), _unusable(where, "Entity thresholds config file not found")
    except OSError as exc:  # a FIFO, device or directory too: refused, never read
        return (), _unusable(where, f"Failed to read entity thresholds config: {exc.strerror}")
    except YamlCppError as exc:
        failed = f"Failed to parse entity thresholds config: {exc}"
        return (), _unusable(where, failed, exc.line)
    if root is None or not is_map(root):
        got = f"Entity thresholds config must be a YAML map, got {kind_name(root)}"
        return (), _unusable(where, got)
    entries: list[EntityOverride] = []
    warnings: list[str] = []
    items = map_items(root)
    for index, (key, value) in enumerate(items):
        try:
            prefix = as_string(key)
            if not is_map(value):
                warnings.append(
                    ConfigWarning(
                        f"Skipping non-map entry for prefix '{shown_text(prefix)}'",
                        path=where,
                        line=line_of(key),
                    )
                )
                continue
            entries.append(_entry(prefix, value, where, warnings))
        except YamlCppError as exc:
            later = len(items) - index - 1
            warnings.append(
                ConfigWarning(
                    f"Failed to parse entity thresholds config: {exc}; upstream stops reading "
                    f"here: this entry and the {later} after it are dropped; the "
                    f"{len(entries)} entries read before it apply",
                    path=where,
                    line=exc.line,
                )
            )
            break
    return tuple(entries), tuple(warnings)
