"""The fault_manager node's parameters: upstream's names, defaults, sanitising and warnings.

Turns flat node parameters into a FaultManagerConfig; referenced files resolve beside their YAML.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from medkit_replay.config.correlation_file import load_correlation
from medkit_replay.config.entity_thresholds_file import load_entity_thresholds
from medkit_replay.config.nodes import located, located_warnings, values
from medkit_replay.config.reader import INT64_MAX, ParameterReader, to_int32
from medkit_replay.engine.debounce import DebounceConfig
from medkit_replay.engine.manager import FaultManagerConfig
from medkit_replay.engine.storage import (
    DEFAULT_NEAR_MISS_BOUND,
    DEFAULT_STORAGE_TYPE,
    STORAGE_TYPES,
)
from medkit_replay.errors import ConfigError
from medkit_replay.model import NS_PER_MS, NS_PER_SEC
from medkit_replay.releases import default_release

if TYPE_CHECKING:
    from medkit_replay.config.params import NodeParams
    from medkit_replay.engine.thresholds import EntityOverride
    from medkit_replay.releases import Release

DEFAULT_CLEANUP_INTERVAL_SEC = 5.0


def fault_manager_config(
    params: NodeParams, release: Release | None = None
) -> tuple[FaultManagerConfig, list[str]]:
    """Build the manager's config from its parameters, with upstream's warnings (§1.2).

    Raises:
        ConfigError: a parameter of the wrong type, with its file and line.
    """
    config, warnings = located(params, lambda: _build(params, release or default_release()))
    return config, located_warnings(params, warnings)


def _int32(reader: ParameterReader, name: str, value: int, default: int, *, sanitized: bool) -> int:
    """Upstream keeps both thresholds as ``static_cast<int32_t>`` of the negated int64.

    Negating INT64_MIN wraps to itself there, so its low 32 bits (0) are kept, as here. A
    value that wraps past the sanitiser's band is replaced by the sanitiser (when the release
    has one), said in a warning.
    """
    wrapped = to_int32(value)
    if wrapped != value:
        in_band = wrapped < 0 if default < 0 else wrapped >= 0
        fixed = wrapped if in_band or not sanitized else default
        reader.warn(
            f"{name} {value} is outside int32: upstream keeps {wrapped}; using {fixed}",
            parameter=name,
        )
    return wrapped


def _auto_confirm_ns(seconds: float) -> int:
    """The window in nanoseconds; a positive one below half a nanosecond stays on.

    Upstream switches the check on for any value > 0 and compares ages (whole nanoseconds)
    with ``seconds * 1e9``: a fault aged 1 ns or more is due, as with a 1 ns window here.
    """
    window = round(seconds * NS_PER_SEC)
    return max(window, 1) if seconds > 0 else window


def _storage_type(reader: ParameterReader) -> str:
    """``storage_type`` as upstream's node takes it: an unknown name falls back to memory."""
    name = reader.string("storage_type", DEFAULT_STORAGE_TYPE)
    if name in STORAGE_TYPES:
        return name
    reader.warn(
        f"storage_type {name!r} is unknown; using 'memory' (upstream falls back to it)",
        parameter="storage_type",
    )
    return "memory"


def _build(params: NodeParams, release: Release) -> tuple[FaultManagerConfig, list[str]]:
    reader = ParameterReader("fault_manager", values(params))
    warnings = reader.warnings
    sanitized = release.sanitize_thresholds
    conf = reader.integer("confirmation_threshold", -1)
    if conf > 0:
        conf = reader.replaced(
            "confirmation_threshold",
            f"confirmation_threshold {conf} is positive; using {-conf} (upstream negates it)",
            -conf,
        )
    in_int32 = to_int32(conf) == conf
    conf = _int32(reader, "confirmation_threshold", conf, -1, sanitized=sanitized)
    heal = reader.integer("healing_threshold", 3)
    if heal < 0:
        heal = reader.replaced(
            "healing_threshold",
            f"healing_threshold {heal} is negative; using {-heal} (upstream negates it)",
            -heal,
        )
    heal = _int32(reader, "healing_threshold", heal, 3, sanitized=sanitized)
    auto_sec = reader.double("auto_confirm_after_sec", 0.0)
    if auto_sec < 0:
        auto_sec = reader.replaced(
            "auto_confirm_after_sec",
            f"auto_confirm_after_sec {auto_sec} is negative; using 0.0",
            0.0,
        )
    elif math.isnan(auto_sec):
        # Upstream keeps NaN, and its timer starts only when the value is > 0: never.
        auto_sec = reader.replaced(
            "auto_confirm_after_sec", "auto_confirm_after_sec nan is not a number; using 0.0", 0.0
        )
    elif auto_sec * NS_PER_SEC > INT64_MAX:
        # Upstream turns the seconds into an int64-nanosecond duration: inf or a value past
        # ~292 years is undefined there. Nothing that old exists in a recording (whose times
        # are int64 nanoseconds), so the closest behaviour that is defined is: never fires.
        # Said where it was written: a value that looks like "wait a long time" but turns the
        # feature off is easy to miss in a layered config.
        reader.warn(
            f"auto_confirm_after_sec {auto_sec} is beyond int64 nanoseconds (292 years): "
            "time-based confirmation can never fire (upstream accepts it and never "
            "auto-confirms); using 0.0 (off)",
            parameter="auto_confirm_after_sec",
            shown_at=True,
        )
        auto_sec = 0.0
    # A release without near misses does not declare the parameter: a value is ignored.
    near_miss = (
        reader.integer("near_miss.max_per_fault", DEFAULT_NEAR_MISS_BOUND)
        if release.near_misses
        else DEFAULT_NEAR_MISS_BOUND
    )
    if near_miss < 0:
        near_miss = reader.replaced(
            "near_miss.max_per_fault",
            f"near_miss.max_per_fault {near_miss} is negative; using {DEFAULT_NEAR_MISS_BOUND}",
            DEFAULT_NEAR_MISS_BOUND,
        )
    storage_type = _storage_type(reader)  # upstream creates its storage here
    debounce = DebounceConfig(
        confirmation_threshold=conf,
        healing_enabled=reader.boolean("healing_enabled", False),
        healing_threshold=heal,
    )
    if conf == 0 and in_int32 and sanitized:
        reader.warn(
            "confirmation_threshold 0 is invalid; using -1", parameter="confirmation_threshold"
        )

    overrides: tuple[EntityOverride, ...] = ()
    entity_file = params.get("entity_thresholds.config_file")
    entity_path = reader.string("entity_thresholds.config_file", "")
    if entity_path and entity_file is not None:
        overrides, entity_warnings = load_entity_thresholds(entity_file.path.parent / entity_path)
        warnings.extend(entity_warnings)

    correlation = None
    cleanup_sec = DEFAULT_CLEANUP_INTERVAL_SEC
    corr_param = params.get("correlation.config_file")
    corr_path = reader.string("correlation.config_file", "")
    if corr_path and corr_param is not None:
        loaded = load_correlation(corr_param.path.parent / corr_path)
        warnings.extend(loaded.warnings)
        correlation = loaded.config
        if correlation is not None:
            # Declared only when an engine exists, as upstream does.
            cleanup_sec = reader.double(
                "correlation.cleanup_interval_sec", DEFAULT_CLEANUP_INTERVAL_SEC
            )
            if not cleanup_sec > 0:
                reader.warn(
                    f"correlation.cleanup_interval_sec {cleanup_sec} must be "
                    f"positive; using {DEFAULT_CLEANUP_INTERVAL_SEC}",
                    parameter="correlation.cleanup_interval_sec",
                )
                cleanup_sec = DEFAULT_CLEANUP_INTERVAL_SEC
            elif cleanup_sec * 1000 * NS_PER_MS > INT64_MAX:
                # rclcpp refuses a timer period past int64 nanoseconds (std::invalid_argument
                # at start-up; inf first overflows the int64 milliseconds cast): the node stops.
                raise ConfigError(
                    f"fault_manager parameter 'correlation.cleanup_interval_sec' is {cleanup_sec}: "
                    "a timer period must stay within int64 nanoseconds (292 years)",
                    parameter="correlation.cleanup_interval_sec",
                )
    # Upstream's wall timer period is int64(sec * 1000) milliseconds.
    cleanup_ms = max(int(cleanup_sec * 1000), 1)
    config = FaultManagerConfig(
        debounce=debounce,
        auto_confirm_after_ns=_auto_confirm_ns(auto_sec),
        near_miss_bound=near_miss,
        entity_overrides=tuple(overrides),
        correlation=correlation,
        cleanup_interval_ns=cleanup_ms * NS_PER_MS,
        release=release,
        storage_type=storage_type,
    )
    return config, warnings
