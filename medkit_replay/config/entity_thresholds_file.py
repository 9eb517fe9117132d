"""The entity_thresholds YAML read as upstream's EntityThresholdResolver::load_from_yaml reads it.

Per-prefix debounce overrides with the load-time fix-ups only (fault-manager.md §1.12).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

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
from medkit_replay.files import read_limited
from medkit_replay.yaml_bounds import shown_text

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.config.yamlcpp import Node

_NONE = "no per-entity overrides for this run"


def _wrap_int32(value: int) -> int:
    # static_cast<int32_t> of an int: negating INT_MIN wraps to itself.
    return (value + 2**31) % 2**32 - 2**31


def _entry(prefix: str, node: Node, where: str, warnings: list[str]) -> EntityOverride:
    confirmation: int | None = None
    healing_enabled: bool | None = None
    healing: int | None = None
    value = subscript(node, "confirmation_threshold")
    if value is not None:  # present, even null: a null then fails to convert
        confirmation = as_int32(value)
        if confirmation > 0:
            warnings.append(
                f"{where}:{line_of(value)}: confirmation_threshold for '{shown_text(prefix)}' "
                "should be <= 0, "
                f"got {confirmation}. Using {-confirmation}."
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
                f"{where}:{line_of(value)}: healing_threshold for '{shown_text(prefix)}' "
                "should be >= 0, "
                f"got {healing}. Using {fixed}."
            )
            healing = fixed
    return EntityOverride(
        prefix=prefix,
        confirmation_threshold=confirmation,
        healing_enabled=healing_enabled,
        healing_threshold=healing,
    )


def load_entity_thresholds(
    path: Path,
) -> tuple[tuple[EntityOverride, ...], tuple[str, ...]]:
    """Entries in file order, and what upstream would have logged (each prefixed with the path).

    Missing file, unparsable YAML or a non-map root → no entries. A non-map value skips its
    prefix. A value that does not convert stops the reading: that entry and every later one
    are dropped, the earlier ones kept. Positive confirmation_threshold and negative
    healing_threshold are negated; nothing is sanitised here.
    """
    where = f"{path}"
    try:
        root = compose(read_limited(path, MAX_FILE_BYTES))
    except FileNotFoundError:
        return (), (f"{where}: Entity thresholds config file not found; {_NONE}",)
    except OSError as exc:  # a FIFO, device or directory too: refused, never read
        return (), (f"{where}: Failed to read entity thresholds config: {exc.strerror}; {_NONE}",)
    except YamlCppError as exc:
        at = where if exc.line is None else f"{where}:{exc.line}"
        return (), (f"{at}: Failed to parse entity thresholds config: {exc}; {_NONE}",)
    if root is None or not is_map(root):
        return (), (
            f"{where}: Entity thresholds config must be a YAML map, got {kind_name(root)}; {_NONE}",
        )
    entries: list[EntityOverride] = []
    warnings: list[str] = []
    items = map_items(root)
    for index, (key, value) in enumerate(items):
        try:
            prefix = as_string(key)
            if not is_map(value):
                warnings.append(
                    f"{where}:{line_of(key)}: Skipping non-map entry for prefix "
                    f"'{shown_text(prefix)}'"
                )
                continue
            entries.append(_entry(prefix, value, where, warnings))
        except YamlCppError as exc:
            later = len(items) - index - 1
            at = where if exc.line is None else f"{where}:{exc.line}"
            warnings.append(
                f"{at}: Failed to parse entity thresholds config: {exc}; upstream stops reading "
                f"here: this entry and the {later} after it are dropped; the {len(entries)} "
                "entries read before it apply"
            )
            break
    return tuple(entries), tuple(warnings)
