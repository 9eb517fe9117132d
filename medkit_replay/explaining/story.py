"""One fault's story: what the replay did with it, in order, built from a Result and a FaultTrace.

Orders and condenses the entries (entries.py builds them); decides nothing the engine decided.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from medkit_replay.explaining.entries import ENTRY_BUILDERS, EntryBuilder, when
from medkit_replay.explaining.evidence import evidence_entries
from medkit_replay.explaining.lines import Entry, Line, part
from medkit_replay.outputs.muting import NO_EVENTS, event_counts, muting_sentence
from medkit_replay.text import severity_name
from medkit_replay.trace import CorrelationDecision, TracedReport, TracedTransition, item_time

if TYPE_CHECKING:
    from medkit_replay.explaining.lines import JSON
    from medkit_replay.result import Result
    from medkit_replay.trace import FaultTrace, StateAt, TraceItem


@dataclass(frozen=True, slots=True, kw_only=True)
class Story:
    """A fault's story: a header, the entries in order, its state where the story stops."""

    fault_code: str
    origin_ns: int
    end_ns: int
    at_ns: int | None
    inputs: tuple[str, ...]
    upstream_release: str
    """The ros2_medkit release the story was replayed as."""
    header: tuple[Line, ...]
    summary: dict[str, JSON]
    entries: tuple[Entry, ...]
    state: tuple[Line, ...]
    state_fields: JSON


def _ordered(items: list[TraceItem], code: str) -> list[TraceItem]:
    """The trace's items in story order: what a report caused comes after the report.

    The engine decides correlation and changes the status before it records the report that
    caused them; here the report comes first, then its decision and status change.
    """
    out: list[TraceItem] = []
    waiting: list[TraceItem] = []
    for item in items:
        caused = (isinstance(item, CorrelationDecision) and item.fault_code == code) or (
            isinstance(item, TracedTransition) and item.record.cause == "report"
        )
        if caused:
            waiting.append(item)
            continue
        out.append(item)
        if waiting and isinstance(item, TracedReport):
            out += sorted(waiting, key=lambda i: not isinstance(i, TracedTransition))
            waiting = []
    return out + waiting


FOLLOWERS = ("transition", "correlation", "event_withheld", "event")
"""Entries that belong to the report before them at the same time (what it caused), in the
order a step tells them."""


def _follows(entry: Entry, report: Entry, code: str) -> bool:
    if entry.kind not in FOLLOWERS or entry.t_ns != report.t_ns:
        return False
    return entry.kind != "transition" or entry.fields.get("cause") == "report"


def _rank(entry: Entry, code: str) -> int:
    if entry.kind == "correlation" and entry.fields.get("fault_code") != code:
        return len(FOLLOWERS)  # a decision on another fault: after this one's own
    return FOLLOWERS.index(entry.kind)


def _steps(entries: list[Entry], code: str) -> list[list[Entry]]:
    """Entries grouped as steps: a report with what it caused, or a single other entry."""
    steps: list[list[Entry]] = []
    for entry in entries:
        if steps and steps[-1][0].kind == "report" and _follows(entry, steps[-1][0], code):
            steps[-1].append(entry)
        else:
            steps.append([entry])
    return [[step[0], *sorted(step[1:], key=lambda e: _rank(e, code))] for step in steps]


def _signature(step: list[Entry]) -> tuple[JSON, ...] | None:
    """What makes two steps alike: a report that changed no state, the same source and
    kind, and followers saying the same; None for a step that is never condensed."""
    first = step[0]
    f = first.fields
    if first.kind != "report" or not f.get("quiet"):
        return None
    return (
        f["event_type"],
        f["source_id"],
        f["origin"],
        f["status"],
        f["debounce_counter"],
        *(e.fields["text"] for e in step[1:]),
    )


def _repeat(run: list[list[Entry]], origin_ns: int) -> Entry:
    first, last = run[0][0], run[-1][0]
    f = first.fields
    also = [e.fields["text"] for e in run[0][1:]]
    text = (
        f"{len(run)} more {f['event_type']} report(s) from {f['source_id']} until "
        f"{when(last.t_ns, origin_ns)}, each changing nothing"
        + ("" if not also else "; each also: " + "; ".join(str(a) for a in also))
    )
    line: Line = (
        part("repeat ", "kind"),
        part(f"{len(run)} more {f['event_type']}", "dim"),
        part(f" report(s) from {f['source_id']} until ", "dim"),
        part(when(last.t_ns, origin_ns), "plain"),
        part(", each changing nothing", "dim"),
        part("" if not also else " (each also: " + "; ".join(str(a) for a in also) + ")", "dim"),
    )
    return Entry(
        t_ns=first.t_ns,
        kind="repeat",
        line=line,
        fields={
            "t_ns": first.t_ns,
            "offset_ns": f["offset_ns"],
            "kind": "repeat",
            "text": text,
            "event_type": f["event_type"],
            "source_id": f["source_id"],
            "origin": f["origin"],
            "status": f["status"],
            "debounce_counter": f["debounce_counter"],
            "count": len(run),
            "last_t_ns": last.t_ns,
            "times_ns": [step[0].t_ns for step in run],
            "each_also": list(also),
        },
    )


def _condense(entries: list[Entry], origin_ns: int, code: str) -> list[Entry]:
    """Steps in a row alike to the one before them (see :func:`_signature`) become one
    ``repeat`` entry after it: how many, until when (the JSON lists every time)."""
    out: list[Entry] = []
    run: list[list[Entry]] = []
    previous: tuple[JSON, ...] | None = None
    for step in _steps(entries, code):
        signature = _signature(step)
        if signature is not None and signature == previous:
            run.append(step)
            continue
        if run:
            out.append(_repeat(run, origin_ns))
            run = []
        out += step
        previous = signature if step[0].kind == "report" else None
    if run:
        out.append(_repeat(run, origin_ns))
    return out


def state_lines(at: StateAt | None, origin_ns: int, code: str) -> tuple[list[Line], JSON]:
    """The fault where the story stops, as lines and as JSON."""
    if at is None:
        return [(part("state: unknown", "dim"),)], None
    at_text = when(at.t_ns, origin_ns)
    state = at.state
    if state is None:
        return (
            [(part(f"state at {at_text}: ", "kind"), part(f"{code} was not known yet", "dim"))],
            {"t_ns": at.t_ns, "offset_ns": at.t_ns - origin_ns, "known": False},
        )
    lines: list[Line] = [
        (
            part(f"state at {at_text}: ", "kind"),
            part(state.status, f"status:{state.status}"),
            part(f", severity {severity_name(state.severity)}", "plain"),
            part(f", debounce counter {at.counter}", "plain"),
            part(f", {state.occurrence_count} occurrence(s)", "plain"),
        ),
        (
            part("first ", "dim"),
            part(when(state.first_occurred_ns, origin_ns), "plain"),
            part(", last ", "dim"),
            part(when(state.last_occurred_ns, origin_ns), "plain"),
            part(", sources ", "dim"),
            part(", ".join(state.reporting_sources) or "none", "source"),
        ),
    ]
    if at.muted is not None:
        m = at.muted
        lines.append(
            (
                part("muted by ", "muted"),
                part(m.root_cause_code, "code"),
                part(f" under rule {m.rule_id}, last muted {m.delay_ms} ms after the root", "dim"),
            )
        )
    for cluster in at.clusters:
        lines.append(
            (
                part("in cluster ", "plain"),
                part(cluster.cluster_id, "cluster"),
                part(
                    f" ({cluster.rule_id}, {cluster.count} fault(s), represented by "
                    f"{cluster.representative_code})",
                    "dim",
                ),
            )
        )
    fields: JSON = {
        "t_ns": at.t_ns,
        "offset_ns": at.t_ns - origin_ns,
        "known": True,
        "status": state.status,
        "severity": state.severity,
        "debounce_counter": at.counter,
        "occurrence_count": state.occurrence_count,
        "first_occurred_ns": state.first_occurred_ns,
        "last_occurred_ns": state.last_occurred_ns,
        "reporting_sources": list(state.reporting_sources),
        "muted_by": (
            {
                "root_cause_code": at.muted.root_cause_code,
                "rule_id": at.muted.rule_id,
                "delay_ms": at.muted.delay_ms,
            }
            if at.muted is not None
            else None
        ),
        "clusters": [c.cluster_id for c in at.clusters],
    }
    return lines, fields


def build_story(result: Result, trace: FaultTrace) -> Story:
    """The story of ``trace.fault_code``, stopped at ``trace.at_ns`` when there is one.

    Raises:
        ValueError: the trace holds and counts nothing (the code never appeared).
    """
    if not trace.seen:
        raise ValueError(f"{trace.fault_code} never appears")
    start, end = result.span()
    origin_ns = start if start is not None else (trace.origin_ns or 0)
    end_ns = end if end is not None else origin_ns
    builder = EntryBuilder(result, trace, origin_ns)
    at_ns = trace.at_ns
    for item in _ordered(trace.items, trace.fault_code):
        if at_ns is not None and item_time(item) > at_ns:
            break
        builder.t_ns = item_time(item)
        ENTRY_BUILDERS[type(item)](builder, item)
    entries = _with_evidence(
        _condense(builder.entries, origin_ns, trace.fault_code),
        [e for e in evidence_entries(result, trace.fault_code, origin_ns) if _told(e.t_ns, trace)],
    )
    state, state_fields = state_lines(trace.state_at, origin_ns, trace.fault_code)
    header, summary = _header(result, trace, builder.entries, origin_ns)
    header += _told_lines(trace, origin_ns)
    if trace.before or trace.left_out:  # only then: a whole story's JSON stays as it was
        summary["left_out"] = {
            "before_from": trace.before,
            "past_limit": trace.left_out,
            "past_limit_from_ns": trace.left_out_from_ns,
            "limit": trace.limit,
        }
    return Story(
        fault_code=trace.fault_code,
        origin_ns=origin_ns,
        end_ns=end_ns,
        at_ns=at_ns,
        inputs=builder.inputs,
        upstream_release=result.upstream_release,
        header=tuple(header),
        summary=summary,
        entries=tuple(entries),
        state=tuple(state),
        state_fields=state_fields,
    )


def _told(t_ns: int, trace: FaultTrace) -> bool:
    """Whether the stretch the story tells holds ``t_ns`` (``--from``, ``--at``, the cut)."""
    at_ns, from_ns, cut_ns = trace.at_ns, trace.from_ns, trace.left_out_from_ns
    return (
        (at_ns is None or t_ns <= at_ns)
        and (from_ns is None or t_ns >= from_ns)
        and (cut_ns is None or t_ns < cut_ns)
    )


def _told_lines(trace: FaultTrace, origin_ns: int) -> list[Line]:
    """What the story leaves out (``--from``, ``--limit``) and how to see it."""
    lines: list[Line] = []
    if trace.before:
        lines.append(
            (
                part("from ", "kind"),
                part(f"{when(trace.from_ns or origin_ns, origin_ns)} (--from): ", "plain"),
                part(f"{trace.before:,} earlier item(s) not told", "dim"),
            )
        )
    if trace.left_out:
        start = trace.left_out_from_ns if trace.left_out_from_ns is not None else origin_ns
        lines.append(
            (
                part("story cut ", "reject"),
                part(
                    f"after {trace.limit:,} items: {trace.left_out:,} more from "
                    f"{when(start, origin_ns)} not told (narrow it with --from and --at, or "
                    "raise --limit)",
                    "plain",
                ),
            )
        )
    return lines


def _with_evidence(entries: list[Entry], evidence: list[Entry]) -> list[Entry]:
    """Each evidence entry after every story entry up to its time (the confirming step first)."""
    out: list[Entry] = []
    pending = list(evidence)
    for entry in entries:
        while pending and pending[0].t_ns < entry.t_ns:
            out.append(pending.pop(0))
        out.append(entry)
    return out + pending


def _header(
    result: Result, trace: FaultTrace, entries: list[Entry], origin_ns: int
) -> tuple[list[Line], dict[str, JSON]]:
    code = trace.fault_code
    counts: dict[str, int] = {}
    for entry in entries:
        counts[entry.kind] = counts.get(entry.kind, 0) + 1
    reports = [e for e in entries if e.kind == "report"]
    rejected = sum(1 for e in reports if not e.fields["accepted"])
    near = [n for n in result.near_misses if n.fault_code == code]
    closest = (
        min(near, key=lambda n: (n.debounce_counter - n.confirmation_threshold, n.t_ns))
        if near
        else None
    )
    lines: list[Line] = [
        (
            part("reports: ", "dim"),
            part(f"{len(reports)} reached the manager ({rejected} rejected), ", "plain"),
            part(f"{counts.get('held', 0)} held before it", "plain"),
            part("; events: ", "dim"),
            part(f"{counts.get('event', 0)} published, ", "plain"),
            part(f"{counts.get('event_withheld', 0)} withheld", "plain"),
        )
    ]
    muted = next((m for m in result.muted_faults if m.fault_code == code), None)
    first = next(
        (
            e.fields["delay_ms"]
            for e in entries
            if e.kind == "correlation"
            and e.fields.get("fault_code") == code
            and e.fields.get("should_mute")
        ),
        None,
    )
    if muted is not None:
        first_ms = first if isinstance(first, int) and not trace.before else None
        lines.append(
            (
                part("muted at the end of the run: ", "muted"),
                part(
                    muting_sentence(event_counts(result).get(code, NO_EVENTS), muted, first_ms),
                    "plain",
                ),
            )
        )
    if closest is not None:
        margin = closest.debounce_counter - closest.confirmation_threshold
        lines.append(
            (
                part("closest near miss: ", "near"),
                part(
                    f"came within {margin} of confirming at {when(closest.t_ns, origin_ns)} "
                    f"({len(near)} near miss(es) recorded)",
                    "near",
                ),
            )
        )
    summary: dict[str, JSON] = {
        "reports": len(reports),
        "reports_rejected": rejected,
        "held": counts.get("held", 0),
        "events_published": counts.get("event", 0),
        "events_withheld": counts.get("event_withheld", 0),
        "transitions": counts.get("transition", 0),
        "near_misses": len(near),
        "closest_near_miss": (
            {
                "t_ns": closest.t_ns,
                "margin": closest.debounce_counter - closest.confirmation_threshold,
            }
            if closest is not None
            else None
        ),
    }
    return lines, summary
