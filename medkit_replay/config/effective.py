"""The effective configuration of a replay as plain JSON-ready values, for reports to show.

Reads the typed configs after sanitising; defaults included, so a reader sees what was in force.
"""

from __future__ import annotations

import dataclasses
import enum
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from medkit_replay.config.replay_options import ReplayOptions
    from medkit_replay.engine.manager import FaultManagerConfig


def _plain(value: object) -> object:
    if isinstance(value, enum.Enum):
        return value.value
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in sorted(value.items())}
    if isinstance(value, list | tuple | frozenset | set):
        items = sorted(value) if isinstance(value, frozenset | set) else value
        return [_plain(v) for v in items]
    return value


def effective_config(
    manager: FaultManagerConfig, options: ReplayOptions, files: tuple[str, ...]
) -> dict[str, object]:
    """Every node's configuration as the replay applied it, plus the files it came from."""
    return {
        "files": list(files),
        # The release is the report's own top-level key, not a fault_manager parameter;
        # storage_type changes nothing from 0.7.0 on, and the report's keys do not vary.
        "fault_manager": {
            k: v
            for k, v in _as_dict(_plain(manager)).items()
            if k not in ("release", "storage_type")
        },
        "diagnostic_bridge": _plain(options.diagnostic),
        "action_status_bridge": _plain(options.action_status),
        "log_bridge": {"enabled": options.log_bridge, **_as_dict(_plain(options.log))},
        "medkit_replay": {"action_sources": dict(sorted(options.action_sources.items()))},
    }


def _as_dict(value: object) -> dict[str, object]:
    return dict(value) if isinstance(value, dict) else {}
