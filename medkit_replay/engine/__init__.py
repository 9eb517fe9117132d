"""The pure core: reporter filter, fault manager and correlation, driven by bag time.

Imports nothing from inputs, bridges or outputs, and never reads a clock or a file.
"""

from __future__ import annotations

from medkit_replay.engine.debounce import DebounceConfig, clamp, compute_status, sanitize
from medkit_replay.engine.local_filter import LocalFilter, LocalFilterConfig
from medkit_replay.engine.manager import FaultManager, FaultManagerConfig
from medkit_replay.engine.storage import FaultRecord, FaultStorage
from medkit_replay.engine.thresholds import EntityOverride, EntityThresholdResolver
from medkit_replay.engine.timeline import Timeline

__all__ = [
    "DebounceConfig",
    "EntityOverride",
    "EntityThresholdResolver",
    "FaultManager",
    "FaultManagerConfig",
    "FaultRecord",
    "FaultStorage",
    "LocalFilter",
    "LocalFilterConfig",
    "Timeline",
    "clamp",
    "compute_status",
    "sanitize",
]
