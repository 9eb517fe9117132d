"""Several fault managers driven as one by a single pass over a recording (a sweep's variants).

Each variant has its own FaultManager and Timeline, the one implementation; this only hands every
request and every timer step to all of them, in the same order a replay of each would.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.engine.timeline import Timeline

if TYPE_CHECKING:
    from collections.abc import Sequence

    from medkit_replay.engine.manager import FaultManager
    from medkit_replay.model import ClearRequest, Origin, ReportRequest


class FanOut:
    """A Clock, request target and report sink for the replay loop that drives many managers.

    ``report_fields`` gives a bridge's request to every manager in turn; ``advance`` runs the
    timers of those that are due. Managers do not see each other: each gets exactly the calls a
    replay of it alone would make.
    """

    def __init__(self, managers: Sequence[FaultManager]) -> None:
        self.timelines = [Timeline(manager) for manager in managers]
        self._reporters = [manager.report_fields for manager in managers]
        self.last_ns: int | None = None
        self._due = -(2**63)

    def due_ns(self) -> int:
        """The earliest message time at which some manager has a timer to run."""
        return self._due

    def advance(self, t_ns: int) -> None:
        """Run every manager's timer ticks due at or before ``t_ns``."""
        self.last_ns = t_ns
        due = 2**63
        for timeline in self.timelines:
            if t_ns >= timeline.due_ns():
                timeline.advance(t_ns)
            else:
                timeline.last_ns = t_ns
            due = min(due, timeline.due_ns())
        self._due = due

    def apply(self, request: ReportRequest | ClearRequest) -> None:
        """One request object (a script's, a recorded service call's) to every manager."""
        for timeline in self.timelines:
            timeline.apply(request)

    def report_fields(
        self,
        t_ns: int,
        origin: Origin,
        topic: str | None,
        fault_code: str,
        event_type: int,
        severity: int,
        description: str,
        source_id: str,
    ) -> None:
        """One bridge request, field by field, to every manager (a :class:`ReportSink`).

        Its fields named, not ``*request``: a sweep runs this per bridge request, and forwarding
        a packed tuple costs more per call (see ``FaultManager.report_fields``).
        """
        for report in self._reporters:
            report(t_ns, origin, topic, fault_code, event_type, severity, description, source_id)

    def finish(self) -> None:
        """Note the last message's time on every timeline (the loop sets it on this one)."""
        for timeline in self.timelines:
            timeline.last_ns = self.last_ns
