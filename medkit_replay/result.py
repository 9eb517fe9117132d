"""The one result of a replay that every output reads: faults, events, transitions and more.

Plain frozen values; ``medkit_replay.tables(result)`` builds pandas DataFrames of them on request.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from medkit_replay import model
from medkit_replay.releases import DEFAULT_RELEASE, RELEASES

if TYPE_CHECKING:
    from collections.abc import Sequence

    from medkit_replay.captures import EvidenceRecording, SnapshotCapture
    from medkit_replay.model import (
        ClearRecord,
        Cluster,
        EventTally,
        FaultEvent,
        FaultSnapshot,
        InputSummary,
        Loss,
        MutedFault,
        NearMiss,
        ReportRecord,
        RetroactiveMute,
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


@dataclass(frozen=True, slots=True)
class TopicUse:
    """Messages on one topic and the path that reads them, named as requests name their origin
    (a bridge, ``report_fault`` or ``clear_fault`` for recorded calls, ``script``), or
    ``fault_events``: recorded FaultEvents, compared under ``parity``, which raise nothing."""

    origin: str
    topic: str
    messages: int


_FED = ("diagnostic_bridge", "action_status_bridge", "log_bridge", "script")
"""Paths into the fault manager fed by messages (recorded calls count by call, not message)."""


def _count(number: int, word: str) -> str:
    return f"{number:,} {word}" + ("" if number == 1 else "s")


RELEASE_PARAMETER = "medkit_replay.upstream_release"
"""The parameter that chooses the ros2_medkit release modelled (``config/release.py``)."""


def release_line(names: Sequence[str]) -> str:
    """What every summary's header says of the release(s) modelled, and how to choose another."""
    known = ", ".join(RELEASES)
    named = " and ".join(name for name in RELEASES if name in names)
    return f"ros2_medkit {named} modelled ({RELEASE_PARAMETER}: {known})"


LOG_BRIDGE_HINT = "medkit_replay: {enable_log_bridge: true}"
"""The parameter that turns the log bridge on (a ``log_bridge`` section does too)."""


@dataclass(frozen=True, slots=True, kw_only=True)
class Consumption:
    """Which paths into the fault manager took how much of the recording: computed once by
    the replay, as it routed the messages. Not in the JSON report.

    Attributes:
        messages_read: every message the replay read (``Summary.messages_read``).
        holds_messages: some input holds a message, read or not.
        diagnostics_topic: the diagnostic bridge's topic.
        rosout_topic: the log bridge's topic (``/rosout`` while it is off).
        log_bridge: the log bridge was on.
        taken: per path and topic, the topics a path took messages from, in path then topic
            order; ``messages`` are those the recording holds on the topic (its index's count,
            or the count found while reading it; 0 when no input counts them): a message that
            could not be decoded is among them, and said in the warnings.
        report_calls, clear_calls: recorded ReportFault / ClearFault calls applied.
        metadata_only: recorded calls without their request (metadata-only introspection),
            which cannot be replayed.
        unread: topics a path would read if configured so (origin: that path): log messages
            while the log bridge is off, DiagnosticArrays on another topic than the bridge's.
        log_floor: the lowest log level the log bridge reports.
    """

    messages_read: int
    holds_messages: bool
    diagnostics_topic: str
    rosout_topic: str
    log_bridge: bool
    taken: tuple[TopicUse, ...] = ()
    report_calls: int = 0
    clear_calls: int = 0
    metadata_only: int = 0
    unread: tuple[TopicUse, ...] = ()
    log_floor: int = model.LOG_LEVEL_WARN
    """The lowest log level the log bridge reports (``log_bridge.severity_floor``; WARN)."""

    def topics(self, origin: str) -> tuple[TopicUse, ...]:
        """What one path took, by topic."""
        return tuple(use for use in self.taken if use.origin == origin)

    def messages(self, origin: str) -> int:
        """Messages one path took (recorded service calls: the calls applied)."""
        if origin == "report_fault":
            return self.report_calls
        if origin == "clear_fault":
            return self.clear_calls
        return sum(use.messages for use in self.topics(origin))

    @property
    def empty(self) -> bool:
        """Nothing reached a path that can raise a fault (a recording whose topics were read
        but gave no report, all goals SUCCEEDED say, is not empty)."""
        fed = any(use.origin in _FED for use in self.taken)
        return not (fed or self.report_calls or self.clear_calls)

    def _unread(self, origin: str) -> tuple[TopicUse, ...]:
        return tuple(use for use in self.unread if use.origin == origin)

    def _diagnostics_hint(self) -> str:
        other = self._unread("diagnostic_bridge")
        if not other:
            return ""
        use = other[0]
        return (
            f" ({use.topic} holds {_count(use.messages, 'DiagnosticArray')}: "
            f"diagnostic_bridge.diagnostics_topic: {use.topic} to read it)"
        )

    def lines(self) -> list[str]:
        """What each path took, one line per path, in words."""

        def taken(origin: str) -> str:
            return ", ".join(
                f"{_count(u.messages, 'message') if u.messages else 'messages'} on {u.topic}"
                for u in self.topics(origin)
            )

        diagnostics = taken("diagnostic_bridge") or f"nothing on {self.diagnostics_topic}"
        actions = taken("action_status_bridge") or "no */_action/status topic"
        logs = self._unread("log_bridge")
        if not self.log_bridge:
            log = "off" + "".join(
                f"; {u.topic} holds {_count(u.messages, 'log message')} "
                f"({LOG_BRIDGE_HINT} to read them)"
                for u in logs
            )
        else:
            log = taken("log_bridge") or f"nothing on {self.rosout_topic}"
        lines = [
            f"diagnostic bridge: {diagnostics}{self._diagnostics_hint()}",
            f"action status bridge: {actions}",
            f"log bridge: {log}",
            f"recorded ReportFault calls: {self.report_calls:,}, ClearFault calls: "
            f"{self.clear_calls:,}"
            + (
                f" ({self.metadata_only:,} more recorded without their request)"
                if self.metadata_only
                else ""
            ),
        ]
        if self.messages("script"):
            lines.append(f"script requests: {self.messages('script'):,}")
        events = sum(u.messages for u in self.topics("fault_events"))
        if events:
            lines.append(
                f"recorded fault manager events: {events:,} (compared under parity; they raise "
                "no fault)"
            )
        return lines

    def no_report(self) -> str:
        """Why a replay made no report, on one line: what each path that ran saw (a bridge
        that took messages and reported nothing saw nothing it reports)."""
        if self.empty:
            return self.nothing_replayed()
        seen: list[str] = []
        floor = model.LOG_LEVELS.get(self.log_floor, str(self.log_floor))
        for origin, what, verdict in (
            ("diagnostic_bridge", "DiagnosticArray", "none reported"),
            ("action_status_bridge", "action status message", "no goal aborted"),
            (
                "log_bridge",
                "log line",
                f"none at {floor} or above reported",
            ),
        ):
            uses = self.topics(origin)
            if not uses:
                continue
            count = self.messages(origin)
            counted = _count(count, what) if count else f"{what}s"
            on = (
                f"on {_count(len(uses), 'server')}"
                if origin == "action_status_bridge" and len(uses) > 1
                else "on " + ", ".join(use.topic for use in uses)
            )
            seen.append(f"{counted} {on}: {verdict}")
        return "no report: " + "; ".join(seen)

    def nothing_replayed(self) -> str:
        """What was missing, and how to read it, on one line (for an empty consumption)."""
        parts = [] if self.holds_messages else ["no readable message"]
        parts.append(f"no {self.diagnostics_topic}{self._diagnostics_hint()}")
        parts.append("no */_action/status")
        if self.log_bridge:
            parts.append(f"no {self.rosout_topic}")
        else:
            parts += [
                f"{u.topic} present but the log bridge is off ({LOG_BRIDGE_HINT} to read it)"
                for u in self._unread("log_bridge")
            ]
        if self.metadata_only:
            parts.append(
                f"{_count(self.metadata_only, 'ReportFault/ClearFault call')} recorded without "
                "the request (metadata-only service introspection)"
            )
        else:
            parts.append("no ReportFault/ClearFault calls")
        return "nothing replayed: " + ", ".join(parts)


@dataclass(frozen=True, slots=True, kw_only=True)
class Result:
    """What the live fault manager would have concluded from the inputs."""

    tool_version: str
    upstream_release: str = DEFAULT_RELEASE
    """The ros2_medkit release modelled (``medkit_replay.upstream_release``), set by the replay."""
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
    consumed: Consumption | None = None
    """What each path into the fault manager took (None: a Result not made by a replay); not
    in the JSON report."""
    summary: Summary
    config: dict[str, object] = field(default_factory=dict)
    snapshots: tuple[SnapshotCapture, ...] = ()
    recordings: tuple[EvidenceRecording, ...] = ()
    evidence_notes: tuple[str, ...] = ()
    fetched: dict[str, tuple[int, int]] = field(default_factory=dict)
    """Remote inputs by name: (bytes fetched, bytes of their files); not in the JSON report."""
    evidence_refused: tuple[str, ...] = ()
    """Clip folders left unwritten: the evidence folder held something else under their names
    (no clip was written then); not in the JSON report, which is the same either way."""
    event_tally: EventTally = field(default_factory=lambda: ({}, {}))
    """Per fault code, its FaultEvents by kind (published, withheld) as the engine counted them,
    so no output reads the spooled records back for them; not in the JSON report."""
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
