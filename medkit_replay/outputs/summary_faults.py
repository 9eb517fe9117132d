"""The faults of the terminal summary: worst first, each with its story and what muted it.

Each fault is a row (code, status, severity, occurrences) sized to the codes shown, its story
from the transitions ("confirmed 65.751 s → healed 70.750 s → confirmed 136.750 s"), its
description, and what correlation did to its events, said from the events of the same report.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rich.text import Text

from medkit_replay.outputs.muting import NO_EVENTS, MutedEvents, event_counts, events_words
from medkit_replay.outputs.summary_lines import Piece, fixed, free, listing, piece, words
from medkit_replay.outputs.times import from_start
from medkit_replay.text import clip, printable, severity_name

if TYPE_CHECKING:
    from medkit_replay.model import FaultSnapshot, MutedFault
    from medkit_replay.result import Result

STATUS_RANK = {"CONFIRMED": 0, "PREFAILED": 1, "HEALED": 2}
"""Worst first: CONFIRMED, PREFAILED, HEALED, then the rest."""
STATUS_STYLES = {
    "CONFIRMED": "bold red",
    "HEALED": "green",
    "CLEARED": "cyan",
    "PREFAILED": "yellow",
    "PREPASSED": "dim",
}
SEVERITY_STYLES = {"INFO": "dim", "WARN": "yellow", "ERROR": "red", "CRITICAL": "bold red"}
STORY_STATUSES = {"CONFIRMED": "confirmed", "HEALED": "healed", "CLEARED": "cleared"}
"""The status changes a fault's story tells."""
MAX_TEXT = 256
"""Characters of a code, source or cluster id shown (a valid fault code has at most 256)."""
ARROW = " → "


def show(value: object, limit: int = MAX_TEXT) -> str:
    """Recorded text made safe for a terminal (medkit_replay/text.py ``printable``: line breaks
    and tabs become spaces, control and bidirectional characters escapes such as ``\\x1b``), so
    nothing a recording holds can move the cursor, recolour or reorder the screen; cut at
    ``limit`` characters with an ellipsis and the count of characters left out."""
    return printable(clip(str(value), limit))


@dataclass(frozen=True, slots=True)
class Facts:
    """What the summary tells per fault, gathered in one pass over the report's records."""

    stories: dict[str, list[tuple[str, int]]]
    events: dict[str, MutedEvents]
    """Per code, its FaultEvents withheld and published (outputs.muting)."""
    near_misses: Counter[str]
    muted: dict[str, MutedFault]


def gather(result: Result) -> Facts:
    """Stories (status changes in time order), events published and withheld, near misses."""
    stories: dict[str, list[tuple[str, int]]] = {}
    for transition in result.transitions:
        if transition.to_status in STORY_STATUSES:
            stories.setdefault(transition.fault_code, []).append(
                (transition.to_status, transition.t_ns)
            )
    return Facts(
        stories=stories,
        events=event_counts(result),
        near_misses=Counter(n.fault_code for n in result.near_misses),
        muted={m.fault_code: m for m in result.muted_faults},
    )


def worst_first(faults: tuple[FaultSnapshot, ...], facts: Facts) -> list[FaultSnapshot]:
    """Status (CONFIRMED, PREFAILED, HEALED, the rest), severity descending, first
    confirmation (never confirmed last), code."""

    def key(fault: FaultSnapshot) -> tuple[int, int, int, int, str]:
        confirmed = [
            t for status, t in facts.stories.get(fault.fault_code, ()) if status == "CONFIRMED"
        ]
        return (
            STATUS_RANK.get(fault.status, len(STATUS_RANK)),
            -fault.severity,
            0 if confirmed else 1,
            confirmed[0] if confirmed else 0,
            fault.fault_code,
        )

    return sorted(faults, key=key)


def story(steps: list[tuple[str, int]], origin_ns: int, width: int, everything: bool) -> str:
    """``confirmed 65.751 s → healed 70.750 s → …`` within ``width``: as many changes as fit,
    then ``+N more`` with the count of each change left out."""
    told = [f"{STORY_STATUSES[status]} {from_start(t, origin_ns)}" for status, t in steps]
    shown = len(told)
    if not everything:
        while shown > 1 and len(_story(told, steps, shown)) > width:
            shown -= 1
    return _story(told, steps, shown)


def _story(told: list[str], steps: list[tuple[str, int]], shown: int) -> str:
    line = ARROW.join(told[:shown])
    if shown == len(told):
        return line
    counts = Counter(STORY_STATUSES[status] for status, _ in steps[shown:])
    left = ", ".join(f"{n} {word}" for word, n in counts.items())
    return f"{line}{ARROW}+{len(told) - shown} more ({left})"


def muting_lines(code: str, facts: Facts, width: int) -> list[Text]:
    """What correlation muting did to one fault's events, from the events of the report:
    which were withheld, which published; the delay labelled as the last mute's."""
    muted = facts.muted.get(code)
    events = facts.events.get(code, NO_EVENTS)
    if muted is None and not events.withheld:
        return []
    pieces: list[Piece] = []
    if muted is not None:
        pieces += [
            piece("muted by ", "magenta"),
            piece(show(muted.root_cause_code), "bold magenta"),
            piece(f" (rule {show(muted.rule_id)},", "magenta"),
            piece(f" last muted {muted.delay_ms} ms after it);", "magenta"),
        ]
    else:
        pieces.append(piece("muted in its cluster;", "magenta"))
    pieces.append(piece(f" FaultEvents: {events_words(events)}", "magenta"))
    return words(pieces, width, indent=4)


@dataclass(frozen=True, slots=True)
class Columns:
    """Widths of the fault rows, sized to what they show."""

    code: int
    status: int
    severity: int
    occ: int

    def rest(self) -> int:
        return 2 + self.status + 2 + self.severity + 2 + self.occ


def columns(faults: list[FaultSnapshot], width: int) -> Columns:
    """Each column as wide as its widest cell; the code column gives way to the line."""
    status = max([len("status"), *(len(show(f.status)) for f in faults)])
    severity = max([len("severity"), *(len(severity_name(f.severity)) for f in faults)])
    occ = max([len("occ"), *(len(str(f.occurrence_count)) for f in faults)])
    cols = Columns(0, status, severity, occ)
    code = max([len("code"), *(len(show(f.fault_code)) for f in faults)])
    return Columns(min(code, max(width - cols.rest(), len("code"))), status, severity, occ)


def heading(cols: Columns) -> Text:
    return fixed(
        f"{'code':<{cols.code}}  {'status':<{cols.status}}  {'severity':<{cols.severity}}"
        f"  {'occ':>{cols.occ}}",
        "bold",
    )


def fault_lines(
    fault: FaultSnapshot,
    facts: Facts,
    cols: Columns,
    origin_ns: int,
    width: int,
    *,
    everything: bool,
) -> list[Text]:
    """One fault: its row (its code alone above when wider than the column), story,
    description, sources, clusters and muting."""
    code = show(fault.fault_code)
    lines: list[Text] = []
    row = Text()
    if len(code) > cols.code:
        lines.append(fixed(code, "bold"))
        row.append(" " * cols.code)
    else:
        row.append(code, style="bold")
        row.append(" " * (cols.code - len(code)))
    severity = severity_name(fault.severity)
    row.append("  ")
    row.append(f"{show(fault.status):<{cols.status}}", style=STATUS_STYLES.get(fault.status, ""))
    row.append("  ")
    row.append(f"{severity:<{cols.severity}}", style=SEVERITY_STYLES.get(severity, ""))
    row.append(f"  {fault.occurrence_count:>{cols.occ}}")
    lines.append(fixed(row))
    steps = facts.stories.get(fault.fault_code, [])
    if steps:
        told = story(steps, origin_ns, width - 2, everything)
    else:
        told = (
            f"reported failing {from_start(fault.first_occurred_ns, origin_ns)} to "
            f"{from_start(fault.last_occurred_ns, origin_ns)}, never confirmed"
        )
    lines.append(fixed("  " + told))
    near = facts.near_misses.get(fault.fault_code, 0)
    if near:
        lines.append(fixed(f"  {near} near miss" + ("" if near == 1 else "es"), "yellow"))
    if fault.description:
        lines.append(
            free(show(fault.description), width, indent=4, style="italic dim", whole=everything)
        )
    for head, style, items in (
        ("    from ", "dim", fault.reporting_sources),
        ("    cluster ", "blue", fault.cluster_ids),
    ):
        if items:
            shown = [show(item) for item in items]
            lines.append(listing(Text(head, style=style), shown, width, everything=everything))
    return lines + muting_lines(fault.fault_code, facts, width)
