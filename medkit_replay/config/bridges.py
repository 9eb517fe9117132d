"""Bridge nodes' parameters read into their typed settings, with upstream's load-time checks.

Read as the release modelled reads them (bridges.md §1.5, §2.5, §3.3; docs/releases.md): a
parameter a release does not declare is not read, and keeps the value that release behaves as.
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
    NODE_NAME as LOG_NODE,
    LogBridgeConfig,
)
from medkit_replay.config.reader import INT32_MAX, ParameterReader, to_int32
from medkit_replay.errors import ConfigError
from medkit_replay.model import LOG_LEVEL_WARN, NS_PER_SEC
from medkit_replay.releases import Release, default_release

if TYPE_CHECKING:
    from collections.abc import Mapping


def _integer(read: ParameterReader, release: Release, name: str, default: int) -> int:
    """An integer parameter as the release's node holds it before its range check: the int64
    itself, or that int64 narrowed to a 32-bit int (``declare_parameter<int>``)."""
    value = read.integer(name, default)
    return value if release.bridge_ints_read_as_int64 else to_int32(value)


def diagnostic_bridge_config(
    params: Mapping[str, object], release: Release | None = None
) -> tuple[DiagnosticBridgeConfig, list[str]]:
    """Read ``diagnostic_bridge`` parameters as ``release`` (the newest when None) does; returns
    the config and start-up warnings."""
    release = release or default_release()
    read = ParameterReader(DIAGNOSTIC_NODE, params)
    topic = read.string("diagnostics_topic", "/diagnostics")
    auto_generate = read.boolean("auto_generate_codes", True)
    # Without these parameters the node has one reporter named after itself: the same as
    # the flag off, whatever the bound.
    use_hardware_id, tracked = False, 512
    if release.diagnostic_hardware_id_sources:
        use_hardware_id = read.boolean("use_hardware_id_as_source_id", False)
        requested = read.integer("max_tracked_sources", 512)
        tracked = min(max(requested, 1), INT32_MAX)
        if tracked != requested:
            read.warn(
                f"max_tracked_sources={requested} clamped to {tracked}",
                parameter="max_tracked_sources",
            )
    keys: tuple[str, ...] = ()
    if release.diagnostic_keyvalue_codes:
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
    params: Mapping[str, object], release: Release | None = None
) -> tuple[ActionStatusBridgeConfig, list[str]]:
    """Read ``action_status_bridge`` parameters as ``release`` (the newest when None) does;
    returns the config and start-up warnings."""
    release = release or default_release()
    read = ParameterReader(ACTION_NODE, params)
    severity = _integer(read, release, "aborted_severity", 2)
    if not 0 <= severity <= 3:
        severity = read.replaced(
            "aborted_severity",
            f"aborted_severity {severity} out of range [0,3]; clamping to ERROR",
            2,
        )
    canceled_is_fault = read.boolean("canceled_is_fault", False)
    heal_on_succeeded = read.boolean("heal_on_succeeded", True)
    rescan = read.double("rescan_period_sec", 2.0)
    if rescan <= 0.0:
        rescan = read.replaced(
            "rescan_period_sec", f"rescan_period_sec {rescan:.3f} not positive; using 2.0", 2.0
        )
    retry = 0.05  # without the retry timer (0.6.0) the default stands, for the record
    if release.action_bridge_defers_delivery:
        retry = read.double("retry_period_sec", 0.05)
        if retry <= 0.0:
            retry = read.replaced(
                "retry_period_sec", f"retry_period_sec {retry:.3f} not positive; using 0.05", 0.05
            )
    prefix = action_code_prefix(read.string("code_prefix", "ACTION"))
    if not prefix:
        read.warn("code_prefix empty after normalization; using ACTION", parameter="code_prefix")
        prefix = "ACTION"
    exclude = read.strings("exclude_actions")
    include_only = read.strings("include_only_actions")
    capacity = _integer(read, release, "dedup_capacity", 4096)
    if not 0 < capacity <= INT32_MAX:  # a narrowed value can only fail by not being positive
        wrong = "out of range" if release.bridge_ints_read_as_int64 else "not positive"
        read.warn(f"dedup_capacity {capacity} {wrong}; using 4096", parameter="dedup_capacity")
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


def log_bridge_config(
    params: Mapping[str, object], release: Release | None = None
) -> tuple[LogBridgeConfig, list[str]]:
    """Read ``log_bridge`` parameters as ``release`` (the newest when None) does; returns the
    config and start-up warnings.

    Raises:
        ConfigError: besides a mistyped value, a ``report_cooldown_sec`` that is NaN, infinite
            or too large for nanoseconds where the release has no check for it (its node would
            run with an undefined window).
    """
    release = release or default_release()
    read = ParameterReader(LOG_NODE, params)
    topic = read.string("rosout_topic", "/rosout")
    floor = _integer(read, release, "severity_floor", LOG_LEVEL_WARN)
    if not 0 <= floor <= LEVEL_FATAL:
        floor = read.replaced(
            "severity_floor",
            f"severity_floor={floor} out of range [0,{LEVEL_FATAL}], clamping",
            min(max(floor, 0), LEVEL_FATAL),
        )
    prefix = log_code_prefix(read.string("code_prefix", "LOG"))
    exclude = read.strings("exclude_nodes")
    include_only = read.strings("include_only_nodes")
    requested = _integer(read, release, "max_tracked_nodes", 512)
    tracked = min(max(requested, 1), INT32_MAX)
    if tracked != requested and release.log_bridge_checks_coercions:
        read.warn(
            f"max_tracked_nodes {requested} clamped to {tracked}", parameter="max_tracked_nodes"
        )
    cooldown = read.double("report_cooldown_sec", DEFAULT_COOLDOWN_SEC)
    if release.log_bridge_checks_coercions:
        if not math.isfinite(cooldown * NS_PER_SEC) or cooldown < 0.0:
            read.warn(
                f"report_cooldown_sec {cooldown:.2f} must be finite and >= 0. "
                f"Using default {DEFAULT_COOLDOWN_SEC}.",
                parameter="report_cooldown_sec",
            )
            cooldown = DEFAULT_COOLDOWN_SEC
    elif cooldown < 0.0:
        cooldown = 0.0  # which turns the cooldown off
    elif not math.isfinite(cooldown * NS_PER_SEC):
        # NaN and +inf pass "negative -> 0" and "<= 0 is off" alike into an undefined
        # nanosecond conversion: whether the node suppresses everything or nothing depends on
        # its CPU, so there is no behaviour to model.
        problem = (
            f"{LOG_NODE} parameter 'report_cooldown_sec' must be a finite double of seconds, "
            f"got {cooldown!r} (ros2_medkit {release.name} turns it into an undefined window)"
        )
        raise ConfigError(problem, parameter="report_cooldown_sec")
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
