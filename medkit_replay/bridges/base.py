"""What every bridge shares: the Bridge protocol and the FaultReporter each bridge reports through.

The reporter mirrors ros2_medkit_fault_reporter (bridges.md §0): empty codes dropped, then filtered.
"""

from __future__ import annotations

from collections import OrderedDict
from typing import TYPE_CHECKING, Protocol, cast

from medkit_replay.engine.local_filter import LocalFilter, LocalFilterConfig
from medkit_replay.model import EventType, ReportRequest

if TYPE_CHECKING:
    from collections.abc import Iterable

    from medkit_replay.model import Origin, ReportFields, ReportSink


_FAILED, _PASSED = int(EventType.FAILED), int(EventType.PASSED)


class WithheldSink(Protocol):
    """A ReportSink that also takes the requests a bridge held back, and why (``explain``).

    Plain sinks have no ``withheld``: a bridge tells it only to a sink that has one
    (:func:`withheld_listener`).
    """

    def withheld(self, stage: str, reason: str, *request: *ReportFields) -> None:
        """Note one request that did not reach the manager (``stage``: what held it)."""


def withheld_listener(sink: ReportSink) -> WithheldSink | None:
    """``sink`` when it listens for held-back requests (most do not: then there is nothing to
    tell, and nothing to word)."""
    return cast("WithheldSink", sink) if getattr(sink, "withheld", None) is not None else None


class Bridge(Protocol):
    """A live bridge node replayed offline: decoded messages in, ReportFault requests out."""

    @property
    def name(self) -> str:
        """Upstream node name (``diagnostic_bridge``, ``action_status_bridge``, ``log_bridge``)."""
        ...

    @property
    def origin(self) -> Origin:
        """The ``origin`` stamped on every request this bridge emits."""
        ...

    def wants(self, topic: str, msgtype: str) -> bool:
        """Whether the live node would subscribe to this topic of this type."""
        ...

    def feed(self, t_ns: int, topic: str, msg: object, report: ReportSink) -> None:
        """Feed one message (received at bag time ``t_ns``); hand each request the node would
        send to ``report``, in order."""
        ...


class RequestList(list[ReportRequest]):
    """A ReportSink that keeps the requests as objects, for callers that want a list."""

    def __call__(self, *request: *ReportFields) -> None:
        self.append(ReportRequest.of(*request))


class MessageBridge:
    """Base of the bridges: :meth:`on_message` as a list, over each bridge's one ``feed``."""

    def feed(self, t_ns: int, topic: str, msg: object, report: ReportSink) -> None:
        """Feed one message; each request goes to ``report``."""
        raise NotImplementedError

    def on_message(self, t_ns: int, topic: str, msg: object) -> list[ReportRequest]:
        """Feed one message; the requests the node would send, in order."""
        requests = RequestList()
        self.feed(t_ns, topic, msg, requests)
        return requests


class TopicBridge(MessageBridge):
    """A bridge node that subscribes to one topic named relative to itself and reports through
    one FaultReporter per source, the least recently used dropped beyond ``capacity`` (the
    diagnostic and log bridges)."""

    origin: Origin

    def __init__(
        self, node_fqn: str, topic: str, capacity: int, filter_config: LocalFilterConfig
    ) -> None:
        self.node_fqn = node_fqn
        self.topic = resolve_topic(topic, node_fqn)
        self.reporters = ReporterCache(capacity, filter_config, origin=self.origin)


class FaultReporter:
    """One upstream FaultReporter: a fixed source_id and its own LocalFilter.

    The manager's service is taken as always ready (bridges.md §10.2); the action bridge models
    outages itself before calling in, as upstream gates on ``is_service_ready()``.
    """

    def __init__(
        self,
        source_id: str,
        filter_config: LocalFilterConfig,
        *,
        origin: Origin,
    ) -> None:
        self.source_id = source_id
        self.origin: Origin = origin
        self.local_filter = LocalFilter(filter_config)

    def report(
        self,
        t_ns: int,
        topic: str,
        fault_code: str,
        severity: int,
        description: str,
        sink: ReportSink,
    ) -> None:
        """Send a FAILED request unless the code is empty or the local filter holds it."""
        if not fault_code:
            return
        if self.local_filter.should_forward(fault_code, severity, t_ns):
            sink(
                t_ns, self.origin, topic, fault_code, _FAILED, severity, description,
                self.source_id,
            )  # fmt: skip
        else:
            self._held(sink, t_ns, topic, fault_code, _FAILED, severity, description)

    def report_passed(self, t_ns: int, topic: str, fault_code: str, sink: ReportSink) -> None:
        """Send a PASSED request (severity 0, no description) unless held back."""
        if not fault_code:
            return
        if self.local_filter.should_forward_passed(fault_code, t_ns):
            sink(t_ns, self.origin, topic, fault_code, _PASSED, 0, "", self.source_id)
        else:
            self._held(sink, t_ns, topic, fault_code, _PASSED, 0, "")

    def _held(
        self,
        sink: ReportSink,
        t_ns: int,
        topic: str,
        fault_code: str,
        event_type: int,
        severity: int,
        description: str,
    ) -> None:
        listener = withheld_listener(sink)
        if listener is None:
            return
        config = self.local_filter.config
        passed = event_type == _PASSED
        seen = self.local_filter.tracked(fault_code, passed=passed)
        reason = (
            f"the {self.source_id} reporter's local filter held it: {seen} of "
            f"{config.default_threshold} {'PASSED' if passed else 'FAILED'} report(s) within "
            f"{config.default_window_sec:g} s"
        )
        listener.withheld(
            "local_filter", reason,
            t_ns, self.origin, topic, fault_code, event_type, severity, description, self.source_id,
        )  # fmt: skip


class ReporterCache:
    """Reporters keyed by source_id, least recently used evicted beyond ``capacity``.

    An evicted reporter's filter counts are lost; a later lookup builds a fresh one (§2.4).
    """

    def __init__(self, capacity: int, filter_config: LocalFilterConfig, *, origin: Origin) -> None:
        self.capacity = max(capacity, 1)
        self._filter_config = filter_config
        self._origin: Origin = origin
        self._reporters: OrderedDict[str, FaultReporter] = OrderedDict()
        self._last: tuple[str, FaultReporter] | None = None  # the most recently used

    def __len__(self) -> int:
        return len(self._reporters)

    def __contains__(self, source_id: object) -> bool:
        return source_id in self._reporters

    def get(self, source_id: str) -> FaultReporter:
        """The reporter for ``source_id``, created on first use; a lookup refreshes its recency."""
        last = self._last
        if last is not None and last[0] == source_id:
            return last[1]  # already the most recent: refreshing it changes nothing
        reporter = self._reporters.get(source_id)
        if reporter is not None:
            self._reporters.move_to_end(source_id)
        else:
            reporter = FaultReporter(source_id, self._filter_config, origin=self._origin)
            self._reporters[source_id] = reporter
            if len(self._reporters) > self.capacity:
                self._reporters.popitem(last=False)  # never the one just added
        self._last = (source_id, reporter)
        return reporter


def any_substring(patterns: Iterable[str], text: str) -> bool:
    """True when a non-empty pattern occurs anywhere in ``text`` (empty patterns never match)."""
    return any(pattern and pattern in text for pattern in patterns)


def passes_lists(include_only: tuple[str, ...], exclude: tuple[str, ...], text: str) -> bool:
    """Upstream's include-only-then-exclude eligibility with unanchored substrings."""
    if include_only and not any_substring(include_only, text):
        return False
    return not any_substring(exclude, text)


def resolve_topic(name: str, node_fqn: str) -> str:
    """Expand a relative (``diagnostics``) or private (``~/x``) topic name as rcl would."""
    if name.startswith("/"):
        return name
    if name == "~" or name.startswith("~/"):
        return node_fqn + name[1:]
    namespace = node_fqn.rsplit("/", 1)[0] or "/"
    return f"{namespace.rstrip('/')}/{name}"
