"""The one result of a replay that every output reads: faults, events, transitions and more.

Plain frozen values; ``medkit_replay.tables(result)`` builds pandas DataFrames of them on request.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from medkit_replay import model

if TYPE_CHECKING:
    from collections.abc import Sequence

    from medkit_replay.model import (
        ClearRecord,
        Cluster,
        EvidenceRecording,
        FaultEvent,
        FaultSnapshot,
        InputSummary,
        Loss,
        MutedFault,
        NearMiss,
        ReportRecord,
        RetroactiveMute,
        SnapshotCapture,
        Transition,
    )

REPORT_SCHEMA = "medkit-replay/report/v1"
"""Schema of the JSON report a Result is written as (``outputs/json_report.py``)."""
STATUSES, EVENT_KINDS = model.STATUSES, model.EVENT_KINDS  # re-exported for outputs and checks


@dataclass(frozen=True, slots=True, kw_only=True)
class Summary:
    """Counts over the whole replay."""

    messages_read: int
    reports: int
    reports_accepted: int
    reports_rejected: int
    clears: int
    events: dict[str, int]
    faults: int
    faults_by_status: dict[str, int]
    transitions: int
    start_ns: int | None
    end_ns: int | None

    @property
    def duration_ns(self) -> int:
        """Span of bag time read (0 when nothing was read)."""
        if self.start_ns is None or self.end_ns is None:
            return 0
        return self.end_ns - self.start_ns


@dataclass(frozen=True, slots=True, kw_only=True)
class Result:
    """What the live fault manager would have concluded from the inputs."""

    tool_version: str
    inputs: tuple[InputSummary, ...]
    faults: tuple[FaultSnapshot, ...]
    events: Sequence[FaultEvent]
    transitions: Sequence[Transition]
    reports: Sequence[ReportRecord]
    clears: Sequence[ClearRecord]
    muted_faults: tuple[MutedFault, ...]
    clusters: tuple[Cluster, ...]
    near_misses: tuple[NearMiss, ...]
    retroactive_mutes: tuple[RetroactiveMute, ...] = ()
    parity: dict[str, object] | None = None
    warnings: tuple[str, ...] = ()
    summary: Summary
    config: dict[str, object] = field(default_factory=dict)
    snapshots: tuple[SnapshotCapture, ...] = ()
    recordings: tuple[EvidenceRecording, ...] = ()
    evidence_notes: tuple[str, ...] = ()
    fetched: dict[str, tuple[int, int]] = field(default_factory=dict)
    """Remote inputs by name: (bytes fetched, bytes of their files); not in the JSON report."""
    losses: tuple[Loss, ...] = ()
    """What damage cost, one per damage warning (each also in ``warnings``, which say it); not
    in the JSON report as a key of its own."""

    def losses_by_input(self) -> tuple[Loss, ...]:
        """What damage cost, in total per input that lost anything (in the order found)."""
        return model.losses_by_input(self.losses)

    def span(self) -> tuple[int | None, int | None]:
        """The recording's first and last log time: its inputs' spans and the messages read."""
        summary = self.summary
        starts = [i.start_ns for i in self.inputs if i.start_ns is not None]
        ends = [i.end_ns for i in self.inputs if i.end_ns is not None]
        if summary.start_ns is not None:
            starts.append(summary.start_ns)
        if summary.end_ns is not None:
            ends.append(summary.end_ns)
        return min(starts, default=None), max(ends, default=None)

    def fault(self, fault_code: str) -> FaultSnapshot | None:
        """The final state of one fault, or None when it was never reported."""
        return next((f for f in self.faults if f.fault_code == fault_code), None)
