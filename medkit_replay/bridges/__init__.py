"""The bridge nodes replayed offline: decoded ROS messages in, ReportFault requests out.

Pure and clock-free: every message carries its bag time; nothing here reads a bag or a file.
"""

from __future__ import annotations

from medkit_replay.bridges.action_status import ActionStatusBridge, ActionStatusBridgeConfig
from medkit_replay.bridges.base import Bridge, FaultReporter, ReporterCache
from medkit_replay.bridges.diagnostic import DiagnosticBridge, DiagnosticBridgeConfig
from medkit_replay.bridges.log import LogBridge, LogBridgeConfig

__all__ = [
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
