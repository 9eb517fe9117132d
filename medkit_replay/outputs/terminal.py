"""The short human summary of a replay, as plain text for a terminal or a log.

Reads only the Result; the one place that prints.
"""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, TextIO

if TYPE_CHECKING:
    from medkit_replay.result import Result


def _seconds(ns: int) -> str:
    return f"{ns / 1e9:.3f}s"


def render_summary(result: Result) -> str:
    """A few lines: span, counts, faults that confirmed or healed, clusters, warnings."""
    s = result.summary
    start = s.start_ns or 0
    lines = [
        f"medkit-replay {result.tool_version}: {len(result.inputs)} input(s), "
        f"{s.messages_read} message(s), {_seconds(s.duration_ns)} of bag time",
        f"reports: {s.reports} ({s.reports_rejected} rejected), clears: {s.clears}, "
        + "events: "
        + ", ".join(f"{k} {v}" for k, v in s.events.items()),
        "faults: " + (", ".join(f"{k} {v}" for k, v in s.faults_by_status.items() if v) or "none"),
    ]
    shown = [f for f in result.faults if f.status in ("CONFIRMED", "HEALED", "CLEARED")]
    if shown:
        lines.append("")
        lines.append(
            f"{'code':<32} {'status':<9} {'sev':>3} {'first':>10} {'last':>10} {'occ':>4}  notes"
        )
        for fault in shown:
            notes = []
            if fault.muted:
                notes.append(f"muted by {fault.root_cause_code}")
            if fault.cluster_ids:
                notes.append("cluster " + ",".join(fault.cluster_ids))
            lines.append(
                f"{fault.fault_code[:32]:<32} {fault.status:<9} {fault.severity:>3} "
                f"{_seconds(fault.first_occurred_ns - start):>10} "
                f"{_seconds(fault.last_occurred_ns - start):>10} {fault.occurrence_count:>4}  "
                + "; ".join(notes)
            )
    for cluster in result.clusters:
        lines.append(
            f"cluster {cluster.cluster_id} ({cluster.rule_name}): "
            f"{cluster.representative_code} represents {cluster.count} fault(s)"
        )
    for warning in result.warnings:
        lines.append(f"WARNING: {warning}")
    return "\n".join(lines) + "\n"


def echo(text: str, stream: TextIO | None = None) -> None:
    """Write text to a stream (standard output by default)."""
    print(text, end="", file=stream or sys.stdout)
