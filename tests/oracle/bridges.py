"""The diagnostic and log bridges' per-message rules written plainly, status by status.

Oracles for the bridges' ``feed`` (which plans per distinct status head and checks the level
first): each drives a bridge's own reporters, so its local filters count as the node's would.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, cast

from medkit_replay.bridges.diagnostic import map_to_severity
from medkit_replay.bridges.log import (
    NODE_NAME as LOG_NODE,
    is_medkit_stack_logger,
    map_level_to_severity,
    node_source_id,
)
from medkit_replay.model import Severity

if TYPE_CHECKING:
    from medkit_replay.bridges.diagnostic import DiagnosticArrayLike, DiagnosticBridge
    from medkit_replay.bridges.log import LogBridge, LogLike

Fields = tuple[object, ...]
"""A request as the manager takes it: t_ns, origin, topic, code, event, severity, text, source."""


def oracle_diagnostic(bridge: DiagnosticBridge, t_ns: int, topic: str, msg: object) -> list[Fields]:
    """Every status of the array, in order: code, source, then its reporter's filter."""
    out: list[Fields] = []
    for status in cast("DiagnosticArrayLike", msg).status:
        code = bridge.map_to_fault_code(status)
        if not code:
            continue
        reporter = bridge.reporters.get(bridge.source_id_for(status))
        severity = map_to_severity(status.level)
        source = reporter.source_id
        if severity is None:
            if reporter.local_filter.should_forward_passed(code, t_ns):
                out.append((t_ns, bridge.origin, topic, code, 1, 0, "", source))
        elif reporter.local_filter.should_forward(code, severity, t_ns):
            out.append((t_ns, bridge.origin, topic, code, 0, severity, status.message, source))
    return out


def oracle_log(bridge: LogBridge, t_ns: int, topic: str, msg: object) -> list[Fields]:
    """One log line in upstream's order: node, stack, lists, level, code, cooldown, filter."""
    log = cast("LogLike", msg)
    source_id = node_source_id(log.name)
    if source_id in (bridge.node_fqn, "/" + LOG_NODE):
        return []
    if bridge.config.exclude_medkit_stack and is_medkit_stack_logger(log.name):
        return []
    if not bridge.node_is_eligible(source_id):
        return []
    severity = map_level_to_severity(log.level, bridge.config.severity_floor)
    if severity is None:
        return []
    code = bridge.fault_code(source_id, log.msg)
    if severity >= Severity.ERROR and not bridge.cooldown_allows(code, severity, t_ns):
        return []
    reporter = bridge.reporters.get(source_id)
    if not code or not reporter.local_filter.should_forward(code, severity, t_ns):
        return []
    return [(t_ns, bridge.origin, topic, code, 0, severity, log.msg, source_id)]
