"""The human summary of a replay, drawn with rich: colour on a terminal, plain text elsewhere.

Reads only the Result; the one place that prints. Laid out by hand (summary_lines.py) so that no
code, name or number is split, and cut to MAX_LINES lines unless ``--all``. Every string that
comes from a recording, a script or a config (codes, descriptions, sources, paths, warnings) is
shown literally: it goes into ``rich.text.Text`` objects or through ``rich.markup.escape``, never
parsed as markup or emoji, with controls escaped (text.py) and cut to a few hundred characters
(the reports hold all).
"""

from __future__ import annotations

import re
import sys
from typing import TYPE_CHECKING, TextIO

from rich import box
from rich.console import Group
from rich.markup import escape
from rich.panel import Panel
from rich.text import Text

from medkit_replay.model import read_in_part
from medkit_replay.outputs.console import draw, drawn, literal_console, plain_text
from medkit_replay.outputs.summary_faults import (
    STATUS_STYLES,
    Facts,
    columns,
    fault_lines,
    gather,
    heading,
    show,
    worst_first,
)
from medkit_replay.outputs.summary_lines import fixed, free, listing, piece, words
from medkit_replay.outputs.times import from_start, start_text
from medkit_replay.result import release_line
from medkit_replay.text import WARNING_CAP, seconds

if TYPE_CHECKING:
    from rich.console import RenderableType

    from medkit_replay.result import Result

MAX_LINES = 60
"""Lines of the summary by default (``--all``: every line); the reports have everything."""
MAX_CLUSTERS = 3
"""Clusters listed by default."""
MAX_WARNINGS = 5
"""Warnings listed by default, each on one line."""
CUT_POINTER = "cut to fit a screen: --all prints everything; --html or --json FILE has it all"
MAX_WARNING = WARNING_CAP
"""Characters of a warning (or a path) shown; the JSON report has it whole."""
MAX_EVIDENCE_LINES = 3
"""Freeze-frame captures and recordings listed each by default; the rest are counted."""
_CORRELATION_OFF = re.compile(r"correlation (is off|is disabled)", re.IGNORECASE)
_CORRELATION_ERROR = re.compile(r"correlation config error", re.IGNORECASE)


def correlation_disabled(warning: str) -> bool:
    """Whether a warning says correlation does not run (no muting, no clusters) this run."""
    return _CORRELATION_OFF.search(warning) is not None


def _markup(template: str, **values: object) -> Text:
    """Our markup template with every value made safe and escaped, so recorded text stays
    literal (``[bold red]`` in a description prints as written)."""
    escaped = {key: escape(show(value, MAX_WARNING)) for key, value in values.items()}
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


def _header(
    result: Result,
    span: tuple[int | None, int | None],
    facts: Facts,
    width: int,
    everything: bool,
) -> list[RenderableType]:
    start_ns, end_ns = span
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
        path = show(summary.path, MAX_WARNING)
        lines += words(
            [piece(path, "dim", whole=True), piece(f" ({show(summary.storage)})", "dim")],
            width,
            indent=2,
        )
        if summary.path in result.fetched:
            lines.append(_fetched(*result.fetched[summary.path]))
    if len(result.inputs) > 3:
        lines.append(fixed(f"  +{len(result.inputs) - 3} more inputs", "dim"))
    for loss in result.losses_by_input():
        lines.append(_markup("[bold yellow]{lost}[/bold yellow]", lost=read_in_part(loss)))
    if start_ns is None or end_ns is None:
        lines.append(Text("recording: empty (no message read)"))
    else:
        lines += words(
            [
                piece("recording: "),
                piece(_duration(end_ns - start_ns), "bold", whole=True),
                piece(" of bag time from "),
                piece(start_text(start_ns, whole_beyond=True), whole=True),
            ],
            width,
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
    lines.append(by_status)
    near = _near_misses(result, facts, width, everything)
    if near is not None:
        lines.append(near)
    nothing = _nothing_reported(result)
    if nothing is not None:
        lines.append(nothing)
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


def _faults(
    result: Result, facts: Facts, origin_ns: int, width: int, room: int | None
) -> tuple[list[Text], int]:
    """The faults worst first, as many as ``room`` lines hold (all when None); and how many
    were left out."""
    if not result.faults:
        return [fixed("no fault reported")], 0
    ordered = worst_first(result.faults, facts)
    cols = columns(ordered, width)
    title = fixed(f"Faults: {len(ordered)}, worst first (times in s from the start)", "bold")
    lines = [title, heading(cols)]
    shown = 0
    for fault in ordered:
        block = fault_lines(fault, facts, cols, origin_ns, width, everything=room is None)
        more = 1 if shown + 1 < len(ordered) else 0
        if room is not None and shown and len(lines) + len(block) + more > room:
            break
        lines += block
        shown += 1
    left = len(ordered) - shown
    if left:
        lines.append(fixed(f"+{left} more faults"))
    return lines, left


def _clusters(result: Result, origin_ns: int, width: int, everything: bool) -> list[Text]:
    if not result.clusters:
        return []
    lines = [fixed(f"Clusters: {len(result.clusters)}", "bold")]
    shown = result.clusters if everything else result.clusters[:MAX_CLUSTERS]
    for cluster in shown:
        representative = show(cluster.representative_code)
        lines += words(
            [
                piece(show(cluster.cluster_id), "blue", whole=True),
                piece(f" ({show(cluster.rule_name or cluster.rule_id)}), "),
                piece(from_start(cluster.first_at_ns, origin_ns), whole=True),
                piece(" to "),
                piece(from_start(cluster.last_at_ns, origin_ns) + ",", whole=True),
                piece(f" {_plural(cluster.count, 'fault')}, represented by "),
                piece(representative, "bold", whole=True),
            ],
            width,
            indent=2,
        )
        lines.append(
            listing(
                Text("    "),
                [show(code) for code in cluster.fault_codes],
                width,
                everything=everything,
            )
        )
    if len(result.clusters) > len(shown):
        lines.append(fixed(f"  +{len(result.clusters) - len(shown)} more clusters"))
    return lines


def _near_misses(result: Result, facts: Facts, width: int, everything: bool) -> Text | None:
    if not result.near_misses:
        return None
    head = Text(f"near misses: {len(result.near_misses)}, for ")
    codes = sorted(facts.near_misses, key=lambda code: (-facts.near_misses[code], code))
    return listing(
        head,
        [f"{show(code)} ({facts.near_misses[code]})" for code in codes],
        width,
        everything=everything,
    )


def _evidence(result: Result, origin_ns: int, width: int, everything: bool) -> Group | None:
    """Counts of freeze-frame captures and black-box recordings, one line per recording."""
    captures, recordings = result.snapshots, result.recordings
    if not captures and not recordings:
        return None
    limit = None if everything else MAX_EVIDENCE_LINES
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
    for capture in captures[:limit]:
        names = [show(t.topic) for t in capture.topics]
        topics = [
            piece(f" {name}{',' if number < len(names) - 1 else ''}", whole=True)
            for number, name in enumerate(names)
        ]
        lines += words(
            [
                piece(from_start(capture.t_ns, origin_ns), whole=True),
                piece(" "),
                piece(show(capture.fault_code), "bold", whole=True),
                piece(f" capture {capture.capture_id}: "),
                *(topics or [piece("nothing sampled")]),
            ],
            width,
            indent=2,
        )
    for recording in recordings[:limit]:
        line = Text(
            f"  {from_start(recording.start_ns, origin_ns)} to "
            f"{from_start(recording.end_ns, origin_ns)}  "
        )
        line.append(show(recording.recording_id), style="bold")
        size = recording.bytes
        shown = f"{size} B" if size < 1000 else f"{size / 1000:.1f} kB"
        line.append(f"  {recording.messages} msg, {shown}")
        lines.append(fixed(line))
        if recording.deleted_reason is not None:
            at = from_start(recording.deleted_ns or 0, origin_ns)
            gone = [piece(f"deleted at {at}:", "yellow", whole=True), piece(" ")]
            gone.append(piece(show(recording.deleted_reason)))
            lines += words(gone, width, indent=4, hang=6)
    hidden = 0 if limit is None else max(len(captures) - limit, 0) + max(len(recordings) - limit, 0)
    if hidden:
        lines.append(fixed(f"  +{hidden} more in the JSON report"))
    for note in result.evidence_notes:
        lines.append(free("note: " + show(note, MAX_WARNING), width, indent=2, whole=everything))
    return Group(*lines)


def _correlation_panel(warnings: list[str]) -> Panel:
    body = Text(
        "CORRELATION IS DISABLED FOR THIS RUN: no root-cause muting, no auto-clear of "
        "symptoms, no clusters (as the live fault manager with this config).",
        style="bold",
    )
    for warning in warnings:
        body.append("\n- ")
        body.append(show(warning, MAX_WARNING))
    return Panel(
        body,
        title="correlation disabled",
        title_align="left",
        border_style="bold red",
        box=box.HEAVY,
    )


def _warnings(warnings: list[str], width: int, everything: bool) -> list[RenderableType]:
    shown = warnings if everything else warnings[:MAX_WARNINGS]
    lines: list[RenderableType] = [fixed(f"Warnings ({len(warnings)})", "bold yellow")]
    for warning in shown:
        text = show(warning, MAX_WARNING)
        lines.append(free("! " + text, width, indent=0, whole=everything))
    if len(warnings) > len(shown):
        lines.append(fixed(f"+{len(warnings) - len(shown)} more warnings"))
    return lines


def _nothing_reported(result: Result) -> Text | None:
    """Why a replay whose bridges ran made no report, from what each took (the checks' fact)."""
    consumed = result.consumed
    if consumed is None or consumed.empty or result.summary.reports or result.summary.clears:
        return None  # an empty replay is said in its warnings, with how to read what it holds
    return Text(consumed.no_report())


def _is_loud(warning: str) -> bool:
    """Shown in the correlation panel: the warning that turned it off and the errors why."""
    return correlation_disabled(warning) or _CORRELATION_ERROR.search(warning) is not None


def _height(parts: list[RenderableType], width: int) -> int:
    return len(plain_text(Group(*parts), width, crop=False).splitlines()) if parts else 0


def summary_renderable(result: Result, width: int = 80, *, everything: bool = False) -> Group:
    """The whole summary as one rich renderable, laid out for ``width`` columns: at most
    MAX_LINES lines unless ``everything``, the worst faults first."""
    start_ns, end_ns = result.span()
    facts = gather(result)
    head: list[RenderableType] = list(_header(result, (start_ns, end_ns), facts, width, everything))
    off = any(correlation_disabled(w) for w in result.warnings)
    loud = [w for w in result.warnings if off and _is_loud(w)]
    other = [w for w in result.warnings if not (off and _is_loud(w))]
    if loud:
        head += [Text(""), _correlation_panel(loud)]
    tail: list[RenderableType] = []
    if start_ns is not None:
        clusters = _clusters(result, start_ns, width, everything)
        if clusters:
            tail += [Text(""), *clusters]
        evidence = _evidence(result, start_ns, width, everything)
        if evidence is not None:
            tail += [Text(""), evidence]
    if other:
        tail += [Text(""), *_warnings(other, width, everything)]
    if start_ns is None:
        return Group(*head, *tail)
    pointer = words([piece(CUT_POINTER, "dim")], width)
    used = _height(head, width) + _height(tail, width) + 1 + len(pointer)
    room = None if everything else MAX_LINES - used
    faults, left = _faults(result, facts, start_ns, width, room)
    cut = not everything and (
        left
        or len(result.clusters) > MAX_CLUSTERS
        or len(other) > MAX_WARNINGS
        or len(result.snapshots) > MAX_EVIDENCE_LINES
        or len(result.recordings) > MAX_EVIDENCE_LINES
    )
    return Group(*head, Text(""), *faults, *tail, *(pointer if cut else []))


def render_summary(result: Result, width: int = 80, *, everything: bool = False) -> str:
    """The summary as plain text (no ANSI codes) laid out for ``width`` columns."""
    return plain_text(summary_renderable(result, width, everything=everything), width, crop=False)


def print_summary(
    result: Result, stream: TextIO | None = None, *, everything: bool = False
) -> None:
    """Draw the summary on ``stream`` (standard output by default) with rich.

    Colour and the terminal's width when the stream is a terminal; plain text at 80 columns
    (or ``COLUMNS``) otherwise. ``NO_COLOR`` and ``FORCE_COLOR`` are honoured, as rich does.
    """
    console = literal_console(stream or sys.stdout)
    draw(console, summary_renderable(result, console.width, everything=everything), crop=False)


def summary_text(result: Result, stream: TextIO, *, everything: bool = False) -> str:
    """The summary as :func:`print_summary` would draw it on ``stream``, to print later."""
    console = literal_console(stream)
    renderable = summary_renderable(result, console.width, everything=everything)
    return drawn(console, renderable, crop=False)
