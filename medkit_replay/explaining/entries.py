"""Story entries, one builder per kind of trace item: a report, a held request, a decision...

Reads the records the replay made; every verdict shown is the engine's, none is recomputed.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.explaining.lines import JSON, Entry, EntryKind, Line, part, plain
from medkit_replay.explaining.recorded import (
    message_fields,
    message_lines,
    rule_fields,
    rule_text,
)
from medkit_replay.text import seconds, severity_name
from medkit_replay.trace import (
    CorrelationDecision,
    HeldRequest,
    TracedClear,
    TracedEvent,
    TracedReport,
    TracedTransition,
)

if TYPE_CHECKING:
    from collections.abc import Callable

    from medkit_replay.model import NearMiss
    from medkit_replay.result import Result
    from medkit_replay.trace import FaultTrace, RecordedMessage, RuleFacts, TraceItem

MAX_REMEMBERED = 4096
"""Distinct recorded messages remembered, to say "the same as at" instead of repeating them."""

CAUSES = {
    "report": "by this report",
    "auto_confirm": (
        "by the time-based confirmation tick (PREFAILED for auto_confirm_after_sec since the "
        "last FAILED)"
    ),
    "clear": "by a ClearFault",
    "auto_clear": "auto-cleared with its root cause",
}


def when(ns: int, origin_ns: int) -> str:
    return f"{seconds(ns - origin_ns)} s"


def _severity(severity: int) -> str:
    return severity_name(severity)


def _band(conf: int | None, heal: int | None, healing: bool, prefix: str | None) -> str:
    text = f"confirm at {conf}, heal at {heal}"
    if not healing:
        text += " (healing off)"
    if prefix is not None:
        text += f"; per-entity thresholds of {prefix}"
    return text


class EntryBuilder:
    """Walks the trace once, turning each item into entries (see ENTRY_BUILDERS)."""

    def __init__(self, result: Result, trace: FaultTrace, origin_ns: int) -> None:
        self.result = result
        self.trace = trace
        self.code = trace.fault_code
        self.origin_ns = origin_ns
        self.inputs = tuple(i.path for i in result.inputs)
        self.near: dict[int, NearMiss] = {
            n.t_ns: n for n in result.near_misses if n.fault_code == self.code
        }
        self.entries: list[Entry] = []
        self.last_clear: TracedClear | None = None
        self.previous: tuple[str | None, int | None] = (None, None)  # status, counter
        self.shown: object = None  # the content of the last recorded message shown
        self.seen: dict[object, int] = {}  # recorded message content -> first shown at
        self.t_ns = 0  # the time of the item being told

    def recorded_lines(self, message: RecordedMessage | None, description: str) -> list[Line]:
        """The request's description and recorded message, unless the same as last shown."""
        lines: list[Line] = []
        recorded = (
            {v for _, v in message.fields if isinstance(v, str)} if message is not None else set()
        )
        if description and description not in recorded:
            lines.append((part("description ", "dim"), part(repr(description), "text")))
        if message is None:
            return lines
        content = (message.type, message.topic, message.fields, message.items)
        first_ns = self.seen.get(content)
        if first_ns is not None:  # shown before: once in a row is enough, else say when
            if content != self.shown:
                lines.append(
                    (part(f"recorded: the same as at {when(first_ns, self.origin_ns)}", "dim"),)
                )
        else:
            if len(self.seen) < MAX_REMEMBERED:
                self.seen[content] = self.t_ns
            lines += message_lines(message, self.inputs)
        self.shown = content
        return lines

    def add(
        self, t_ns: int, kind: EntryKind, line: Line, details: list[Line], fields: dict[str, JSON]
    ) -> None:
        base: dict[str, JSON] = {
            "t_ns": t_ns,
            "offset_ns": t_ns - self.origin_ns,
            "kind": kind,
            "text": plain(line),
        }
        self.entries.append(
            Entry(t_ns=t_ns, kind=kind, line=line, details=tuple(details), fields=base | fields)
        )

    # -- one builder per trace item type -----------------------------------------------------

    def report(self, item: TraceItem) -> None:
        assert isinstance(item, TracedReport)
        r = item.record
        line: list[tuple[str, str]] = [
            part("report ", "kind"),
            part(r.event_type, "failed" if r.event_type == "FAILED" else "passed"),
        ]
        if r.event_type == "FAILED":
            line.append(part(f" {_severity(r.severity)}", "severity"))
        line += [part(" from ", "dim"), part(r.source_id, "source")]
        line += [part(f" ({r.origin}", "dim")]
        if r.topic:
            line += [part(" on ", "dim"), part(r.topic, "topic")]
        line.append(part(")", "dim"))
        details: list[Line] = []
        fields: dict[str, JSON] = {
            "origin": r.origin,
            "topic": r.topic,
            "event_type": r.event_type,
            "severity": r.severity,
            "description": r.description,
            "source_id": r.source_id,
            "accepted": r.accepted,
            "reject_reason": r.reject_reason,
            "status": r.status,
            "debounce_counter": r.debounce_counter,
            "confirmation_threshold": r.confirmation_threshold,
            "healing_threshold": r.healing_threshold,
            "healing_enabled": item.healing_enabled,
            "entity_prefix": item.entity_prefix,
            "near_miss_margin": None,
            "message": message_fields(item.message),
        }
        if not r.accepted:
            line += [part(": rejected", "reject"), part(f" ({r.reject_reason})", "text")]
        elif r.status is None:
            line.append(part(": accepted; the fault is not known, nothing is stored", "dim"))
        else:
            line += [
                part(": counter ", "plain"),
                part(str(r.debounce_counter), "counter"),
                part(" (", "dim"),
                part(
                    _band(
                        r.confirmation_threshold,
                        r.healing_threshold,
                        item.healing_enabled,
                        item.entity_prefix,
                    ),
                    "dim",
                ),
                part("), ", "dim"),
                part(r.status, f"status:{r.status}"),
            ]
        details += self.recorded_lines(item.message, r.description)
        near = self.near.get(r.t_ns) if r.accepted and r.event_type == "FAILED" else None
        if (
            near is not None
            and near.debounce_counter == r.debounce_counter
            and near.source_id == r.source_id
        ):
            margin = near.debounce_counter - near.confirmation_threshold
            fields["near_miss_margin"] = margin
            details.append(
                (
                    part("near miss: ", "near"),
                    part(
                        f"came within {margin} of confirming at {when(r.t_ns, self.origin_ns)}",
                        "near",
                    ),
                )
            )
        quiet = (
            r.accepted
            and (r.status, r.debounce_counter) == self.previous
            and fields["near_miss_margin"] is None
        )
        if r.accepted:
            self.previous = (r.status, r.debounce_counter)
        fields["quiet"] = quiet
        self.add(r.t_ns, "report", tuple(line), details, fields)
        if r.withheld_event is not None:
            self.add(
                r.t_ns,
                "event_withheld",
                (
                    part("event ", "kind"),
                    part(r.withheld_event, "event"),
                    part(" not published: ", "muted"),
                    part("correlation muted this fault", "muted"),
                ),
                [],
                {"event_type": r.withheld_event, "reason": "muted by correlation"},
            )

    def held(self, item: TraceItem) -> None:
        assert isinstance(item, HeldRequest)
        line: Line = (
            part("held ", "held"),
            part(item.event_type, "failed" if item.event_type == "FAILED" else "passed"),
            part(f" {_severity(item.severity)}" if item.event_type == "FAILED" else "", "severity"),
            part(" from ", "dim"),
            part(item.source_id, "source"),
            part(f" ({item.origin}", "dim"),
            part(f" on {item.topic}" if item.topic else "", "dim"),
            part("): ", "dim"),
            part(item.reason, "held"),
        )
        fields: dict[str, JSON] = {
            "origin": item.origin,
            "topic": item.topic,
            "event_type": item.event_type,
            "severity": item.severity,
            "description": item.description,
            "source_id": item.source_id,
            "stage": item.stage,
            "reason": item.reason,
            "message": message_fields(item.message),
        }
        details = self.recorded_lines(item.message, item.description)
        self.add(item.t_ns, "held", line, details, fields)

    def decision(self, item: TraceItem) -> None:
        assert isinstance(item, CorrelationDecision)
        rule = item.rule
        fields: dict[str, JSON] = {
            "fault_code": item.fault_code,
            "should_mute": item.should_mute,
            "is_root_cause": item.is_root_cause,
            "root_cause_code": item.root_cause_code or None,
            "delay_ms": item.delay_ms,
            "cluster_id": item.cluster_id or None,
            "retroactive_mute_codes": list(item.retroactive_mute_codes),
            "rule": rule_fields(rule),
        }
        line: list[tuple[str, str]] = [part("correlation ", "kind")]
        if item.fault_code != self.code and self.code in item.retroactive_mute_codes:
            line += [
                part("cluster ", "plain"),
                part(item.cluster_id, "cluster"),
                part(" became active on a report of ", "dim"),
                part(item.fault_code, "code"),
                part(": upstream logs this fault as retroactively muted (a log line only)", "dim"),
            ]
        elif item.fault_code != self.code:
            when = f"that report {item.delay_ms} ms after this fault"
            muted = "muted" if item.should_mute else "not muted"
            line += _related("root of ", item.fault_code, rule, when, muted)
        elif item.is_root_cause:
            line += [
                part("root cause", "plain"),
                part(f" under {rule_text(rule)}: its symptoms in the window are", "dim"),
                part(
                    " muted" if rule is not None and rule.mute_symptoms else " not muted", "muted"
                ),
            ]
        elif item.root_cause_code:
            when = f"this report {item.delay_ms} ms after the root"
            muted = "muted" if item.should_mute else "not muted (mute_symptoms off)"
            line += _related("symptom of ", item.root_cause_code, rule, when, muted)
        elif item.cluster_id:
            line += [part("cluster ", "plain"), part(item.cluster_id, "cluster")]
            if rule is not None:
                line.append(
                    part(
                        f" joined under {rule_text(rule)}, min_count {rule.min_count}, "
                        f"representative {rule.representative}",
                        "dim",
                    )
                )
            if item.should_mute:
                line.append(part(": muted, the cluster shows as one fault", "muted"))
            if item.retroactive_mute_codes:
                line.append(
                    part(
                        "; the cluster became active, upstream logs as retroactively muted: "
                        + ", ".join(item.retroactive_mute_codes),
                        "dim",
                    )
                )
        else:
            return  # no rule concerns this report
        self.add(item.t_ns, "correlation", tuple(line), [], fields)

    def transition(self, item: TraceItem) -> None:
        assert isinstance(item, TracedTransition)
        r = item.record
        cause = CAUSES.get(r.cause, r.cause)
        if r.cause == "report" and r.to_status == "HEALED":
            cause = "healed by this report"
        if r.cause == "auto_clear" and self.last_clear is not None:
            cause = f"auto-cleared with its root {self.last_clear.record.fault_code}"
        line: Line = (
            part("status ", "kind"),
            part(r.from_status or "(new)", f"status:{r.from_status}"),
            part(" -> ", "dim"),
            part(r.to_status, f"status:{r.to_status}"),
            part(f" {cause}", "plain"),
        )
        fields: dict[str, JSON] = {
            "from_status": r.from_status,
            "to_status": r.to_status,
            "cause": r.cause,
            "source_id": r.source_id,
        }
        self.add(r.t_ns, "transition", line, [], fields)
        if r.cause == "auto_confirm":
            self.add(
                r.t_ns,
                "event_withheld",
                (
                    part("event ", "kind"),
                    part("fault_confirmed", "event"),
                    part(" not published: ", "muted"),
                    part("time-based confirmation is silent upstream", "muted"),
                ),
                [],
                {"event_type": "fault_confirmed", "reason": "auto-confirm is silent"},
            )

    def event(self, item: TraceItem) -> None:
        assert isinstance(item, TracedEvent)
        r = item.record
        fields: dict[str, JSON] = {
            "event_type": r.event_type,
            "fault_code": r.fault.fault_code,
            "status": r.fault.status,
            "muted": r.fault.muted,
            "root_cause_code": r.fault.root_cause_code,
            "auto_cleared_codes": list(r.auto_cleared_codes),
        }
        line: list[tuple[str, str]] = [
            part("event ", "kind"),
            part(r.event_type, "event"),
            part(" published", "plain"),
        ]
        if r.fault.fault_code != self.code:
            line += [part(" for its root ", "dim"), part(r.fault.fault_code, "code")]
            line.append(part(", naming this fault among the auto-cleared codes", "dim"))
        elif r.auto_cleared_codes:
            line.append(part(f" (auto-cleared: {', '.join(r.auto_cleared_codes)})", "dim"))
        self.add(r.t_ns, "event", tuple(line), [], fields)

    def clear(self, item: TraceItem) -> None:
        assert isinstance(item, TracedClear)
        r = item.record
        self.last_clear = item
        fields: dict[str, JSON] = {
            "fault_code": r.fault_code,
            "success": r.success,
            "message": r.message,
            "skip_correlation_auto_clear": r.skip_correlation_auto_clear,
            "auto_cleared_codes": list(r.auto_cleared_codes),
        }
        line: list[tuple[str, str]] = [part("clear ", "kind"), part("ClearFault(", "plain")]
        line += [part(r.fault_code, "code"), part(")", "plain")]
        if r.fault_code != self.code:
            line.append(part(": its root, auto-clears this fault with it", "muted"))
        else:
            line += [
                part(": ", "dim"),
                part("success" if r.success else "failed", "passed" if r.success else "reject"),
                part(f" ({r.message})", "text"),
            ]
        self.add(r.t_ns, "clear", tuple(line), [], fields)


ENTRY_BUILDERS: dict[type, Callable[[EntryBuilder, TraceItem], None]] = {
    TracedReport: EntryBuilder.report,
    HeldRequest: EntryBuilder.held,
    CorrelationDecision: EntryBuilder.decision,
    TracedTransition: EntryBuilder.transition,
    TracedEvent: EntryBuilder.event,
    TracedClear: EntryBuilder.clear,
}
"""How each kind of trace item joins the story. A later step (a freeze frame or a recording
captured at a moment, say) joins by adding its item type to the trace (trace.py TraceItem),
a method here that turns it into entries, and its kind to EntryKind."""


def _related(
    role: str, code: str, rule: RuleFacts | None, when: str, muted: str
) -> list[tuple[str, str]]:
    """A correlation line's words for a report tied to another code: its role (root of,
    symptom of), the code, the rule and the delay, and whether it was muted."""
    return [
        part(role, "plain"),
        part(code, "code"),
        part(f" under {rule_text(rule)}, {when}: ", "dim"),
        part(muted, "muted"),
    ]
