"""Parity: the replayed FaultEvents against the ones the live fault manager published.

Matches per fault code in order on (event_type, status); reports what matched, what differs and why.
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Iterable

    from medkit_replay.bridges.action_status import ActionStatusBridge
    from medkit_replay.bridges.service_calls import RecordedResponse
    from medkit_replay.config.replay_options import ReplayOptions
    from medkit_replay.model import ClearRecord, FaultEvent, ReportRecord

MAX_LISTED = 200


@dataclass(frozen=True, slots=True, kw_only=True)
class RecordedEvent:
    """A FaultEvent found in the recording (bag time of the message that carried it)."""

    t_ns: int
    topic: str
    event_type: str
    fault_code: str
    status: str
    severity: int
    occurrence_count: int
    reporting_sources: tuple[str, ...]
    auto_cleared_codes: tuple[str, ...]


def recorded_event(t_ns: int, topic: str, msg: object) -> RecordedEvent:
    """Read a decoded ros2_medkit_msgs/msg/FaultEvent."""
    fault = getattr(msg, "fault", None)
    return RecordedEvent(
        t_ns=t_ns,
        topic=topic,
        event_type=str(getattr(msg, "event_type", "")),
        fault_code=str(getattr(fault, "fault_code", "")),
        status=str(getattr(fault, "status", "")),
        severity=int(getattr(fault, "severity", 0)),
        occurrence_count=int(getattr(fault, "occurrence_count", 0)),
        reporting_sources=tuple(str(s) for s in getattr(fault, "reporting_sources", ())),
        auto_cleared_codes=tuple(str(c) for c in getattr(msg, "auto_cleared_codes", ())),
    )


def _entry(recorded: RecordedEvent | None, replayed: FaultEvent | None) -> dict[str, object]:
    entry: dict[str, object] = {}
    if recorded is not None:
        entry.update(
            fault_code=recorded.fault_code,
            event_type=recorded.event_type,
            status=recorded.status,
            recorded_t_ns=recorded.t_ns,
        )
    if replayed is not None:
        entry.update(
            fault_code=replayed.fault.fault_code,
            event_type=replayed.event_type,
            status=replayed.fault.status,
            replayed_t_ns=replayed.t_ns,
        )
    return entry


def _differences(recorded: RecordedEvent, replayed: FaultEvent) -> dict[str, object]:
    fault = replayed.fault
    fields: dict[str, tuple[object, object]] = {
        "severity": (recorded.severity, fault.severity),
        "occurrence_count": (recorded.occurrence_count, fault.occurrence_count),
        "reporting_sources": (list(recorded.reporting_sources), list(fault.reporting_sources)),
        "auto_cleared_codes": (
            list(recorded.auto_cleared_codes),
            list(replayed.auto_cleared_codes),
        ),
    }
    return {name: {"recorded": a, "replayed": b} for name, (a, b) in fields.items() if a != b}


def compare(recorded: Iterable[RecordedEvent], replayed: Iterable[FaultEvent]) -> dict[str, object]:
    """Pair recorded and replayed events per fault code; summarise matches and mismatches.

    Time offsets are replayed minus recorded bag time: the live manager stamps with its wall
    clock and publishes after handling, so small positive or negative offsets are expected.
    """
    rec_by_code: dict[str, list[RecordedEvent]] = {}
    for rec_event in recorded:
        rec_by_code.setdefault(rec_event.fault_code, []).append(rec_event)
    rep_by_code: dict[str, list[FaultEvent]] = {}
    for rep_event in replayed:
        rep_by_code.setdefault(rep_event.fault.fault_code, []).append(rep_event)
    matched = 0
    offsets: list[int] = []
    differing: list[dict[str, object]] = []
    missing: list[dict[str, object]] = []
    extra: list[dict[str, object]] = []
    for code in sorted(set(rec_by_code) | set(rep_by_code), key=lambda c: c.encode("utf-8")):
        recs = rec_by_code.get(code, [])
        reps = rep_by_code.get(code, [])
        matcher = difflib.SequenceMatcher(
            a=[(r.event_type, r.status) for r in recs],
            b=[(e.event_type, e.fault.status) for e in reps],
            autojunk=False,
        )
        for tag, i1, i2, j1, j2 in matcher.get_opcodes():
            if tag == "equal":
                for rec, rep in zip(recs[i1:i2], reps[j1:j2], strict=True):
                    matched += 1
                    offsets.append(rep.t_ns - rec.t_ns)
                    diff = _differences(rec, rep)
                    if diff:
                        differing.append({**_entry(rec, rep), "differences": diff})
                continue
            missing.extend(_entry(rec, None) for rec in recs[i1:i2])
            extra.extend(_entry(None, rep) for rep in reps[j1:j2])
    n_recorded = sum(len(v) for v in rec_by_code.values())
    n_replayed = sum(len(v) for v in rep_by_code.values())
    return {
        "recorded_events": n_recorded,
        "replayed_events": n_replayed,
        "matched": matched,
        "matched_with_differences": len(differing),
        "missing_in_replay": len(missing),
        "extra_in_replay": len(extra),
        "verdict": "match" if not (differing or missing or extra) else "differ",
        "max_abs_time_offset_ns": max((abs(o) for o in offsets), default=0),
        "differences": differing[:MAX_LISTED],
        "missing": missing[:MAX_LISTED],
        "extra": extra[:MAX_LISTED],
        "listed_at_most": MAX_LISTED,
    }


def suggest_action_sources(
    recorded: Iterable[RecordedEvent], bridge: ActionStatusBridge, options: ReplayOptions
) -> dict[str, str]:
    """Action → server node, where the live manager saw one other source for an action's code.

    The live action bridge reports as the action server's node, which a recording cannot
    tell; the recorded FaultEvents' reporting_sources can.
    """
    codes: dict[str, str] = {}
    for action in bridge.watched_actions():
        if action in options.action_sources:
            continue
        for canceled in (False, True):
            codes[bridge.fault_code(action, canceled=canceled)] = action
    seen: dict[str, set[str]] = {}
    for event in recorded:
        owner = codes.get(event.fault_code)
        if owner is not None:
            seen.setdefault(owner, set()).update(event.reporting_sources)
    suggestion = {}
    for action in sorted(seen):
        others = seen[action] - {action}
        if len(others) == 1:
            suggestion[action] = next(iter(others))
    return suggestion


def compare_responses(
    responses: Iterable[RecordedResponse],
    reports: Iterable[ReportRecord],
    clears: Iterable[ClearRecord],
) -> dict[str, object]:
    """Recorded service responses against the replay's verdict on the same calls.

    ReportFault ``accepted`` and ClearFault ``success``/``auto_cleared_codes`` are compared
    for each recorded call the replay applied (matched on request time, topic and code).
    """
    recorded = list(responses)
    wanted = {(r.request_t_ns, r.fault_code) for r in recorded}
    accepted = {
        (r.t_ns, r.fault_code): r.accepted
        for r in reports
        if r.origin == "report_fault" and (r.t_ns, r.fault_code) in wanted
    }
    cleared = {(c.t_ns, c.fault_code): c for c in clears if (c.t_ns, c.fault_code) in wanted}
    disagree: list[dict[str, object]] = []
    for response in recorded:
        key = (response.request_t_ns, response.fault_code)
        if response.kind == "report":
            ours: object = accepted.get(key)
            theirs: object = response.accepted
        else:
            clear = cleared.get(key)
            ours = None if clear is None else [clear.success, list(clear.auto_cleared_codes)]
            theirs = [response.accepted, list(response.auto_cleared_codes)]
        if ours != theirs:
            disagree.append(
                {
                    "kind": response.kind,
                    "fault_code": response.fault_code,
                    "t_ns": response.request_t_ns,
                    "recorded": theirs,
                    "replayed": ours,
                }
            )
    return {
        "recorded_responses": len(recorded),
        "agree": len(recorded) - len(disagree),
        "disagree": disagree[:MAX_LISTED],
    }
