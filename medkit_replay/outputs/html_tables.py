"""Sortable, filterable HTML tables of the report's records, capped at a fixed number of rows.

Every text lands escaped, bidirectional controls and U+2028/9 as visible escapes, and cut at
CELL_CAP characters; numbers carry their sort key in ``data-v``. Reads only the Result.
"""

from __future__ import annotations

import html
import json
from itertools import islice
from typing import TYPE_CHECKING

from medkit_replay.outputs.html_timeline import LIST_CAP, TEXT_CAP
from medkit_replay.text import clip, seconds, severity_name, xml_text

if TYPE_CHECKING:
    from collections.abc import Iterable, Iterator

    from medkit_replay.outputs.html_timeline import Span
    from medkit_replay.result import Result

TABLE_CAP = 2000  # rows per table embedded in the page; the JSON report and CSV hold them all
CELL_CAP = 300  # characters of one cell shown (recorded text can be megabytes); JSON has it all

# (text shown, numeric sort key or None)
Cell = tuple[str, int | None]
Row = list[Cell]


def esc(text: object) -> str:
    """Text escaped for HTML content and quoted attributes; control and bidirectional
    characters, U+2028/9 and lone surrogates shown as escapes (``\\u202e``): see text.py."""
    return html.escape(xml_text(str(text)), quote=True)


def short(value: object, limit: int = TEXT_CAP) -> str:
    """Recorded text for a label or a tooltip: at most ``limit`` characters (ellipsis)."""
    return clip(str(value), limit)


def listed(items: Iterable[object], limit: int = LIST_CAP) -> str:
    """A list joined with commas: its first ``limit`` items (each cut), then ``+N more``."""
    shown: list[str] = []
    more = 0
    for item in items:
        if len(shown) < limit:
            shown.append(short(item))
        else:
            more += 1
    return ", ".join(shown) + (f", +{more:,} more" if more else "")


def text(value: object) -> Cell:
    """A text cell (None shows as an empty cell)."""
    return ("" if value is None else str(value), None)


def num(value: int) -> Cell:
    """A numeric cell."""
    return (str(value), value)


def when(span: Span, t_ns: int) -> Cell:
    """A bag-time cell: seconds since the recording's start, sorted by nanoseconds."""
    return (f"{seconds(t_ns - span.start_ns)}", t_ns - span.start_ns)


def table(
    table_id: str,
    title: str,
    columns: list[str],
    rows: Iterable[Row],
    total: int,
    *,
    numeric: frozenset[str] = frozenset(),
) -> str:
    """One section: a title, a filter box, the table (at most TABLE_CAP rows) and a cap note."""
    head = "".join(
        f'<th data-col="{i}"{" class=num" if name in numeric else ""} '
        f'title="sort by {esc(name)}">{esc(name)}</th>'
        for i, name in enumerate(columns)
    )
    codes = {i for i, name in enumerate(columns) if name == "fault_code"}
    body = []
    for row in islice(rows, TABLE_CAP):
        cells = "".join(
            f'<td data-v="{key}">{esc(clip(shown, CELL_CAP))}</td>'
            if key is not None
            else f'<td class="code">{esc(clip(shown, CELL_CAP))}</td>'
            if i in codes
            else f"<td>{esc(clip(shown, CELL_CAP))}</td>"
            for i, (shown, key) in enumerate(row)
        )
        body.append(f"<tr>{cells}</tr>")
    shown = len(body)
    note = (
        f'<p class="cap-note">Showing the first {shown:,} of {total:,} rows; the JSON report '
        f"(--json) and the CSV tables (--csv) hold them all.</p>"
        if total > shown
        else ""
    )
    heading = (
        f'<section class="table-block" id="{table_id}-section"><h3>{esc(title)} '
        f'<span class="count">({total:,})</span></h3>'
    )
    if not body:
        return f'{heading}<p class="empty">None.</p></section>'
    return (
        f'{heading}<div class="table-tools"><input type="search" class="filter" '
        f'data-filter-for="{table_id}" placeholder="filter {esc(title.lower())}…" '
        f'aria-label="filter {esc(title.lower())}"><span class="shown" data-shown-for="{table_id}">'
        f"</span></div>{note}"
        f'<div class="table-wrap"><table class="data sortable" id="{table_id}">'
        f"<thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table></div></section>"
    )


def _fault_rows(result: Result, span: Span) -> Iterator[Row]:
    for f in result.faults:
        yield [
            text(f.fault_code),
            text(f.status),
            (severity_name(f.severity), f.severity),
            text(f.description),
            when(span, f.first_occurred_ns),
            when(span, f.last_occurred_ns),
            when(span, f.last_passed_ns) if f.last_passed_ns else ("never", -1),
            num(f.occurrence_count),
            text(listed(f.reporting_sources)),
            text(f"by {f.root_cause_code}" if f.muted else ""),
            text(listed(f.cluster_ids)),
        ]


def _event_rows(result: Result, span: Span) -> Iterator[Row]:
    for e in result.events:
        yield [
            when(span, e.t_ns),
            text(e.event_type),
            text(e.fault.fault_code),
            text(e.fault.status),
            (severity_name(e.fault.severity), e.fault.severity),
            num(e.fault.occurrence_count),
            text(listed(e.fault.reporting_sources)),
            text(listed(e.auto_cleared_codes)),
        ]


def _report_rows(result: Result, span: Span) -> Iterator[Row]:
    for r in result.reports:
        yield [
            when(span, r.t_ns),
            text(r.origin),
            text(r.topic),
            text(r.fault_code),
            text(r.event_type),
            (severity_name(r.severity), r.severity),
            text(r.description),
            text(r.source_id),
            text("yes" if r.accepted else f"no: {r.reject_reason or ''}"),
            num(r.debounce_counter) if r.debounce_counter is not None else text(""),
            text(r.status),
        ]


def _transition_rows(result: Result, span: Span) -> Iterator[Row]:
    for t in result.transitions:
        yield [
            when(span, t.t_ns),
            text(t.fault_code),
            text(t.from_status or "(new)"),
            text(t.to_status),
            text(t.cause),
            text(t.source_id),
        ]


def _clear_rows(result: Result, span: Span) -> Iterator[Row]:
    for c in result.clears:
        yield [
            when(span, c.t_ns),
            text(c.fault_code),
            text("yes" if c.skip_correlation_auto_clear else "no"),
            text("yes" if c.success else "no"),
            text(c.message),
            text(listed(c.auto_cleared_codes)),
        ]


def record_tables(result: Result, span: Span) -> str:
    """Faults, events, reports, transitions and clears, each sortable and filterable."""
    t = frozenset({"t (s)", "first (s)", "last (s)", "last passed (s)", "occurrences"})
    sev = frozenset({"severity", "counter"})
    return "".join(
        [
            table(
                "faults-table",
                "Faults",
                [
                    "fault_code",
                    "status",
                    "severity",
                    "description",
                    "first (s)",
                    "last (s)",
                    "last passed (s)",
                    "occurrences",
                    "reporting sources",
                    "muted",
                    "clusters",
                ],
                _fault_rows(result, span),
                len(result.faults),
                numeric=t | sev,
            ),
            table(
                "events-table",
                "Events",
                [
                    "t (s)",
                    "event_type",
                    "fault_code",
                    "status",
                    "severity",
                    "occurrences",
                    "reporting sources",
                    "auto-cleared codes",
                ],
                _event_rows(result, span),
                len(result.events),
                numeric=t | sev,
            ),
            table(
                "reports-table",
                "Reports",
                [
                    "t (s)",
                    "origin",
                    "topic",
                    "fault_code",
                    "event_type",
                    "severity",
                    "description",
                    "source_id",
                    "accepted",
                    "counter",
                    "status after",
                ],
                _report_rows(result, span),
                len(result.reports),
                numeric=t | sev,
            ),
            table(
                "transitions-table",
                "Transitions",
                ["t (s)", "fault_code", "from", "to", "cause", "source_id"],
                _transition_rows(result, span),
                len(result.transitions),
                numeric=t,
            ),
            table(
                "clears-table",
                "Clears",
                ["t (s)", "fault_code", "skip auto-clear", "success", "message", "auto-cleared"],
                _clear_rows(result, span),
                len(result.clears),
                numeric=t,
            ),
        ]
    )


def json_pre(value: object) -> str:
    """A value as indented JSON in a <pre>, escaped."""
    return f"<pre class=json>{esc(json.dumps(value, indent=2, default=str))}</pre>"


def _cell(key: str, value: object, span: Span) -> Cell:
    if key.endswith("t_ns") and isinstance(value, int) and not isinstance(value, bool):
        return when(span, value)
    if isinstance(value, int) and not isinstance(value, bool):
        return num(value)
    if isinstance(value, list | dict):
        return text(json.dumps(value, separators=(", ", ": "), default=str))
    return text(value)


def object_block(name: str, value: dict[str, object], span: Span) -> str:
    """A JSON object for people: scalars as a list, lists of objects as sortable tables."""
    scalars = "".join(
        f"<dt>{esc(short(k))}</dt>"
        f"<dd>{esc(short(json.dumps(v) if v is None or isinstance(v, bool) else v, CELL_CAP))}</dd>"
        for k, v in value.items()
        if not isinstance(v, list | dict)
    )
    blocks = []
    for key, item in value.items():
        slug = f"{name}-{key}".replace("_", "-").lower()
        if isinstance(item, dict):
            blocks.append(
                f"<h4>{esc(short(key))}</h4><div class=nested>"
                f"{object_block(slug, item, span)}</div>"
            )
        elif isinstance(item, list):
            rows = [r if isinstance(r, dict) else {"value": r} for r in item]
            columns = list(dict.fromkeys(k for r in rows for k in r))
            blocks.append(
                table(
                    slug,
                    key,
                    [c.removesuffix("_ns") + " (s)" if c.endswith("t_ns") else c for c in columns],
                    ([_cell(c, r.get(c), span) for c in columns] for r in rows),
                    len(rows),
                    numeric=frozenset(
                        c.removesuffix("_ns") + " (s)" for c in columns if c.endswith("t_ns")
                    ),
                )
            )
    return f'<dl class="kv">{scalars}</dl>{"".join(blocks)}'
