"""Which captures the live manager would have run, decided from the engine's transitions.

Freeze frames and black-box recordings are triggered by report-driven transitions into
CONFIRMED (cooldown permitting) and undone by clears; no confirmation is re-derived here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

from medkit_replay.evidence.rules import (
    ATTACHED_FAULT_CAP,
    entity_rosbag_topics,
    entity_snapshot_topics,
    recording_name,
    resolve_configured,
    subscribed_topics,
)
from medkit_replay.model import NS_PER_SEC

if TYPE_CHECKING:
    from collections.abc import Iterable

    from medkit_replay.evidence.graph import NodeGraph
    from medkit_replay.evidence.rules import SnapshotConfig
    from medkit_replay.model import ReportRecord, Transition


class Probe(Protocol):
    """Whether the recording holds any message on ``topics`` in ``[start_ns, end_ns]``."""

    def __call__(self, topics: Iterable[str], start_ns: int, end_ns: int) -> bool: ...


@dataclass(slots=True)
class PlannedCapture:
    """A freeze-frame capture: its id, the resolved topics, how each is sampled."""

    fault_code: str
    capture_id: int
    t_ns: int
    topics: tuple[str, ...]
    background: bool
    entity_scoped: bool


@dataclass(frozen=True, slots=True)
class Segment:
    """A stretch of a recording and the topics written in it (None: every subscribed one)."""

    start_ns: int
    end_ns: int
    topics: frozenset[str] | None


@dataclass(slots=True)
class PlannedRecording:
    """A black-box recording: its windows, faults, and its fate at the live manager."""

    name: str
    fault_code: str
    current: str
    t_ns: int
    start_ns: int
    end_ns: int
    segments: list[Segment]
    attached: list[str] = field(default_factory=list)
    rows: list[str] = field(default_factory=list)
    deleted: tuple[int, str] | None = None  # when and why the live manager deletes it
    filter: frozenset[str] | None = None

    @property
    def fault_codes(self) -> tuple[str, ...]:
        """The primary fault, then those attached in its post-roll (in code order)."""
        attached = sorted(set(self.attached) - {self.fault_code})
        return (self.fault_code, *attached)


@dataclass(slots=True)
class Step:
    """One thing that changes the stored evidence, in time order: a capture or a clear."""

    t_ns: int
    fault_code: str
    capture: PlannedCapture | None = None


@dataclass(slots=True)
class Plan:
    """Everything decided before any message is read."""

    captures: list[PlannedCapture] = field(default_factory=list)
    recordings: list[PlannedRecording] = field(default_factory=list)
    steps: list[Step] = field(default_factory=list)
    subscribed: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


class _Sources:
    """Each fault's reporting sources as they grew (upstream never forgets one).

    The reports are read on first use only: only entity scope (with a node graph) needs them,
    and reading a long replay's spooled reports back costs seconds.
    """

    def __init__(self, reports: Iterable[ReportRecord]) -> None:
        self.reports = reports
        self.first: dict[str, dict[str, int]] | None = None

    def at(self, code: str, t_ns: int) -> list[str]:
        if self.first is None:
            self.first = {}
            for report in self.reports:
                if report.accepted:
                    self.first.setdefault(report.fault_code, {}).setdefault(
                        report.source_id, report.t_ns
                    )
        return sorted(s for s, t in self.first.get(code, {}).items() if t <= t_ns)


def _listed(codes: Iterable[str], limit: int = 20) -> str:
    """Codes for a note: the first ``limit`` in order, then how many more."""
    unique = sorted(set(codes))
    shown = ", ".join(unique[:limit])
    return shown + (f" and {len(unique) - limit} more" if len(unique) > limit else "")


def plan_evidence(
    config: SnapshotConfig,
    transitions: Iterable[Transition],
    reports: Iterable[ReportRecord],
    recorded_topics: Iterable[str],
    graph: NodeGraph | None,
    probe: Probe,
) -> Plan:
    """Walk the transitions once and decide every capture and recording."""
    plan = Plan()
    if not config.captures:
        return plan
    sources = _Sources(reports)
    bag = _BlackBox(config, plan, sources, graph, probe)
    if config.rosbag.enabled:
        plan.subscribed = subscribed_topics(config, recorded_topics)
    cooldown_ns = round(config.recapture_cooldown_sec * NS_PER_SEC)
    last_capture: dict[str, int] = {}
    capture_seq = 0
    no_graph: list[str] = []
    for transition in transitions:
        t_ns, code = transition.t_ns, transition.fault_code
        bag.advance(t_ns)
        bag.status[code] = transition.to_status
        if transition.to_status == "CLEARED":
            last_capture.pop(code, None)
            plan.steps.append(Step(t_ns, code))
            bag.cleared(code, t_ns)
            continue
        if transition.cause != "report":
            continue
        if transition.to_status == "PREFAILED" and transition.from_status != "PREFAILED":
            bag.prefailed(t_ns)
        if transition.to_status != "CONFIRMED" or transition.from_status == "CONFIRMED":
            continue
        if cooldown_ns > 0 and code in last_capture and t_ns - last_capture[code] < cooldown_ns:
            continue
        last_capture[code] = t_ns
        if config.enabled:
            resolution = resolve_configured(config, code)
            topics, entity = resolution.topics, False
            if not topics and not resolution.explicit and config.entity_default:
                if graph is None:
                    no_graph.append(code)
                else:
                    topics = entity_snapshot_topics(graph, sources.at(code, t_ns))
                    entity = bool(topics)
            if topics:
                capture_seq += 1
                capture = PlannedCapture(
                    code,
                    capture_seq,
                    t_ns,
                    topics,
                    config.background_capture and not entity,
                    entity,
                )
                plan.captures.append(capture)
                plan.steps.append(Step(t_ns, code, capture))
        if config.rosbag.enabled:
            bag.confirmed(code, t_ns)
    bag.advance(None)
    if no_graph:
        plan.notes.append(
            f"{len(no_graph)} freeze-frame capture(s) would use entity-default topics (the topics "
            f"the reporting node publishes), which need the node graph: {_listed(no_graph)}; "
            "pass --graph FILE to capture them (capture ids assume they captured nothing)"
        )
    if bag.unscoped:
        why = (
            "pass --graph FILE to scope them"
            if graph is None
            else "their reporting nodes publish or subscribe nothing recorded in the node graph"
        )
        plan.notes.append(
            f"{len(bag.unscoped)} recording(s) in entity mode hold every subscribed topic "
            "(upstream's fallback when the faulting node's topics are unknown): "
            f"{_listed(bag.unscoped)}; {why}"
        )
    return plan


class _BlackBox:
    """The rosbag capture's state: buffer start, open post-roll, stored rows per fault."""

    def __init__(
        self,
        config: SnapshotConfig,
        plan: Plan,
        sources: _Sources,
        graph: NodeGraph | None,
        probe: Probe,
    ) -> None:
        self.config = config.rosbag
        self.plan = plan
        self.sources = sources
        self.graph = graph
        self.probe = probe
        self.running_since: int | None = None if self.config.lazy_start else -(2**63)
        self.buffer_from = -(2**63)
        self.active: PlannedRecording | None = None
        self.status: dict[str, str] = {}
        self.rows: list[tuple[str, PlannedRecording]] = []  # (fault code, recording), stored order
        self.unscoped: list[str] = []
        self.before_ns = round(self.config.duration_sec * NS_PER_SEC)
        self.after_ns = round(self.config.duration_after_sec * NS_PER_SEC)

    def prefailed(self, t_ns: int) -> None:
        if self.running_since is None:
            self.running_since = t_ns
            self.buffer_from = t_ns

    def advance(self, t_ns: int | None) -> None:
        """Close a post-roll whose window ended before ``t_ns`` (None: the recording's end)."""
        active = self.active
        if active is not None and (t_ns is None or t_ns > active.end_ns):
            self.active = None
            self._finalize(active)

    def _entity_topics(self, code: str, t_ns: int) -> frozenset[str] | None:
        if self.config.topics != "entity":
            return None
        if self.graph is None:
            return frozenset()
        return frozenset(
            entity_rosbag_topics(self.graph, self.sources.at(code, t_ns), self.plan.subscribed)
        )

    def confirmed(self, code: str, t_ns: int) -> None:
        if self.running_since is None:
            return  # lazy_start: nothing entered PREFAILED yet, the buffer never started
        active = self.active
        if active is not None:
            if code == active.current or not self.config.post_roll_sharing:
                return  # before sharing (0.6.0), a confirmation during a post-roll is skipped
            scope = self._entity_topics(code, t_ns)
            if code not in active.attached and len(set(active.attached)) < ATTACHED_FAULT_CAP:
                active.attached.append(code)
            self._widen(active, scope, t_ns)
            return
        scope = self._entity_topics(code, t_ns)
        if scope is not None and not scope and self.config.topics == "entity":
            scope = None
            self.unscoped.append(code)
        start = max(t_ns - self.before_ns, self.buffer_from)
        buffered = start <= t_ns and self.probe(self.plan.subscribed, start, t_ns)
        if not buffered and (self.after_ns <= 0 or not self.config.post_roll_only):
            return  # nothing buffered: no bag, unless a post-roll-only one is made (0.7.0)
        recording = PlannedRecording(
            name=recording_name(code, t_ns),
            fault_code=code,
            current=code,
            t_ns=t_ns,
            start_ns=start if buffered else t_ns,
            end_ns=t_ns + self.after_ns,
            segments=[Segment(start, t_ns, scope)] if buffered else [],
            filter=scope,
        )
        self.plan.recordings.append(recording)
        if self.after_ns > 0:
            self.active = recording
        else:
            self._finalize(recording)

    def _widen(self, active: PlannedRecording, scope: frozenset[str] | None, t_ns: int) -> None:
        if self.config.topics != "entity" or active.filter is None:
            return
        widened = None if not scope else active.filter | scope
        if widened == active.filter:
            return
        self._cut(active, t_ns)
        active.filter = widened

    def _cut(self, active: PlannedRecording, t_ns: int) -> None:
        """End the current post-roll segment at ``t_ns``; the next starts after it."""
        begun = max((s.end_ns for s in active.segments), default=active.t_ns)
        if t_ns > begun:
            active.segments.append(Segment(begun + 1, t_ns, active.filter))

    def _finalize(self, recording: PlannedRecording) -> None:
        if self.after_ns > 0:
            self._cut(recording, recording.end_ns)
        self.buffer_from = recording.end_ns + 1
        codes = [recording.current] if recording.current else []
        codes += sorted(set(recording.attached))
        wanted = [c for c in codes if self._wants_row(c)]
        if not wanted:
            recording.deleted = (
                recording.end_ns,
                "every fault of the recording was cleared during its post-roll",
            )
            return
        for code in wanted:
            self.rows.append((code, recording))
            recording.rows.append(code)
            cap = self.config.max_bags_per_fault
            mine = [r for c, r in self.rows if c == code]
            if cap > 0 and len(mine) > cap:
                for old in mine[: len(mine) - cap]:
                    self.rows.remove((code, old))
                    history = self.config.bag_history
                    why = f"max_bags_per_fault {cap}" if history else "one per fault"
                    self._unlink(
                        old, recording.end_ns, f"{why}: replaced by {recording.name} for {code}"
                    )

    def _wants_row(self, code: str) -> bool:
        config = self.config
        if not config.auto_cleanup or config.keeps_history or not config.cleanup_in_post_roll:
            return True
        return self.status.get(code) != "CLEARED"

    def cleared(self, code: str, t_ns: int) -> None:
        if not self.config.auto_cleanup or self.config.keeps_history:
            return
        active = self.active
        if active is not None and code == active.current and self.config.cleanup_in_post_roll:
            active.current = ""  # an attached fault's row is withheld at the finalize
        doomed = [r for c, r in self.rows if c == code]
        self.rows = [(c, r) for c, r in self.rows if c != code]
        for recording in doomed:
            self._unlink(recording, t_ns, f"auto_cleanup: {code} was cleared")

    def _unlink(self, recording: PlannedRecording, t_ns: int, reason: str) -> None:
        if any(r is recording for _, r in self.rows) or recording.deleted is not None:
            return
        recording.deleted = (t_ns, reason)
