"""The human summary of a replay, drawn with rich: colour on a terminal, plain text elsewhere.

Reads only the Result; the one place that prints. Every string that comes from a recording, a
script or a config (codes, descriptions, sources, paths, warnings) is shown literally: it goes into
``rich.text.Text`` objects or through ``rich.markup.escape``, never parsed as markup or emoji,
with controls escaped (text.py) and cut to a few hundred characters (the reports hold all).
"""

from __future__ import annotations

import re
import sys
from datetime import UTC, datetime
from typing import TYPE_CHECKING, TextIO

from rich import box
from rich.console import Group
from rich.markup import escape
from rich.padding import Padding
from rich.panel import Panel
from rich.table import Table
from rich.text import Text

from medkit_replay.model import read_in_part
from medkit_replay.outputs.console import draw, drawn, literal_console, plain_text
from medkit_replay.result import release_line
from medkit_replay.text import WARNING_CAP, clip, printable, seconds, severity_name

if TYPE_CHECKING:
    from rich.console import RenderableType

    from medkit_replay.model import Cluster, FaultSnapshot
    from medkit_replay.result import Result

SHOWN_STATUSES = ("CONFIRMED", "HEALED", "CLEARED")
"""The faults the table lists: those that reached a verdict."""

STATUS_STYLES = {
    "CONFIRMED": "bold red",
    "HEALED": "green",
    "CLEARED": "cyan",
    "PREFAILED": "yellow",
    "PREPASSED": "dim",
}
SEVERITY_STYLES = {"INFO": "dim", "WARN": "yellow", "ERROR": "red", "CRITICAL": "bold red"}
WIDE = 120
"""From this many columns on, sources and muting get columns of their own."""
MAX_ROWS = 200
"""Most faults listed; the JSON report and the tables have all of them."""
MAX_SOURCES = 3
MAX_DESCRIPTION = 100
"""Characters of a description shown; the reports have it whole."""
MAX_TEXT = 256
"""Characters of a source, a code, a cluster id shown (a valid fault code has at most 256, at
0.7.0; 128 at 0.6.0)."""
MAX_WARNING = WARNING_CAP
"""Characters of a warning (or a path) shown; the JSON report has it whole."""
MAX_EVIDENCE_LINES = 20
"""Freeze-frame captures and recordings listed each; the rest are counted."""
EPOCH_FLOOR_NS = 10**18
"""Bag times from here on (2001-09-09) are shown as UTC dates; smaller ones are script times."""
_CORRELATION_OFF = re.compile(r"correlation (is off|is disabled)", re.IGNORECASE)
_CORRELATION_ERROR = re.compile(r"correlation config error", re.IGNORECASE)


def correlation_disabled(warning: str) -> bool:
    """Whether a warning says correlation does not run (no muting, no clusters) this run."""
    return _CORRELATION_OFF.search(warning) is not None


def _show(value: object, limit: int = MAX_TEXT) -> str:
    """Recorded text made safe for a terminal (medkit_replay/text.py ``printable``: line breaks and
    tabs become spaces, control and bidirectional characters escapes such as ``\\x1b``), so
    nothing a recording holds can move the cursor, recolour or reorder the screen; cut at
    ``limit`` characters with an ellipsis and the count of characters left out."""
    return printable(clip(str(value), limit))


def _lit(value: object, style: str = "") -> Text:
    """Recorded text as a literal Text (never parsed as markup or emoji)."""
    return Text(_show(value), style=style)


def _markup(template: str, **values: object) -> Text:
    """Our markup template with every value made safe and escaped, so recorded text stays
    literal (``[bold red]`` in a description prints as written)."""
    escaped = {key: escape(_show(value, MAX_WARNING)) for key, value in values.items()}
    return Text.from_markup(template.format(**escaped), emoji=False)


def _fetched(fetched: int, size: int) -> Text:
    """How much of a remote input was fetched."""
    share = f" ({100 * fetched / size:.1f} %)" if size else ""
    return _markup(
        "  [dim]fetched {fetched} of {size}{share}[/dim]",
        fetched=_megabytes(fetched),
        size=_megabytes(size),
        share=share,
    )


def _megabytes(count: int) -> str:
    return f"{count / 1e6:,.1f} MB" if count >= 100_000 else f"{count:,} bytes"


def _plural(count: int, word: str) -> str:
    return f"{count} {word}" + ("" if count == 1 else "s")


def _hms(ns: int) -> tuple[str, int, int, int, int]:
    """Sign, hours, minutes, seconds and milliseconds of a span (milliseconds truncated)."""
    sign = "-" if ns < 0 else ""
    hours, rest = divmod(abs(ns) // 1_000_000, 3_600_000)
    minutes, rest = divmod(rest, 60_000)
    secs, millis = divmod(rest, 1000)
    return sign, hours, minutes, secs, millis


def _duration(ns: int) -> str:
    if ns < 1000 * 10**9:
        return f"{seconds(ns)} s"
    _, hours, minutes, secs, millis = _hms(ns)
    text = f"{minutes} min {secs:02d}.{millis:03d} s"
    return f"{hours} h {minutes:02d} min {secs:02d}.{millis:03d} s" if hours else text


class _Clock:
    """Formats bag times as offsets from the recording's start, one format for the whole run."""

    def __init__(self, origin_ns: int, length_ns: int) -> None:
        self.origin_ns = origin_ns
        self.long = length_ns >= 1000 * 10**9

    @property
    def unit(self) -> str:
        return "h:mm:ss" if self.long else "s"

    def offset(self, t_ns: int) -> str:
        if not self.long:
            return f"{seconds(t_ns - self.origin_ns)}"
        sign, hours, minutes, secs, millis = _hms(t_ns - self.origin_ns)
        return f"{sign}{hours}:{minutes:02d}:{secs:02d}.{millis:03d}"


def _start_text(t_ns: int) -> str:
    if t_ns >= EPOCH_FLOOR_NS:
        try:
            moment = datetime.fromtimestamp(t_ns // 10**9, tz=UTC)
        except (OverflowError, ValueError, OSError):  # past what a date can show (year 10000)
            return f"t = {t_ns // 10**9:,} s"
        stamp = moment.strftime("%Y-%m-%d %H:%M:%S")
        return f"{stamp}.{(t_ns % 10**9) // 10**6:03d} UTC"
    return f"t = {seconds(t_ns)} s"


def _header(result: Result, clock: _Clock | None, end_ns: int | None) -> list[RenderableType]:
    s = result.summary
    lines: list[RenderableType] = [
        _markup(
            "[bold]medkit-replay {version}[/bold]: {inputs}, {messages} read",
            version=result.tool_version,
            inputs=_plural(len(result.inputs), "input"),
            messages=_plural(s.messages_read, "message"),
        ),
        Text(release_line([result.upstream_release]), style="dim"),
    ]
    for summary in result.inputs[:3]:
        lines.append(
            _markup("  [dim]{path} ({storage})[/dim]", path=summary.path, storage=summary.storage)
        )
        if summary.path in result.fetched:
            lines.append(_fetched(*result.fetched[summary.path]))
    if len(result.inputs) > 3:
        lines.append(_markup("  [dim]... and {n} more[/dim]", n=len(result.inputs) - 3))
    for loss in result.losses_by_input():
        lines.append(_markup("[bold yellow]{lost}[/bold yellow]", lost=read_in_part(loss)))
    if clock is None or end_ns is None:
        lines.append(Text("recording: empty (no message read)"))
    else:
        lines.append(
            _markup(
                "recording: [bold]{length}[/bold] of bag time from {start}",
                length=_duration(end_ns - clock.origin_ns),
                start=_start_text(clock.origin_ns),
            )
        )
    events = s.events
    lines.append(
        _markup(
            "requests: {reports} ({rejected} rejected), {clears}",
            reports=_plural(s.reports, "report"),
            rejected=s.reports_rejected,
            clears=_plural(s.clears, "clear"),
        )
    )
    lines.append(
        _markup(
            "events published: {confirmed} confirmed, {updated} updated, {cleared} cleared",
            confirmed=events.get("fault_confirmed", 0),
            updated=events.get("fault_updated", 0),
            cleared=events.get("fault_cleared", 0),
        )
    )
    by_status = Text("faults: ")
    by_status.append(str(s.faults), style="bold")
    counted = [(status, n) for status, n in s.faults_by_status.items() if n]
    for number, (status, count) in enumerate(counted):
        by_status.append(" - " if number == 0 else ", ")
        by_status.append(status, style=STATUS_STYLES.get(status, ""))
        by_status.append(f" {count}")
    if result.near_misses:
        codes = len({n.fault_code for n in result.near_misses})
        by_status.append(f"; near misses: {len(result.near_misses)} for {_plural(codes, 'fault')}")
    lines.append(by_status)
    if result.parity is not None:
        lines.append(_parity_line(result.parity))
    return lines


def _parity_line(parity: dict[str, object]) -> Text:
    verdict = str(parity.get("verdict", ""))
    line = Text("parity with the recorded FaultEvents: ")
    line.append(verdict, style="green" if verdict == "match" else "bold yellow")
    line.append(
        f" ({parity.get('matched', 0)} of {parity.get('recorded_events', 0)} recorded matched"
        f", {parity.get('matched_with_differences', 0)} with differences"
        f", {parity.get('missing_in_replay', 0)} missing in the replay"
        f", {parity.get('extra_in_replay', 0)} extra)"
    )
    return line


def _sources(fault: FaultSnapshot) -> str:
    sources = [_show(source) for source in fault.reporting_sources[:MAX_SOURCES]]
    if len(fault.reporting_sources) > MAX_SOURCES:
        sources.append(f"+{len(fault.reporting_sources) - MAX_SOURCES} more")
    return ", ".join(sources)


def _notes(fault: FaultSnapshot) -> Text:
    notes = Text()
    if fault.muted:
        notes.append(f"muted by {_show(fault.root_cause_code or '?')}", style="magenta")
    for cluster_id in fault.cluster_ids:
        if notes:
            notes.append("\n")
        notes.append(f"cluster {_show(cluster_id)}", style="blue")
    return notes


def _faults_table(result: Result, clock: _Clock, width: int) -> Table | None:
    shown = [f for f in result.faults if f.status in SHOWN_STATUSES]
    if not shown:
        return None
    wide = width >= WIDE
    title = f"Faults confirmed, healed or cleared: {len(shown)}"
    if len(shown) > MAX_ROWS:
        title += f" (first {MAX_ROWS} listed)"
    title += f" (times in {clock.unit} from the start)"
    table = _table(title, leading=0 if wide else 1)
    table.add_column("code", overflow="fold", min_width=16)
    table.add_column("status", no_wrap=True)
    table.add_column("severity", no_wrap=True)
    table.add_column("first", justify="right", no_wrap=True)
    table.add_column("last", justify="right", no_wrap=True)
    table.add_column("occ", justify="right", no_wrap=True)
    if wide:
        table.add_column("sources", overflow="fold", max_width=40)
        table.add_column("muted by / cluster", overflow="fold")
    for fault in shown[:MAX_ROWS]:
        sources, notes = _sources(fault), _notes(fault)
        details: list[Text] = []
        if fault.description:
            description = fault.description
            if len(description) > MAX_DESCRIPTION:
                description = description[: MAX_DESCRIPTION - 3].rstrip() + "..."
            details.append(_lit(description, "italic dim"))
        if not wide:
            if sources:
                details.append(Text("from " + sources, style="dim"))
            if notes.plain:
                details.extend(notes.split())
        code = Group(
            _lit(fault.fault_code, "bold"),
            *(Padding(detail, (0, 0, 0, 2)) for detail in details),
        )
        severity = severity_name(fault.severity)
        cells: list[RenderableType] = [
            code,
            _lit(fault.status, STATUS_STYLES.get(fault.status, "")),
            Text(severity, style=SEVERITY_STYLES.get(severity, "")),
            Text(clock.offset(fault.first_occurred_ns)),
            Text(clock.offset(fault.last_occurred_ns)),
            Text(str(fault.occurrence_count)),
        ]
        if wide:
            cells += [Text(sources), notes]
        table.add_row(*cells)
    return table


def _cluster_codes(cluster: Cluster) -> Text:
    codes = Text()
    for number, code in enumerate(cluster.fault_codes):
        if number:
            codes.append(", ")
        codes.append(_show(code), style="bold" if code == cluster.representative_code else "")
    return codes


def _clusters(result: Result, clock: _Clock) -> Group | None:
    if not result.clusters:
        return None
    lines: list[RenderableType] = [Text(f"Clusters: {len(result.clusters)}", style="bold")]
    for cluster in result.clusters:
        line = _lit(cluster.cluster_id, "blue")
        line.append(f" ({_show(cluster.rule_name or cluster.rule_id)}): ")
        line.append(_show(cluster.representative_code), style="bold")
        line.append(" [")
        line.append(
            _show(cluster.representative_severity),
            style=SEVERITY_STYLES.get(cluster.representative_severity, ""),
        )
        line.append(f"] represents {_plural(cluster.count, 'fault')}, ")
        line.append(f"{clock.offset(cluster.first_at_ns)} to {clock.offset(cluster.last_at_ns)}: ")
        line.append_text(_cluster_codes(cluster))
        lines.append(Padding(line, (0, 0, 0, 2)))
    return Group(*lines)


def _evidence(result: Result, clock: _Clock) -> Group | None:
    """Counts of freeze-frame captures and black-box recordings, one line per recording."""
    captures, recordings = result.snapshots, result.recordings
    if not captures and not recordings:
        return None
    held = sum(1 for c in captures if c.retained)
    deleted = sum(1 for r in recordings if r.deleted_ns is not None)
    written = sum(1 for r in recordings if r.path is not None)
    head = Text("Evidence: ", style="bold")
    head.append(f"{_plural(len(captures), 'freeze-frame capture')} ({held} retained)")
    if recordings:
        head.append(
            f", {_plural(len(recordings), 'recording')} ({deleted} deleted by the live "
            f"manager, {written} written)"
        )
    lines: list[RenderableType] = [head]
    for capture in captures[:MAX_EVIDENCE_LINES]:
        line = Text(f"{clock.offset(capture.t_ns)}  ")
        line.append(_show(capture.fault_code), style="bold")
        topics = ", ".join(_show(t.topic) for t in capture.topics) or "nothing sampled"
        line.append(f"  capture {capture.capture_id}: {topics}")
        lines.append(Padding(line, (0, 0, 0, 2)))
    for recording in recordings[:MAX_EVIDENCE_LINES]:
        line = Text(f"{clock.offset(recording.start_ns)}-{clock.offset(recording.end_ns)}  ")
        line.append(_show(recording.recording_id), style="bold")
        size = recording.bytes
        shown = f"{size} B" if size < 1000 else f"{size / 1000:.1f} kB"
        line.append(f"  {recording.messages} msg, {shown}")
        lines.append(Padding(line, (0, 0, 0, 2)))
        if recording.deleted_reason is not None:
            gone = Text(f"deleted at {clock.offset(recording.deleted_ns or 0)}: ", style="yellow")
            gone.append(_show(recording.deleted_reason))
            lines.append(Padding(gone, (0, 0, 0, 4)))
    hidden = max(len(captures) - MAX_EVIDENCE_LINES, 0) + max(
        len(recordings) - MAX_EVIDENCE_LINES, 0
    )
    if hidden:
        lines.append(Padding(Text(f"... {hidden} more in the JSON report"), (0, 0, 0, 2)))
    for note in result.evidence_notes:
        lines.append(Padding(Text("note: " + _show(note, MAX_WARNING)), (0, 0, 0, 2)))
    return Group(*lines)


def _table(title: str, *, leading: int) -> Table:
    return Table(
        title=title,
        title_justify="left",
        title_style="bold",
        box=box.SIMPLE_HEAD,
        show_edge=False,
        pad_edge=False,
        padding=(0, 1),
        leading=leading,
    )


def _correlation_panel(warnings: list[str]) -> Panel:
    body = Text(
        "CORRELATION IS DISABLED FOR THIS RUN: no root-cause muting, no auto-clear of "
        "symptoms, no clusters (as the live fault manager with this config).",
        style="bold",
    )
    for warning in warnings:
        body.append("\n- ")
        body.append(_show(warning, MAX_WARNING))
    return Panel(
        body,
        title="correlation disabled",
        title_align="left",
        border_style="bold red",
        box=box.HEAVY,
    )


def _warnings(warnings: list[str]) -> Group:
    grid = Table.grid(padding=(0, 1))
    grid.add_column(no_wrap=True)
    grid.add_column(overflow="fold")
    for warning in warnings:
        grid.add_row(Text("!", style="bold yellow"), Text(_show(warning, MAX_WARNING)))
    return Group(Text(f"Warnings ({len(warnings)})", style="bold yellow"), grid)


def _is_loud(warning: str) -> bool:
    """Shown in the correlation panel: the warning that turned it off and the errors why."""
    return correlation_disabled(warning) or _CORRELATION_ERROR.search(warning) is not None


def summary_renderable(result: Result, width: int = 80) -> Group:
    """The whole summary as one rich renderable, laid out for ``width`` columns."""
    start_ns, end_ns = result.span()
    clock = _Clock(start_ns, (end_ns or start_ns) - start_ns) if start_ns is not None else None
    parts: list[RenderableType] = list(_header(result, clock, end_ns))
    off = any(correlation_disabled(w) for w in result.warnings)
    loud = [w for w in result.warnings if off and _is_loud(w)]
    other = [w for w in result.warnings if not (off and _is_loud(w))]
    if loud:
        parts += [Text(""), _correlation_panel(loud)]
    if clock is not None:
        faults = _faults_table(result, clock, width)
        parts += [Text(""), faults or Text("no fault confirmed, healed or cleared")]
        clusters = _clusters(result, clock)
        if clusters is not None:
            parts += [Text(""), clusters]
        evidence = _evidence(result, clock)
        if evidence is not None:
            parts += [Text(""), evidence]
    if other:
        parts += [Text(""), _warnings(other)]
    return Group(*parts)


def render_summary(result: Result, width: int = 80) -> str:
    """The summary as plain text (no ANSI codes) laid out for ``width`` columns."""
    return plain_text(summary_renderable(result, width), width)


def print_summary(result: Result, stream: TextIO | None = None) -> None:
    """Draw the summary on ``stream`` (standard output by default) with rich.

    Colour and the terminal's width when the stream is a terminal; plain text at 80 columns
    (or ``COLUMNS``) otherwise. ``NO_COLOR`` and ``FORCE_COLOR`` are honoured, as rich does.
    """
    console = literal_console(stream or sys.stdout)
    draw(console, summary_renderable(result, console.width))


def summary_text(result: Result, stream: TextIO) -> str:
    """The summary as :func:`print_summary` would draw it on ``stream``, to print later."""
    console = literal_console(stream)
    return drawn(console, summary_renderable(result, console.width))
