"""The replay's own options (node ``medkit_replay``) and the bridge nodes' configs.

Each bridge reads its node's parameters with upstream's defaults; errors get file and line.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from medkit_replay.bridges.action_status import ActionStatusBridgeConfig
from medkit_replay.bridges.diagnostic import DiagnosticBridgeConfig
from medkit_replay.bridges.log import LogBridgeConfig
from medkit_replay.config.bridges import (
    action_status_bridge_config,
    diagnostic_bridge_config,
    log_bridge_config,
)
from medkit_replay.config.nodes import located, located_warnings, values
from medkit_replay.config.reader import ParameterReader
from medkit_replay.config.unknown_keys import unknown_keys
from medkit_replay.errors import ConfigError
from medkit_replay.releases import Release, default_release

if TYPE_CHECKING:
    from medkit_replay.config.params import ParameterSet

_ACTION_SOURCES = "action_sources."


@dataclass(frozen=True, slots=True, kw_only=True)
class ReplayOptions:
    """Everything the pipeline needs besides the fault manager's own config.

    Attributes:
        log_bridge: replay /rosout through the log bridge (on when the config has a
            ``log_bridge`` section or ``medkit_replay.enable_log_bridge`` is true).
        action_sources: action name → action server node, the source_id the live action
            bridge would have found from the graph (a recording holds no node names).
    """

    log_bridge: bool = False
    action_sources: dict[str, str] = field(default_factory=dict)
    diagnostic: DiagnosticBridgeConfig = field(default_factory=DiagnosticBridgeConfig)
    action_status: ActionStatusBridgeConfig = field(default_factory=ActionStatusBridgeConfig)
    log: LogBridgeConfig = field(default_factory=LogBridgeConfig)
    release: Release = field(default_factory=default_release)
    """The upstream release modelled (``medkit_replay.upstream_release``)."""


def replay_options(
    params: ParameterSet, release: Release | None = None
) -> tuple[ReplayOptions, list[str]]:
    """Read ``medkit_replay`` and the three bridge nodes from the merged parameter files, for
    ``release`` (the newest when None); the warnings start with the names upstream ignores."""
    release = release or default_release()
    warnings: list[str] = list(unknown_keys(params, release))
    own = params.node("medkit_replay")

    def read_own() -> tuple[bool, dict[str, str]]:
        reader = ParameterReader("medkit_replay", values(own))
        enabled = reader.boolean("enable_log_bridge", False)
        sources: dict[str, str] = {}
        for name in sorted(own):
            if name.startswith(_ACTION_SOURCES):
                node = reader.string(name, "")
                action = name.removeprefix(_ACTION_SOURCES)
                if not node.startswith("/"):
                    problem = f"action_sources: {node!r} is not a node name (start it with /)"
                    raise ConfigError(problem, parameter=name)
                sources[action if action.startswith("/") else "/" + action] = node
        return enabled, sources

    log_enabled, action_sources = located(own, read_own)
    diag_params = params.node("diagnostic_bridge")
    diagnostic, diag_warnings = located(
        diag_params, lambda: diagnostic_bridge_config(values(diag_params), release)
    )
    action_params = params.node("action_status_bridge")
    action, action_warnings = located(
        action_params, lambda: action_status_bridge_config(values(action_params), release)
    )
    log_params = params.node("log_bridge")
    log, log_warnings = located(log_params, lambda: log_bridge_config(values(log_params), release))
    warnings += located_warnings(diag_params, diag_warnings)
    warnings += located_warnings(action_params, action_warnings)
    warnings += located_warnings(log_params, log_warnings)
    return (
        ReplayOptions(
            log_bridge=log_enabled or params.mentions("log_bridge"),
            action_sources=action_sources,
            diagnostic=diagnostic,
            action_status=action,
            log=log,
            release=release,
        ),
        warnings,
    )
