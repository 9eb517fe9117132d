"""The HTML report: one self-contained, offline page showing the same data as the JSON report.

Inline CSS and vanilla JS (package data in html_assets/), data for the JS as escaped JSON in a
``<script type="application/json">``; no network fetch, no clock, no random ids: same Result, same
bytes. Reads only the Result. Recorded text is cut (cells, tooltips, warnings), so the page grows
with the number of faults and records, never with the length of a string a recording holds.
"""

from __future__ import annotations

import base64
import hashlib
import json
from typing import TYPE_CHECKING

from medkit_replay.outputs.atomic import atomic_text
from medkit_replay.outputs.html_evidence import evidence_section
from medkit_replay.outputs.html_page import asset
from medkit_replay.outputs.html_tables import (
    CELL_CAP,
    esc,
    json_pre,
    listed,
    object_block,
    record_tables,
    short,
    table,
    text,
    when,
)
from medkit_replay.outputs.html_timeline import (
    LIST_CAP,
    ROW_CAP,
    Span,
    build_lanes,
    page_data,
)
from medkit_replay.outputs.muting import NO_EVENTS, event_counts, muting_sentence
from medkit_replay.outputs.times import utc_date
from medkit_replay.result import EVENT_KINDS, STATUSES, release_line
from medkit_replay.text import WARNING_CAP, clip, seconds, severity_name

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.outputs.html_timeline import Lane
    from medkit_replay.result import Result

AXIS_TICKS = 10  # ticks drawn without JavaScript; the script redraws them for each zoom


def script_json(value: object) -> str:
    """JSON safe inside <script>: no '<', '>', '&', U+2028 or U+2029 survives unescaped."""
    dumped = json.dumps(value, ensure_ascii=True, separators=(",", ":"), default=str)
    for raw, escaped in (
        ("<", "\\u003c"),
        (">", "\\u003e"),
        ("&", "\\u0026"),
        ("\u2028", "\\u2028"),
        ("\u2029", "\\u2029"),
    ):
        dumped = dumped.replace(raw, escaped)
    return dumped


def _pct(value: float) -> str:
    return f"{value:.5f}".rstrip("0").rstrip(".") + "%"


def _utc(t_ns: int) -> str:
    date = utc_date(t_ns)
    return f" ({date})" if date else ""


def _n(count: int, noun: str) -> str:
    return f"{count:,} {noun}{'' if count == 1 else 's'}"


def _header(result: Result, span: Span) -> str:
    s = result.summary
    start, end = result.span()  # as the terminal's summary says it
    length = 0 if start is None or end is None else end - start
    if start is None or end is None:
        recorded = "nothing was read"
    else:
        recorded = (
            f"{seconds(length)} s of bag time, from {start} ns{_utc(start)} to "
            f"{end} ns (times below are seconds from the start)"
            + ("; no message was read" if s.start_ns is None else "")
        )
    names = listed(i.path for i in result.inputs) or "no input"
    inputs = []
    for item in result.inputs:
        topics = "".join(
            f"<tr><td>{esc(clip(t.topic, CELL_CAP))}</td><td>{esc(clip(t.type, CELL_CAP))}</td>"
            f"<td>{esc(t.role or '—')}</td>"
            f'<td class="n">{t.messages:,}</td></tr>'
            for t in item.topics
        )
        topic_block = (
            f'<table class="topics"><thead><tr><th>topic</th><th>type</th><th>role</th>'
            f"<th>messages</th></tr></thead><tbody>{topics}</tbody></table>"
            if topics
            else '<span class="muted-text">no topics (script)</span>'
        )
        first = "—" if item.start_ns is None else span.label(item.start_ns)
        last = "—" if item.end_ns is None else span.label(item.end_ns)
        inputs.append(
            f'<tr><td class="path">{esc(clip(item.path, CELL_CAP))}</td>'
            f"<td>{esc(item.storage)}</td>"
            f'<td>{esc(first)} \u2013 {esc(last)}</td><td class="n">{item.message_count:,}</td>'
            f"<td>{topic_block}</td></tr>"
        )
    warnings = "".join(f"<li>{esc(clip(w, WARNING_CAP))}</li>" for w in result.warnings)
    warn_block = (
        f'<section id="warnings" class="warnings" role="alert"><h2>⚠ {len(result.warnings)} '
        f"warning{'s' if len(result.warnings) != 1 else ''}</h2><ul>{warnings}</ul></section>"
        if warnings
        else '<p id="warnings" class="no-warnings">No warnings.</p>'
    )
    statuses = "".join(
        f'<span class="badge s-{st}">{st} {s.faults_by_status.get(st, 0)}</span>' for st in STATUSES
    )
    events = " · ".join(f"{k.removeprefix('fault_')} {s.events.get(k, 0)}" for k in EVENT_KINDS)
    cards = [
        ("Bag time", f"{seconds(length)} s", f"{s.messages_read:,} messages read"),
        (
            "Reports",
            f"{s.reports:,}",
            f"{s.reports_accepted:,} accepted · {s.reports_rejected:,} rejected",
        ),
        ("Events", f"{sum(s.events.values()):,}", events),
        ("Faults", f"{s.faults:,}", statuses),
        ("Transitions", f"{s.transitions:,}", _n(s.clears, "ClearFault request")),
        (
            "Correlation",
            f"{len(result.muted_faults)} muted",
            _n(len(result.clusters), "active cluster"),
        ),
    ]
    card_html = "".join(
        f'<div class="card"><div class="k">{esc(k)}</div><div class="v">{esc(v)}</div>'
        f'<div class="d">{d if k == "Faults" else esc(d)}</div></div>'
        for k, v, d in cards
    )
    return (
        f'<header class="top"><h1>medkit-replay report</h1><p class="sub">'
        f'<span class="names">{esc(names)}</span> · medkit-replay {esc(result.tool_version)}</p>'
        f'<p class="release">{esc(release_line([result.upstream_release]))}</p>'
        f'<p class="span-line">Recording: {esc(recorded)}</p></header>{warn_block}'
        f'<section class="cards">{card_html}</section>'
        f'<section id="inputs"><h2>Inputs</h2><table class="inputs"><thead><tr><th>path</th>'
        f"<th>storage</th><th>span</th><th>messages</th><th>topics</th></tr></thead><tbody>"
        f"{''.join(inputs)}</tbody></table></section>"
    )


def _row(index: int, lane: Lane, span: Span) -> str:
    f = lane.fault
    tags = []
    if f.muted:
        root = short(f.root_cause_code or "?")
        tags.append(f'<span class="tag tag-muted">muted ← {esc(root)}</span>')
    clusters = f.cluster_ids[:LIST_CAP]
    tags.extend(f'<span class="tag tag-cluster">{esc(short(c))}</span>' for c in clusters)
    if len(f.cluster_ids) > LIST_CAP:
        tags.append(f'<span class="tag">+{len(f.cluster_ids) - LIST_CAP:,} more</span>')
    sources = listed(f.reporting_sources) or "—"
    tip = (
        f"{f.fault_code}\n{short(f.description)}\nstatus {f.status}, "
        f"severity {severity_name(f.severity)}, occurrences {f.occurrence_count}\n"
        f"sources: {sources}\n"
        + (f"muted by {short(f.root_cause_code or '?')}\n" if f.muted else "")
        + (f"clusters: {listed(f.cluster_ids)}\n" if f.cluster_ids else "")
        + "click for the debounce counter and near misses"
    )
    bands = "".join(
        f'<div class="band s-{esc(b.status)}" style="left:{_pct(span.percent(b.start_ns))};'
        f'width:{_pct(span.percent(b.end_ns) - span.percent(b.start_ns))}" '
        f'data-tip="{esc(b.tip)}"></div>'
        for b in lane.bands
    )
    markers = "".join(
        f'<div class="mk mk-{esc(m.kind)}" style="left:{_pct(span.percent(m.t_ns))}" '
        f'data-tip="{esc(m.tip)}"></div>'
        for m in lane.markers
    )
    return (
        f'<div class="fault-row" id="f-{index}" data-index="{index}" '
        f'data-code="{esc(f.fault_code)}" tabindex="0" role="button" aria-expanded="false">'
        f'<div class="fault-label" '
        f'data-tip="{esc(tip)}"><div class="code">{esc(f.fault_code)}</div><div class="badges">'
        f'<span class="badge s-{esc(f.status)}">{esc(f.status)}</span>'
        f'<span class="sev sev-{f.severity}">{esc(severity_name(f.severity))}</span>'
        f"{''.join(tags)}</div></div>"
        f'<div class="fault-track">{bands}{markers}</div></div>'
    )


def _timeline(result: Result, lanes: list[Lane], span: Span) -> str:
    legend = "".join(f'<span class="lg"><i class="sw s-{st}"></i>{st}</span>' for st in STATUSES)
    legend += "".join(
        f'<span class="lg"><i class="mk mk-{kind}"></i>{label}</span>'
        for kind, label in (
            ("fault_confirmed", "fault_confirmed"),
            ("fault_updated", "fault_updated"),
            ("fault_cleared", "fault_cleared"),
            ("clear", "ClearFault request"),
        )
    )
    ticks = "".join(
        f'<div class="tick" style="left:{_pct(100 * k / AXIS_TICKS)}"><span>'
        f"{seconds(span.duration_ns * k / AXIS_TICKS)}</span></div>"
        for k in range(AXIS_TICKS + 1)
    )
    rows = "".join(_row(i, lane, span) for i, lane in enumerate(lanes))
    capped = (
        f'<p class="cap-note">Showing {len(lanes):,} of {len(result.faults):,} faults (the '
        f"{ROW_CAP:,} most serious by status and severity); the Faults table lists all.</p>"
        if len(lanes) < len(result.faults)
        else ""
    )
    body = (
        f'<div id="tl-scroll" class="tl-scroll"><div id="tl-inner" class="tl-inner">'
        f'<div class="tl-axis-row"><div class="fault-label axis-label">seconds from start</div>'
        f'<div class="fault-track" id="tl-axis">{ticks}<div id="tl-brush" hidden></div></div></div>'
        f'<div id="tl-grid" aria-hidden="true"></div>{rows}</div></div>'
        if lanes
        else '<p class="empty">No fault was reported.</p>'
    )
    return (
        f'<section id="timeline"><h2>Fault timeline <span class="count">({len(lanes):,})'
        f'</span></h2><div class="tl-toolbar"><button type="button" data-zoom="in" title="zoom in">'
        f'+</button><button type="button" data-zoom="out" title="zoom out">&minus;</button>'
        f'<button type="button" data-zoom="reset">reset</button><span id="tl-range">'
        f"0.000 \u2013 {seconds(span.duration_ns)} s</span>"
        f'<input type="search" id="tl-filter" placeholder="filter faults…" aria-label="filter '
        f'faults"><span class="hint">wheel on the axis or Ctrl+wheel: zoom · drag on the axis: '
        f"zoom to a range · click a row: debounce counter and near misses</span></div>"
        f'<div class="legend">{legend}</div>{capped}{body}</section>'
    )


def _rules(result: Result) -> dict[str, dict[str, object]]:
    manager = result.config.get("fault_manager")
    correlation = manager.get("correlation") if isinstance(manager, dict) else None
    rules = correlation.get("rules") if isinstance(correlation, dict) else None
    if not isinstance(rules, list):
        return {}
    return {str(r.get("id")): r for r in rules if isinstance(r, dict)}


_LAST_DELAY = "last muted after root (ms)"
"""The muted table's delay column: upstream's delay_ms, which the last mute overwrote."""


def _correlation(result: Result, span: Span) -> str:
    rules = _rules(result)

    def rule_text(rule_id: str) -> str:
        rule = rules.get(rule_id, {})
        name = rule.get("name")
        return short(f"{rule_id} — {name}" if name else rule_id)

    muted_rows = []
    counts = event_counts(result) if result.muted_faults else {}
    for m in result.muted_faults:
        rule = rules.get(m.rule_id, {})
        mode = str(rule.get("mode", ""))
        window = rule.get("window_ms")
        within = f" (window {window} ms)" if window is not None else ""
        why = (
            f"a member of a cluster represented by {m.root_cause_code}{within}"
            if mode == "auto_cluster"
            else f"a symptom of root cause {m.root_cause_code}{within}"
        )
        muted_rows.append(
            [
                text(m.fault_code),
                text(m.root_cause_code),
                text(rule_text(m.rule_id)),
                (str(m.delay_ms), m.delay_ms),
                text(f"muted as {why}. {muting_sentence(counts.get(m.fault_code, NO_EVENTS), m)}"),
            ]
        )
    muted = table(
        "muted-table",
        "Muted faults",
        ["fault_code", "root cause", "rule", _LAST_DELAY, "why"],
        muted_rows,
        len(result.muted_faults),
        numeric=frozenset({_LAST_DELAY}),
    )
    cards = []
    for c in result.clusters:
        members = "".join(
            f'<li><span class="code-link" data-open="{esc(code)}">{esc(code)}</span>'
            + (' <span class="tag">representative</span>' if code == c.representative_code else "")
            + "</li>"
            for code in c.fault_codes
        )
        cards.append(
            f'<div class="cluster"><h4>{esc(short(c.cluster_id))} <span class="muted-text">'
            f"{esc(rule_text(c.rule_id))}</span></h4><p>{esc(clip(c.label, CELL_CAP))}</p><dl>"
            f'<dt>representative</dt><dd><span class="code-link" data-open="'
            f'{esc(c.representative_code)}">{esc(c.representative_code)}</span> '
            f"({esc(short(c.representative_severity))})</dd><dt>members</dt><dd>{c.count}<ul>{members}"
            f"</ul></dd><dt>span</dt><dd>{esc(span.label(c.first_at_ns))} \u2013 "
            f"{esc(span.label(c.last_at_ns))} ({seconds(c.last_at_ns - c.first_at_ns)} s)"
            f"</dd></dl></div>"
        )
    clusters = "".join(cards) or '<p class="empty">No active cluster at the end.</p>'
    retro = table(
        "retro-table",
        "Retroactive cluster mutes (information only)",
        ["t (s)", "cluster", "fault codes"],
        (
            [when(span, r.t_ns), text(r.cluster_id), text(listed(r.fault_codes))]
            for r in result.retroactive_mutes
        ),
        len(result.retroactive_mutes),
        numeric=frozenset({"t (s)"}),
    )
    return (
        f'<section id="correlation"><h2>Correlation</h2>{muted}<h3>Clusters '
        f'<span class="count">({len(result.clusters)})</span></h3><div class="clusters">'
        f"{clusters}</div>{retro}<p class=note>Upstream computes these codes as “retroactively "
        f"muted” when a cluster activates and only logs them; their events were not withheld."
        f"</p></section>"
    )


def _parity(parity: dict[str, object] | None, span: Span) -> str:
    if parity is None:
        return ""
    verdict = esc(short(parity.get("verdict", "")))
    return (
        f'<section id="parity"><h2>Parity with the recorded FaultEvents <span class="verdict '
        f'v-{verdict}">{verdict}</span></h2>{object_block("parity", parity, span)}</section>'
    )


def render_html(result: Result) -> str:
    """The whole page as text; the same Result always gives the same text."""
    span = Span.of(result)
    lanes = build_lanes(result, span)
    script = asset("report.js")
    digest = base64.b64encode(hashlib.sha256(script.encode("utf-8")).digest()).decode("ascii")
    csp = (
        "default-src 'none'; img-src data:; style-src 'unsafe-inline'; "
        f"script-src 'sha256-{digest}'; base-uri 'none'; form-action 'none'"
    )
    title = listed(i.path for i in result.inputs) or "no input"
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        f'<meta http-equiv="Content-Security-Policy" content="{csp}">'
        '<meta name="referrer" content="no-referrer">'
        f"<title>medkit-replay — {esc(title)}</title><style>{asset('report.css')}</style>"
        '</head><body><div id="js-errors" hidden></div><main>'
        + _header(result, span)
        + _timeline(result, lanes, span)
        + _correlation(result, span)
        + evidence_section(result, span)
        + '<section id="records"><h2>Records</h2>'
        + record_tables(result, span)
        + "</section>"
        + _parity(result.parity, span)
        + '<section id="config"><h2>Effective configuration</h2><details><summary>'
        "fault manager, bridges and replay options as the replay used them</summary>"
        + json_pre(result.config)
        + "</details></section></main>"
        + '<div id="tip" role="tooltip" hidden></div><svg id="svg-ns" width="0" height="0" '
        'aria-hidden="true"></svg><script type="application/json" id="medkit-data">'
        + script_json(page_data(lanes, span))
        + f"</script><script>{script}</script></body></html>\n"
    )


def write_html(result: Result, path: Path) -> None:
    """Write the page to a file (UTF-8) through a temporary file renamed into place."""
    page = render_html(result)
    with atomic_text(path) as stream:
        stream.write(page)
