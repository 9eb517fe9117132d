"""The engine's four record logs as spools, so that memory stays bounded however long the run,
and the EngineOutput that fills them: one replay's, or one tuning variant's."""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

from medkit_replay.model import (
    CLEAR_ROWS,
    EVENT_ROWS,
    REPORT_ROWS,
    TRANSITION_ROWS,
    ClearRecord,
    EngineOutput,
    FaultEvent,
    ReportRecord,
    Transition,
)
from medkit_replay.spool import Spool

if TYPE_CHECKING:
    from medkit_replay.spool import SpillListener


class SpooledLogs(NamedTuple):
    """Events, transitions, reports and clears, each in its spool (in the report's order)."""

    events: Spool[FaultEvent]
    transitions: Spool[Transition]
    reports: Spool[ReportRecord]
    clears: Spool[ClearRecord]

    def output(self) -> EngineOutput:
        """An engine output that appends to these spools."""
        return EngineOutput(
            events=self.events,
            transitions=self.transitions,
            reports=self.reports,
            clears=self.clears,
        )


def spooled_logs(listener: SpillListener | None = None) -> SpooledLogs:
    """Four empty spools; ``listener`` is told of every chunk any of them spills."""
    return SpooledLogs(
        Spool(codec=EVENT_ROWS, listener=listener),
        Spool(codec=TRANSITION_ROWS, listener=listener),
        Spool(codec=REPORT_ROWS, listener=listener),
        Spool(codec=CLEAR_ROWS, listener=listener),
    )
