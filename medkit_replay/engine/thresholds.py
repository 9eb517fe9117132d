"""Per-entity debounce overrides: longest path-boundary prefix of the reporting source_id.

Pure: holds already-parsed entries; the YAML file is read by medkit_replay.config.
"""

from __future__ import annotations

from dataclasses import dataclass

from medkit_replay.engine.debounce import DebounceConfig, sanitize


@dataclass(frozen=True, slots=True, kw_only=True)
class EntityOverride:
    """One prefix entry of entity_thresholds; unset fields inherit the global config."""

    prefix: str
    confirmation_threshold: int | None = None
    healing_enabled: bool | None = None
    healing_threshold: int | None = None


def merge(global_config: DebounceConfig, entry: EntityOverride) -> DebounceConfig:
    """Overlay an entry's set fields on the global config (no sanitising)."""
    return DebounceConfig(
        confirmation_threshold=(
            global_config.confirmation_threshold
            if entry.confirmation_threshold is None
            else entry.confirmation_threshold
        ),
        healing_enabled=(
            global_config.healing_enabled
            if entry.healing_enabled is None
            else entry.healing_enabled
        ),
        healing_threshold=(
            global_config.healing_threshold
            if entry.healing_threshold is None
            else entry.healing_threshold
        ),
        critical_immediate_confirm=global_config.critical_immediate_confirm,
    )


class EntityThresholdResolver:
    """Resolve the debounce config of a report from its source_id (fault-manager.md §1.12)."""

    def __init__(
        self,
        global_config: DebounceConfig,
        entries: list[EntityOverride] | tuple[EntityOverride, ...] = (),
        *,
        sanitize_entries: bool = True,
    ) -> None:
        self.global_config = global_config
        # A later duplicate prefix replaces an earlier one, as a YAML map would.
        self._configs: dict[str, DebounceConfig] = {}
        for entry in entries:
            merged = merge(global_config, entry)
            self._configs[entry.prefix] = sanitize(merged) if sanitize_entries else merged
        self._cache: dict[str, DebounceConfig] = {}

    def __len__(self) -> int:
        return len(self._configs)

    def resolve(self, source_id: str) -> DebounceConfig:
        """Config of the longest prefix equal to source_id or followed by '/' in it."""
        cached = self._cache.get(source_id)
        if cached is not None:
            return cached
        best = self.prefix_for(source_id)
        config = self.global_config if best is None else self._configs[best]
        if len(self._cache) < 65536:
            self._cache[source_id] = config
        return config

    def prefix_for(self, source_id: str) -> str | None:
        """The entry whose band applies to ``source_id`` (None: the global config)."""
        best: str | None = None
        for prefix in self._configs:
            if (source_id == prefix or source_id.startswith(prefix + "/")) and (
                best is None or len(prefix) > len(best)
            ):
                best = prefix
        return best
