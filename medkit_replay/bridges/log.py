"""/rosout → faults: upstream's log_bridge replayed over rcl_interfaces/msg/Log messages.

Raise-only: a log line never heals anything, so the bridge sends FAILED requests alone.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol, cast

from medkit_replay.bridges.base import (
    TopicBridge,
    any_substring,
    passes_lists,
    withheld_listener,
)
from medkit_replay.bridges.codes import log_fault_code
from medkit_replay.engine.local_filter import LocalFilterConfig
from medkit_replay.model import LOG_LEVEL_WARN, NS_PER_SEC, Severity

if TYPE_CHECKING:
    from medkit_replay.model import Origin, ReportSink

NODE_NAME = "log_bridge"
LOG_TYPE = "rcl_interfaces/msg/Log"
LEVEL_INFO = 20
LEVEL_ERROR = 40
LEVEL_FATAL = 50
MEDKIT_STACK_LOGGERS = (
    "fault_manager",
    "ros2_medkit_gateway",
    "diagnostic_bridge",
    "action_status_bridge",
)
DEFAULT_COOLDOWN_SEC = 5.0


class LogLike(Protocol):
    """The fields of rcl_interfaces/msg/Log the bridge reads."""

    level: int
    name: str
    msg: str


@dataclass(frozen=True, slots=True, kw_only=True)
class LogBridgeConfig:
    """The node's parameters after upstream's load-time checks (bridges.md §3.3)."""

    rosout_topic: str = "/rosout"
    severity_floor: int = LOG_LEVEL_WARN
    code_prefix: str = "LOG"
    exclude_nodes: tuple[str, ...] = ()
    include_only_nodes: tuple[str, ...] = ()
    max_tracked_nodes: int = 512
    report_cooldown_sec: float = DEFAULT_COOLDOWN_SEC
    exclude_medkit_stack: bool = True
    local_filter: LocalFilterConfig = field(default_factory=LocalFilterConfig)


def node_source_id(log_name: str) -> str:
    """The logging node's FQN: the logger name up to its first ``.``, with a leading ``/``.

    A namespaced node logs as ``ns.node`` and so collapses to ``/ns``, as upstream documents.
    """
    node = log_name.split(".", 1)[0] or log_name
    return node if node.startswith("/") else "/" + node


def is_medkit_stack_logger(log_name: str) -> bool:
    """Whether a raw logger name belongs to medkit's own nodes (substring match)."""
    return any_substring(MEDKIT_STACK_LOGGERS, log_name)


def map_level_to_severity(level: int, severity_floor: int) -> int | None:
    """Fault severity of a log level, or None when it is dropped.

    DEBUG and INFO never pass whatever the floor; a non-standard level above INFO is ERROR.
    """
    if level < severity_floor or level <= LEVEL_INFO:
        return None
    if level == LOG_LEVEL_WARN:
        return int(Severity.WARN)
    if level == LEVEL_FATAL:
        return int(Severity.CRITICAL)
    return int(Severity.ERROR)


class LogBridge(TopicBridge):
    """Mirrors upstream node ``log_bridge`` (ros2_medkit 0.6.0 @ 505bc2d5, bridges.md §3).

    Each Log message at or above the floor becomes a FAILED report from the logging node, coded
    ``<PREFIX>_<NODE>_<hash of the message template>``. ERROR and FATAL repeats of one code are
    cooled down per (code, severity) on bag time; WARN is left to the node's LocalFilter.
    ``node_fqn`` is this bridge's own name (its logs are never promoted) and the base for a
    relative ``rosout_topic``.
    """

    name = NODE_NAME
    origin: Origin = "log_bridge"

    def __init__(
        self, config: LogBridgeConfig | None = None, *, node_fqn: str = "/" + NODE_NAME
    ) -> None:
        self.config = config or LogBridgeConfig()
        super().__init__(
            node_fqn,
            self.config.rosout_topic,
            self.config.max_tracked_nodes,
            self.config.local_filter,
        )
        # rclcpp::Duration::from_seconds truncates toward zero.
        self._cooldown_ns = int(self.config.report_cooldown_sec * NS_PER_SEC)
        self._last_forward: dict[tuple[str, int], int] = {}

    def wants(self, topic: str, msgtype: str) -> bool:
        """The configured rosout topic, when it carries rcl_interfaces/msg/Log."""
        return msgtype == LOG_TYPE and topic == self.topic

    def node_is_eligible(self, source_id: str) -> bool:
        """``include_only_nodes`` then ``exclude_nodes``, as unanchored substrings of the FQN."""
        cfg = self.config
        return passes_lists(cfg.include_only_nodes, cfg.exclude_nodes, source_id)

    def fault_code(self, source_id: str, message: str) -> str:
        """The code a message from ``source_id`` is reported under."""
        return log_fault_code(self.config.code_prefix, source_id, message)

    def cooldown_allows(self, fault_code: str, severity: int, t_ns: int) -> bool:
        """False while this (code, severity) was forwarded less than the cooldown ago."""
        if self._cooldown_ns <= 0:
            return True
        key = (fault_code, severity)
        last = self._last_forward.get(key)
        if last is not None and t_ns - last < self._cooldown_ns:
            return False
        self._last_forward[key] = t_ns
        return True

    def feed(self, t_ns: int, topic: str, msg: object, report: ReportSink) -> None:
        """One log line through upstream's pipeline (bridges.md §3.1), in its order.

        The level is looked at first: the checks upstream runs before it change no state, so
        a line below the floor is dropped at once, whatever its node.
        """
        log = cast("LogLike", msg)
        severity = map_level_to_severity(log.level, self.config.severity_floor)
        if severity is None:
            return
        source_id = node_source_id(log.name)
        if source_id in (self.node_fqn, "/" + NODE_NAME):
            return
        if self.config.exclude_medkit_stack and is_medkit_stack_logger(log.name):
            return
        if not self.node_is_eligible(source_id):
            return
        code = self.fault_code(source_id, log.msg)
        if severity >= Severity.ERROR and not self.cooldown_allows(code, severity, t_ns):
            listener = withheld_listener(report)
            if listener is not None:
                last = self._last_forward[(code, severity)]
                reason = (
                    f"the log bridge's cooldown held it: the same code at this severity was "
                    f"forwarded {(t_ns - last) / NS_PER_SEC:.3f} s before "
                    f"(report_cooldown_sec {self.config.report_cooldown_sec:g})"
                )
                listener.withheld(
                    "cooldown", reason, t_ns, self.origin, topic, code, 0, severity, log.msg,
                    source_id,
                )  # fmt: skip
            return
        self.reporters.get(source_id).report(t_ns, topic, code, severity, log.msg, report)
