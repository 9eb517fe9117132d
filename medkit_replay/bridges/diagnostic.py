"""Diagnostics → faults: upstream's diagnostic_bridge replayed over DiagnosticArray messages.

Stateless per status; all debouncing is the per-source FaultReporter's LocalFilter.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol, Self, cast

from medkit_replay.bridges.base import ReporterCache, forward, resolve_topic
from medkit_replay.bridges.codes import upper_snake
from medkit_replay.engine.local_filter import LocalFilterConfig
from medkit_replay.model import Severity
from medkit_replay.parameters import INT32_MAX, ParameterReader

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence

    from medkit_replay.bridges.base import ReportSink
    from medkit_replay.model import Origin, ReportRequest

NODE_NAME = "diagnostic_bridge"
DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"
LEVEL_OK = 0
LEVEL_WARN = 1
LEVEL_ERROR = 2
LEVEL_STALE = 3
_NAME_TO_CODE = "name_to_code."
_MAX_PLANS = 4096

Head = tuple[int, str, str, str]
"""A status as the bridge reads it without ``keyvalue_codes``: level, name, message, hardware_id."""
Plan = tuple[str, str, "int | None", str]
"""What a head comes to: fault code (``""``: skipped), source_id, severity (None: PASSED), text."""


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

    @classmethod
    def from_parameters(cls, params: Mapping[str, object]) -> tuple[Self, list[str]]:
        """Read ``diagnostic_bridge`` parameters; returns the config and start-up warnings."""
        read = ParameterReader(NODE_NAME, params)
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
            name[len(_NAME_TO_CODE) :]: value
            for name, value in params.items()
            if name.startswith(_NAME_TO_CODE) and isinstance(value, str)
        }
        config = cls(
            diagnostics_topic=topic,
            auto_generate_codes=auto_generate,
            use_hardware_id_as_source_id=use_hardware_id,
            max_tracked_sources=tracked,
            keyvalue_codes=keys,
            name_to_code=mapping,
            local_filter=read.local_filter(),
        )
        return config, read.warnings


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


class DiagnosticBridge:
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
        self.node_fqn = node_fqn
        self.topic = resolve_topic(self.config.diagnostics_topic, node_fqn)
        self.reporters = ReporterCache(
            self.config.max_tracked_sources, self.config.local_filter, origin=self.origin
        )
        self._plans: dict[Head, Plan] = {}

    def wants(self, topic: str, msgtype: str) -> bool:
        """The configured diagnostics topic, when it carries DiagnosticArray."""
        return msgtype == DIAGNOSTIC_ARRAY and topic == self.topic

    def map_to_fault_code(self, status: DiagnosticStatusLike) -> str:
        """The status's code; ``""`` (skip it) when nothing applies (bridges.md §2.3).

        ``name_to_code`` first, then the first configured key present, then the folded name.
        """
        mapped = self.config.name_to_code.get(status.name)
        if mapped is not None:
            return mapped
        for key in self.config.keyvalue_codes:
            for pair in status.values:
                if pair.key == key:
                    # Returned verbatim: an empty value skips the status, with no fallback (§2.3).
                    return pair.value
        if self.config.auto_generate_codes:
            return upper_snake(status.name)
        return ""

    def source_id_for(self, status: DiagnosticStatusLike) -> str:
        """The bridge's FQN, or a hardware_id holding a ``/`` when that option is on."""
        hardware_id = status.hardware_id
        if self.config.use_hardware_id_as_source_id and "/" in hardware_id:
            return hardware_id
        return self.node_fqn

    def on_message(self, t_ns: int, topic: str, msg: object) -> list[ReportRequest]:
        """Every status of the array through its reporter, in array order."""
        out: list[ReportRequest] = []
        for status in cast("DiagnosticArrayLike", msg).status:
            code = self.map_to_fault_code(status)
            if not code:
                continue
            reporter = self.reporters.get(self.source_id_for(status))
            severity = map_to_severity(status.level)
            if severity is None:
                report = reporter.report_passed(t_ns, topic, code)
            else:
                report = reporter.report(t_ns, topic, code, severity, status.message)
            if report is not None:
                out.append(report)
        return out

    def feed(self, t_ns: int, topic: str, msg: object, report: ReportSink) -> None:
        """:meth:`on_message` for the replay's hot path: no request objects, one plan per head.

        Without ``keyvalue_codes`` a status's code, source and severity depend only on its
        level, name, message and hardware_id, so they are worked out once per distinct head
        (a light DiagnosticArray hands the heads over without building status objects).
        """
        if self.config.keyvalue_codes:
            forward(self.on_message(t_ns, topic, msg), report)
            return
        heads: list[Head] | None = getattr(msg, "heads", None)
        if heads is None:
            heads = [
                (s.level, s.name, s.message, s.hardware_id)
                for s in cast("DiagnosticArrayLike", msg).status
            ]
        plans, reporters, origin = self._plans, self.reporters, self.origin
        for head in heads:
            plan = plans.get(head)
            if plan is None:
                plan = self._plan(head)
                if len(plans) >= _MAX_PLANS:
                    plans.clear()
                plans[head] = plan
            code, source_id, severity, message = plan
            if not code:
                continue
            local_filter = reporters.get(source_id).local_filter
            if severity is None:
                if local_filter.should_forward_passed(code, t_ns):
                    report(t_ns, origin, topic, code, 1, 0, "", source_id)
            elif local_filter.should_forward(code, severity, t_ns):
                report(t_ns, origin, topic, code, 0, severity, message, source_id)

    def _plan(self, head: Head) -> Plan:
        level, name, message, hardware_id = head
        code = self.config.name_to_code.get(name)
        if code is None:
            code = upper_snake(name) if self.config.auto_generate_codes else ""
        source_id = (
            hardware_id
            if self.config.use_hardware_id_as_source_id and "/" in hardware_id
            else self.node_fqn
        )
        return code, source_id, map_to_severity(level), message
