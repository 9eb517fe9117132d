"""The Result of a replay, assembled from the manager's final state and the spooled records.

Counts for the summary come from running totals, never from reading the spools back.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.result import EVENT_KINDS, STATUSES, Result, Summary
from medkit_replay.version import __version__

if TYPE_CHECKING:
    from collections.abc import Sequence

    from medkit_replay.engine.manager import FaultManager
    from medkit_replay.engine.timeline import Timeline
    from medkit_replay.model import (
        ClearRecord,
        EngineOutput,
        FaultEvent,
        InputSummary,
        ReportRecord,
        Transition,
    )
    from medkit_replay.result import Consumption
    from medkit_replay.spool import Spool


def assemble_result(
    manager: FaultManager,
    timeline: Timeline,
    output: EngineOutput,
    summaries: Sequence[InputSummary],
    messages: int,
    warnings: list[str],
    parity: dict[str, object] | None,
    logs: tuple[Spool[FaultEvent], Spool[Transition], Spool[ReportRecord], Spool[ClearRecord]],
    config: dict[str, object],
    consumed: Consumption | None = None,
) -> Result:
    events, transitions, reports, clears = logs
    faults = manager.faults()
    correlation = manager.correlation
    near_misses = [
        entry
        for code in sorted(manager.storage.near_misses, key=lambda c: c.encode("utf-8"))
        for entry in manager.storage.near_misses[code]
    ]
    by_status: dict[str, int] = dict.fromkeys(STATUSES, 0)
    for fault in faults:
        by_status[fault.status] += 1
    by_event: dict[str, int] = {kind: output.event_counts.get(kind, 0) for kind in EVENT_KINDS}
    accepted = output.reports_accepted
    summary = Summary(
        messages_read=messages,
        reports=len(reports),
        reports_accepted=accepted,
        reports_rejected=len(reports) - accepted,
        clears=len(clears),
        events=by_event,
        faults=len(faults),
        faults_by_status=by_status,
        transitions=len(transitions),
        start_ns=timeline.t0_ns,
        end_ns=timeline.last_ns,
    )
    return Result(
        tool_version=__version__,
        upstream_release=manager.config.release.name,
        inputs=tuple(summaries),
        faults=tuple(faults),
        events=events,
        transitions=transitions,
        reports=reports,
        clears=clears,
        muted_faults=tuple(correlation.muted_faults()) if correlation else (),
        clusters=tuple(correlation.clusters()) if correlation else (),
        near_misses=tuple(near_misses),
        retroactive_mutes=tuple(output.retroactive_mutes),
        parity=parity,
        warnings=tuple(warnings + output.warnings),
        summary=summary,
        config=config,
        consumed=consumed,
        event_tally=(
            {code: dict(kinds) for code, kinds in output.published_by_code.items()},
            {code: dict(kinds) for code, kinds in output.withheld_by_code.items()},
        ),
    )
