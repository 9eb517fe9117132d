"""The bridge nodes replayed offline: decoded ROS messages in, ReportFault requests out.

Pure and clock-free: every message carries its bag time; nothing here reads a bag or a file.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.bridges.action_status import ActionStatusBridge, ActionStatusBridgeConfig
from medkit_replay.bridges.base import Bridge, FaultReporter, ReporterCache
from medkit_replay.bridges.diagnostic import DiagnosticBridge, DiagnosticBridgeConfig
from medkit_replay.bridges.log import LogBridge, LogBridgeConfig

if TYPE_CHECKING:
    from collections.abc import Mapping

BRIDGES: Mapping[str, type[Bridge]] = {
    ActionStatusBridge.name: ActionStatusBridge,
    DiagnosticBridge.name: DiagnosticBridge,
    LogBridge.name: LogBridge,
}
"""Upstream node name → bridge class."""

__all__ = [
    "BRIDGES",
    "ActionStatusBridge",
    "ActionStatusBridgeConfig",
    "Bridge",
    "DiagnosticBridge",
    "DiagnosticBridgeConfig",
    "FaultReporter",
    "LogBridge",
    "LogBridgeConfig",
    "ReporterCache",
]
