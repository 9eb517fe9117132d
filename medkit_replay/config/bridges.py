"""Bridge nodes' parameters read into their typed settings, with upstream's load-time checks.

The bridges take these settings; only this layer reads ROS parameters (bridges.md §1.5, §2.5, §3.3).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from medkit_replay.bridges.action_status import NODE_NAME as ACTION_NODE, ActionStatusBridgeConfig
from medkit_replay.bridges.codes import action_code_prefix, log_code_prefix
from medkit_replay.bridges.diagnostic import (
    NAME_TO_CODE_PREFIX,
    NODE_NAME as DIAGNOSTIC_NODE,
    DiagnosticBridgeConfig,
)
from medkit_replay.bridges.log import (
    DEFAULT_COOLDOWN_SEC,
    LEVEL_FATAL,
    LEVEL_WARN,
    NODE_NAME as LOG_NODE,
    LogBridgeConfig,
)
from medkit_replay.config.reader import INT32_MAX, ParameterReader
from medkit_replay.model import NS_PER_SEC

if TYPE_CHECKING:
    from collections.abc import Mapping


def diagnostic_bridge_config(
    params: Mapping[str, object],
) -> tuple[DiagnosticBridgeConfig, list[str]]:
    """Read ``diagnostic_bridge`` parameters; returns the config and start-up warnings."""
    read = ParameterReader(DIAGNOSTIC_NODE, params)
    topic = read.string("diagnostics_topic", "/diagnostics")
    auto_generate = read.boolean("auto_generate_codes", True)
    use_hardware_id = read.boolean("use_hardware_id_as_source_id", False)
    requested = read.integer("max_tracked_sources", 512)
    tracked = min(max(requested, 1), INT32_MAX)
    if tracked != requested:
        read.warn(f"max_tracked_sources={requested} clamped to {tracked}")
    keys = tuple(key for key in read.strings("keyvalue_codes") if key)
    # Upstream scans the raw overrides: string values only, anything else is passed over.
    mapping = {
        name[len(NAME_TO_CODE_PREFIX) :]: value
        for name, value in params.items()
        if name.startswith(NAME_TO_CODE_PREFIX) and isinstance(value, str)
    }
    config = DiagnosticBridgeConfig(
        diagnostics_topic=topic,
        auto_generate_codes=auto_generate,
        use_hardware_id_as_source_id=use_hardware_id,
        max_tracked_sources=tracked,
        keyvalue_codes=keys,
        name_to_code=mapping,
        local_filter=read.local_filter(),
    )
    return config, read.warnings


def action_status_bridge_config(
    params: Mapping[str, object],
) -> tuple[ActionStatusBridgeConfig, list[str]]:
    """Read ``action_status_bridge`` parameters; returns the config and start-up warnings."""
    read = ParameterReader(ACTION_NODE, params)
    severity = read.integer("aborted_severity", 2)
    if not 0 <= severity <= 3:
        read.warn(f"aborted_severity {severity} out of range [0,3]; clamping to ERROR")
        severity = 2
    canceled_is_fault = read.boolean("canceled_is_fault", False)
    heal_on_succeeded = read.boolean("heal_on_succeeded", True)
    rescan = read.double("rescan_period_sec", 2.0)
    if rescan <= 0.0:
        read.warn(f"rescan_period_sec {rescan:.3f} not positive; using 2.0")
        rescan = 2.0
    retry = read.double("retry_period_sec", 0.05)
    if retry <= 0.0:
        read.warn(f"retry_period_sec {retry:.3f} not positive; using 0.05")
        retry = 0.05
    prefix = action_code_prefix(read.string("code_prefix", "ACTION"))
    if not prefix:
        read.warn("code_prefix empty after normalization; using ACTION")
        prefix = "ACTION"
    exclude = read.strings("exclude_actions")
    include_only = read.strings("include_only_actions")
    capacity = read.integer("dedup_capacity", 4096)
    if not 0 < capacity <= INT32_MAX:
        read.warn(f"dedup_capacity {capacity} out of range; using 4096")
        capacity = 4096
    config = ActionStatusBridgeConfig(
        aborted_severity=severity,
        canceled_is_fault=canceled_is_fault,
        heal_on_succeeded=heal_on_succeeded,
        rescan_period_sec=rescan,
        retry_period_sec=retry,
        code_prefix=prefix,
        exclude_actions=exclude,
        include_only_actions=include_only,
        dedup_capacity=capacity,
        # The node pre-declares the filter off unless the user set it (§1.3).
        local_filter=read.local_filter(enabled_default=False),
    )
    return config, read.warnings


def log_bridge_config(params: Mapping[str, object]) -> tuple[LogBridgeConfig, list[str]]:
    """Read ``log_bridge`` parameters; returns the config and start-up warnings."""
    read = ParameterReader(LOG_NODE, params)
    topic = read.string("rosout_topic", "/rosout")
    floor = read.integer("severity_floor", LEVEL_WARN)
    if not 0 <= floor <= LEVEL_FATAL:
        read.warn(f"severity_floor={floor} out of range [0,{LEVEL_FATAL}], clamping")
        floor = min(max(floor, 0), LEVEL_FATAL)
    prefix = log_code_prefix(read.string("code_prefix", "LOG"))
    exclude = read.strings("exclude_nodes")
    include_only = read.strings("include_only_nodes")
    requested = read.integer("max_tracked_nodes", 512)
    tracked = min(max(requested, 1), INT32_MAX)
    if tracked != requested:
        read.warn(f"max_tracked_nodes {requested} clamped to {tracked}")
    cooldown = read.double("report_cooldown_sec", DEFAULT_COOLDOWN_SEC)
    if not math.isfinite(cooldown * NS_PER_SEC) or cooldown < 0.0:
        read.warn(
            f"report_cooldown_sec {cooldown:.2f} must be finite and >= 0. "
            f"Using default {DEFAULT_COOLDOWN_SEC}."
        )
        cooldown = DEFAULT_COOLDOWN_SEC
    config = LogBridgeConfig(
        rosout_topic=topic,
        severity_floor=floor,
        code_prefix=prefix,
        exclude_nodes=exclude,
        include_only_nodes=include_only,
        max_tracked_nodes=tracked,
        report_cooldown_sec=cooldown,
        exclude_medkit_stack=read.boolean("exclude_medkit_stack", True),
        local_filter=read.local_filter(),
    )
    return config, read.warnings
