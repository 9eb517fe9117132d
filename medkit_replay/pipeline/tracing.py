"""Follows one fault code through the one replay and fills its FaultTrace (``explain``).

Only listens: it wraps the sinks records and requests already flow through, forwards everything
unchanged, and keeps what concerns the traced code; a replay without it is untouched.
"""

from __future__ import annotations

from dataclasses import fields
from typing import TYPE_CHECKING, Any, cast

from medkit_replay.bridges import provenance
from medkit_replay.inputs.script import SCRIPT_TYPE
from medkit_replay.model import (
    EVENT_ROWS,
    REPORT_ROWS,
    TRANSITION_ROWS,
    ClearRequest,
    EventType,
    ReportRequest,
)
from medkit_replay.trace import (
    CorrelationDecision,
    HeldRequest,
    RecordedMessage,
    RuleFacts,
    StateAt,
    TracedClear,
    TracedEvent,
    TracedReport,
    TracedTransition,
)

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator

    from medkit_replay.engine.correlation.engine import CorrelationResult
    from medkit_replay.engine.correlation.rules import CorrelationRule
    from medkit_replay.engine.manager import Row
    from medkit_replay.engine.timeline import Timeline
    from medkit_replay.inputs import Recording
    from medkit_replay.inputs.selection import Role
    from medkit_replay.model import FaultSnapshot, Origin, ReportFields, ReportSink
    from medkit_replay.pipeline.routing import Gate, Request, Router
    from medkit_replay.trace import FaultTrace

    MessageTuple = tuple[int, int, str, str, Role, object]
_EVENT_NAMES = {int(e): e.name for e in EventType}


_RENAMED = {"rule_id": "id"}  # RuleFacts' field -> the rule's attribute
_SHOWN = {"representative"}  # an enum on the rule, its value's text in the trace


def rule_facts(rule: CorrelationRule) -> RuleFacts:
    """A correlation rule's settings as the trace keeps them: every field of RuleFacts taken
    from the rule's attribute of that name (no list of them to keep here)."""
    values: dict[str, Any] = {}
    for field in fields(RuleFacts):
        value = getattr(rule, _RENAMED.get(field.name, field.name))
        values[field.name] = str(value.value) if field.name in _SHOWN else value
    return RuleFacts(**values)


class Tracer:
    """Fills ``trace`` from one replay: attach it to the manager before the gate is built,
    then to the gate, and let the loop read messages and send requests through it."""

    def __init__(self, trace: FaultTrace, timeline: Timeline, router: Router) -> None:
        self.trace = trace
        self.code = trace.fault_code
        self.timeline = timeline
        manager = self.manager = timeline.manager
        self.router = router
        self._current: MessageTuple | None = None
        self._seen: dict[str, int] = {}  # requests for the code per source in this message
        self._pending: RecordedMessage | None = None  # behind the request in flight
        self._call: ReportFields | None = None
        correlation = manager.config.correlation
        self._rules = {r.id: rule_facts(r) for r in correlation.rules} if correlation else {}
        report, event, transition = manager.report_row, manager.event_row, manager.transition_row
        manager.set_row_sinks(
            self._rows(report, 3, self._report),
            self._rows(event, 2, self._event, also_last=True),
            self._rows(transition, 1, self._transition),
        )
        manager.watch_correlation(self._decided)

    def attach(self, gate: Gate) -> None:
        """Listen for the requests the double-counting gate holds back."""
        gate.on_withheld = self._gate_withheld

    # -- the loop's side -------------------------------------------------------------------

    def messages(
        self, tuples: Iterator[MessageTuple], recording: Recording
    ) -> Iterator[MessageTuple]:
        """The recording's messages, noting each; takes the ``--at`` state on the way."""
        trace, timeline = self.trace, self.timeline
        last_ns: int | None = None
        for item in tuples:
            last_ns = item[0]
            if trace.origin_ns is None:
                declared = [s.start_ns for s in recording.inputs if s.start_ns is not None]
                trace.origin_ns = min([*declared, item[0]])
            at_ns = trace.at_ns
            if at_ns is not None and trace.state_at is None and item[0] > at_ns:
                if timeline.t0_ns is not None:
                    # The ticks due by then; the next message would run them anyway (same result).
                    timeline.advance(at_ns)
                self._take_state(at_ns)
            self._current = item
            self._seen.clear()
            yield item
        if trace.state_at is None:  # the state at the end: --at past it, or none asked
            at_ns = trace.at_ns if trace.at_ns is not None else last_ns
            if at_ns is not None:
                self._take_state(at_ns)

    def sink(self, inner: ReportSink) -> ReportSink:
        """The bridges' sink, noting the message behind each request for the code."""
        return _TracingSink(self, inner)

    def apply(self, inner: Callable[[Request], None]) -> Callable[[Request], None]:
        """The gate's ``apply`` (scripts, recorded service calls), noting clears and sources."""

        def apply(request: Request) -> None:
            code = self.code
            if isinstance(request, ReportRequest) and request.fault_code == code:
                self.requested(*request.as_fields())
            mark, clears = len(self.trace.items), self.manager.output.clears
            before = len(clears)
            inner(request)
            self.settled()
            if isinstance(request, ClearRequest) and len(clears) > before:
                record = clears[before]
                if record.fault_code == code or code in record.auto_cleared_codes:
                    self.trace.add(TracedClear(record=record), mark)

        return apply

    def requested(self, *request: *ReportFields) -> None:
        """A request for the traced code is on its way: note it and the message behind it."""
        self._call = request
        _, origin, *_, source_id = request
        nth = self._seen.get(source_id, 0)
        self._seen[source_id] = nth + 1
        self._pending = self._message(origin, source_id, nth)

    def _message(self, origin: Origin, source_id: str, nth: int) -> RecordedMessage | None:
        current = self._current
        if current is None:
            return None
        _, input_index, topic, msgtype, _, msg = current
        where = (input_index, topic)
        if origin == "diagnostic_bridge":
            return provenance.diagnostic_status(
                self.router.diagnostic, msg, where, self.code, source_id, nth
            )
        if origin == "action_status_bridge":
            return provenance.goal_statuses(msg, where)
        if origin == "log_bridge":
            return provenance.log_line(msg, where)
        if origin == "report_fault":
            return provenance.service_call(msg, msgtype, where)
        return RecordedMessage(input_index=input_index, topic=topic, type=SCRIPT_TYPE)

    def settled(self) -> None:
        """The request in flight has been handled (a report row or a hold took its message)."""
        self._pending = None

    def held(self, stage: str, reason: str, fault_code: str) -> None:
        """The request in flight (see :meth:`requested`) was held back by ``stage``."""
        call = self._call
        if call is None:
            return
        t_ns, origin, topic, _, event_type, severity, description, source_id = call
        self.trace.add(
            HeldRequest(
                t_ns=t_ns,
                origin=origin,
                topic=topic,
                fault_code=fault_code,
                event_type=_EVENT_NAMES.get(event_type, str(event_type)),
                severity=severity,
                description=description,
                source_id=source_id,
                stage=stage,
                reason=reason,
                message=self._pending,
            )
        )
        self._pending = None

    def _gate_withheld(self, origin: str, fault_code: str) -> None:
        if fault_code == self.code:
            self.held(
                "double_counting",
                f"not applied: {fault_code} is in recorded ReportFault traffic, and the recorded "
                f"calls are what the manager received (the {origin}'s requests are withheld)",
                fault_code,
            )

    # -- the manager's side ----------------------------------------------------------------

    def _rows(
        self,
        inner: Callable[[Row], None],
        at: int,
        keep: Callable[[Row], None],
        *,
        also_last: bool = False,
    ) -> Callable[[Row], None]:
        """A row sink that also keeps the rows naming the code at ``at`` (or, with
        ``also_last``, in the row's last field: an event's auto-cleared codes)."""
        code = self.code

        def sink(row: Row) -> None:
            inner(row)
            last = row[-1]
            if row[at] == code or (also_last and isinstance(last, tuple) and code in last):
                keep(row)

        return sink

    def _snapshot(self) -> FaultSnapshot | None:
        fault = self.manager.storage.faults.get(self.code)
        return self.manager.snapshot(fault) if fault is not None else None

    def _report(self, row: Row) -> None:
        if not self.trace.takes(cast("int", row[0])):  # its t_ns: not decoded when not told
            self._pending = None
            return
        record = REPORT_ROWS.decode(row)
        resolver = self.manager.resolver
        self.trace.items.append(
            TracedReport(
                record=record,
                message=self._pending,
                state=self._snapshot(),
                entity_prefix=resolver.prefix_for(record.source_id),
                healing_enabled=resolver.resolve(record.source_id).healing_enabled,
            )
        )
        self._pending = None

    def _transition(self, row: Row) -> None:
        if self.trace.takes(cast("int", row[0])):
            self.trace.items.append(
                TracedTransition(record=TRANSITION_ROWS.decode(row), state=self._snapshot())
            )

    def _event(self, row: Row) -> None:
        if self.trace.takes(cast("int", row[0])):
            self.trace.items.append(TracedEvent(record=EVENT_ROWS.decode(row)))

    def _decided(self, t_ns: int, fault_code: str, result: CorrelationResult) -> None:
        code = self.code
        if code not in (fault_code, result.root_cause_code, *result.retroactive_mute_codes):
            return
        rule = self._rules.get(result.rule_id)
        correlation = self.manager.correlation
        if rule is None and result.cluster_id and correlation is not None:
            cluster_rule = correlation.cluster_rule_of(fault_code)
            rule = rule_facts(cluster_rule) if cluster_rule is not None else None
        self.trace.add(
            CorrelationDecision(
                t_ns=t_ns,
                fault_code=fault_code,
                should_mute=result.should_mute,
                is_root_cause=result.is_root_cause,
                root_cause_code=result.root_cause_code,
                rule=rule,
                delay_ms=result.delay_ms,
                cluster_id=result.cluster_id,
                retroactive_mute_codes=result.retroactive_mute_codes,
            )
        )

    def _take_state(self, at_ns: int) -> None:
        fault = self.manager.storage.faults.get(self.code)
        correlation = self.manager.correlation
        clusters = correlation.clusters() if correlation is not None else []
        self.trace.state_at = StateAt(
            t_ns=at_ns,
            state=self.manager.snapshot(fault) if fault is not None else None,
            counter=fault.counter if fault is not None else None,
            muted=correlation.muted_entry(self.code) if correlation is not None else None,
            clusters=tuple(c for c in clusters if self.code in c.fault_codes),
        )


class _TracingSink:
    """A ReportSink in front of the gate's: notes the traced code's requests and held ones."""

    def __init__(self, tracer: Tracer, inner: ReportSink) -> None:
        self._tracer = tracer
        self._inner = inner

    def __call__(self, *request: *ReportFields) -> None:
        tracer = self._tracer
        if request[3] == tracer.code:  # its fault_code
            tracer.requested(*request)
        self._inner(*request)
        tracer.settled()

    def withheld(self, stage: str, reason: str, *request: *ReportFields) -> None:
        """A request the bridge held back: kept when it is for the traced code."""
        tracer = self._tracer
        fault_code = request[3]
        if fault_code == tracer.code:
            tracer.requested(*request)
            tracer.held(stage, reason, fault_code)
