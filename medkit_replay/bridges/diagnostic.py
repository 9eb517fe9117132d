"""Diagnostics → faults: upstream's diagnostic_bridge replayed over DiagnosticArray messages.

Stateless per status; all debouncing is the per-source FaultReporter's LocalFilter.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol, cast

from medkit_replay.bridges.base import TopicBridge
from medkit_replay.bridges.codes import upper_snake
from medkit_replay.engine.local_filter import LocalFilterConfig
from medkit_replay.model import Severity

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence

    from medkit_replay.model import Origin, ReportSink

NODE_NAME = "diagnostic_bridge"
DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"
LEVEL_OK = 0
LEVEL_WARN = 1
LEVEL_ERROR = 2
LEVEL_STALE = 3
NAME_TO_CODE_PREFIX = "name_to_code."
_MAX_PLANS = 4096

Head = tuple[int, str, str, str]
"""A status as the bridge reads it without ``keyvalue_codes``: level, name, message, hardware_id."""
Plan = tuple[str, str, "int | None"]
"""What a head comes to: fault code (``""``: skipped), source_id, severity (None: PASSED)."""


class KeyValueLike(Protocol):
    """diagnostic_msgs/msg/KeyValue."""

    key: str
    value: str


class DiagnosticStatusLike(Protocol):
    """The fields of diagnostic_msgs/msg/DiagnosticStatus the bridge reads."""

    level: int
    name: str
    message: str
    hardware_id: str
    values: Sequence[KeyValueLike]


class DiagnosticArrayLike(Protocol):
    """diagnostic_msgs/msg/DiagnosticArray as the bridge reads it."""

    status: Sequence[DiagnosticStatusLike]


@dataclass(frozen=True, slots=True, kw_only=True)
class DiagnosticBridgeConfig:
    """The node's parameters after upstream's load-time checks (bridges.md §2.5)."""

    diagnostics_topic: str = "/diagnostics"
    auto_generate_codes: bool = True
    use_hardware_id_as_source_id: bool = False
    max_tracked_sources: int = 512
    keyvalue_codes: tuple[str, ...] = ()
    name_to_code: Mapping[str, str] = field(default_factory=dict)
    local_filter: LocalFilterConfig = field(default_factory=LocalFilterConfig)


def map_to_severity(level: int) -> int | None:
    """Fault severity of a non-OK level (STALE is CRITICAL, unknown is ERROR); None for OK."""
    if level == LEVEL_OK:
        return None
    if level == LEVEL_WARN:
        return int(Severity.WARN)
    if level == LEVEL_STALE:
        return int(Severity.CRITICAL)
    return int(Severity.ERROR)


def is_ok_level(level: int) -> bool:
    """OK statuses heal (PASSED); every other level fails."""
    return level == LEVEL_OK


class DiagnosticBridge(TopicBridge):
    """Mirrors upstream node ``diagnostic_bridge`` (ros2_medkit 0.6.0 @ 505bc2d5, bridges.md §2).

    Each DiagnosticStatus of each array, in order, is mapped to a code and a source and goes
    through that source's FaultReporter. Reporters live in an LRU of ``max_tracked_sources``.
    ``node_fqn`` is the node's fully qualified name: the default source_id and the base for a
    relative ``diagnostics_topic``.
    """

    name = NODE_NAME
    origin: Origin = "diagnostic_bridge"

    def __init__(
        self, config: DiagnosticBridgeConfig | None = None, *, node_fqn: str = "/" + NODE_NAME
    ) -> None:
        self.config = config or DiagnosticBridgeConfig()
        super().__init__(
            node_fqn,
            self.config.diagnostics_topic,
            self.config.max_tracked_sources,
            self.config.local_filter,
        )
        self._plans: dict[Head, Plan] = {}

    def wants(self, topic: str, msgtype: str) -> bool:
        """The configured diagnostics topic, when it carries DiagnosticArray."""
        return msgtype == DIAGNOSTIC_ARRAY and topic == self.topic

    def map_to_fault_code(self, status: DiagnosticStatusLike) -> str:
        """The status's code; ``""`` (skip it) when nothing applies (bridges.md §2.3).

        ``name_to_code`` first, then the first configured key present, then the folded name.
        """
        return self._code(status.name, status.values)

    def source_id_for(self, status: DiagnosticStatusLike) -> str:
        """The bridge's FQN, or a hardware_id holding a ``/`` when that option is on."""
        return self._source(status.hardware_id)

    def feed(self, t_ns: int, topic: str, msg: object, report: ReportSink) -> None:
        """Every status of the array through its reporter, in array order.

        Without ``keyvalue_codes`` a status's code, source and severity depend only on its
        level, name, message and hardware_id, so they are worked out once per distinct head
        (a light DiagnosticArray hands the heads over without building status objects).
        """
        reporters = self.reporters
        if self.config.keyvalue_codes:  # codes depend on the values: no plans
            for status in cast("DiagnosticArrayLike", msg).status:
                code = self._code(status.name, status.values)
                if code:
                    reporter = reporters.get(self._source(status.hardware_id))
                    severity = map_to_severity(status.level)
                    if severity is None:
                        reporter.report_passed(t_ns, topic, code, report)
                    else:
                        reporter.report(t_ns, topic, code, severity, status.message, report)
            return
        heads: list[Head] | None = getattr(msg, "heads", None)
        if heads is None:
            heads = [
                (s.level, s.name, s.message, s.hardware_id)
                for s in cast("DiagnosticArrayLike", msg).status
            ]
        plans = self._plans
        for head in heads:
            plan = plans.get(head)
            if plan is None:
                level, name, _message, hardware_id = head
                plan = (self._code(name, ()), self._source(hardware_id), map_to_severity(level))
                if len(plans) >= _MAX_PLANS:
                    plans.clear()
                plans[head] = plan
            code, source_id, severity = plan
            if code:
                if severity is None:
                    reporters.get(source_id).report_passed(t_ns, topic, code, report)
                else:
                    reporters.get(source_id).report(t_ns, topic, code, severity, head[2], report)

    def _code(self, name: str, values: Sequence[KeyValueLike]) -> str:
        mapped = self.config.name_to_code.get(name)
        if mapped is not None:
            return mapped
        for key in self.config.keyvalue_codes:
            for pair in values:
                if pair.key == key:
                    # Returned verbatim: an empty value skips the status, with no fallback (§2.3).
                    return pair.value
        if self.config.auto_generate_codes:
            return upper_snake(name)
        return ""

    def _source(self, hardware_id: str) -> str:
        if self.config.use_hardware_id_as_source_id and "/" in hardware_id:
            return hardware_id
        return self.node_fqn
