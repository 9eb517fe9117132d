"""The sweep's figures computed the plain way from a replay's Result: the oracle its rows are
checked against (records read back one by one, nothing shared with medkit_replay.tuning)."""

from __future__ import annotations

from collections import Counter
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from medkit_replay.result import Result


def code_figures(result: Result) -> dict[str, dict[str, object]]:
    """Per fault code: the run_codes columns (as the CSV shows them: text)."""
    first_failed: dict[str, int] = {}
    muted_events: Counter[str] = Counter()
    for report in result.reports:
        if report.accepted and report.event_type == "FAILED":
            first_failed.setdefault(report.fault_code, report.t_ns)
        if report.withheld_event is not None:
            muted_events[report.fault_code] += 1
    first_confirmed: dict[str, int] = {}
    since: dict[str, int] = {}
    confirmed_ns: Counter[str] = Counter()
    confirmations: Counter[str] = Counter()
    flaps: Counter[str] = Counter()
    for transition in result.transitions:
        code = transition.fault_code
        if transition.to_status == "CONFIRMED" and transition.from_status != "CONFIRMED":
            first_confirmed.setdefault(code, transition.t_ns)
            since[code] = transition.t_ns
            confirmations[code] += 1
        elif transition.from_status == "CONFIRMED" and transition.to_status != "CONFIRMED":
            confirmed_ns[code] += transition.t_ns - since.pop(code)
            flaps[code] += transition.to_status == "HEALED"
    end_ns = result.summary.end_ns
    for code, start in since.items():
        assert end_ns is not None
        confirmed_ns[code] += end_ns - start
    events = Counter(event.fault.fault_code for event in result.events)
    near = Counter(n.fault_code for n in result.near_misses)
    muted = {m.fault_code for m in result.muted_faults}
    statuses = {f.fault_code: f.status for f in result.faults}
    codes = set(first_failed) | set(statuses) | set(events) | set(first_confirmed) | set(near)
    figures: dict[str, dict[str, object]] = {}
    for code in codes:
        latency = (
            first_confirmed[code] - first_failed[code]
            if code in first_confirmed and code in first_failed
            else None
        )
        figures[code] = {
            "first_failed_ns": first_failed.get(code),
            "detection_latency_ns": latency,
            "confirmations": confirmations[code],
            "flaps": flaps[code],
            "confirmed_ns": confirmed_ns[code],
            "events": events[code],
            "muted_events": muted_events[code],
            "near_misses": near[code],
            "muted": code in muted,
            "status": statuses.get(code, ""),
        }
    return figures


def run_figures(result: Result) -> dict[str, object]:
    """The runs columns that do not sum code figures."""
    summary = result.summary
    return {
        "messages": summary.messages_read,
        "reports": summary.reports_accepted,
        "faults": summary.faults,
        "events": sum(summary.events.values()),
        "events_confirmed": summary.events["fault_confirmed"],
        "events_updated": summary.events["fault_updated"],
        "events_cleared": summary.events["fault_cleared"],
        "muted_faults": len(result.muted_faults),
    }


def as_cell(value: object) -> str:
    """A value as the sweep's CSV writes it."""
    return "" if value is None else str(value)
