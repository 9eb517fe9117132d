"""Records of one fault's path through a replay, kept only when ``explain`` asks for that fault.

Neutral values: the pipeline fills a FaultTrace as the one replay runs; ``explaining`` reads it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from medkit_replay.model import RequestRecord

if TYPE_CHECKING:
    from medkit_replay.model import (
        ClearRecord,
        Cluster,
        FaultEvent,
        FaultSnapshot,
        MutedFault,
        ReportRecord,
        Transition,
    )

MAX_ITEMS = 32
"""Key/value pairs or goals kept of one recorded message (the rest are counted)."""
DEFAULT_STORY_LIMIT = 10_000
"""Trace items a story holds at most (``explain --limit``): reports, held requests, decisions,
status changes, events and clears, each told in a line or two and kept until the story is
written (a few KB each). 10,000 are some 3,000 reports of a flapping fault; the items past
them are counted, and ``--from`` and ``--at`` choose the stretch told."""


@dataclass(frozen=True, slots=True, kw_only=True)
class RecordedMessage:
    """The part of a recorded message a request came from (a DiagnosticStatus, a goal list...).

    Attributes:
        input_index: which input of the recording held it.
        topic: the topic it was recorded on.
        type: the type of the part shown (``diagnostic_msgs/msg/DiagnosticStatus``).
        fields: its named fields, in message order: text as recorded, numbers, or a number
            with its constant's name (``(2, "ERROR")``).
        items: its key/value pairs (DiagnosticStatus values) or goals (id, status), at most
            MAX_ITEMS of them.
        items_left_out: how many pairs or goals were not kept.
    """

    input_index: int
    topic: str
    type: str
    fields: tuple[tuple[str, str | int | tuple[int, str]], ...] = ()
    items: tuple[tuple[str, str], ...] = ()
    items_left_out: int = 0


@dataclass(frozen=True, slots=True, kw_only=True)
class HeldRequest(RequestRecord):
    """A request for the fault that never reached the manager, and what held it back.

    ``stage`` is ``local_filter`` (the bridge reporter's LocalFilter), ``cooldown`` (the log
    bridge's per-code cooldown) or ``double_counting`` (recorded ReportFault calls win).
    """

    stage: str
    reason: str
    message: RecordedMessage | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class RuleFacts:
    """What one correlation rule says, as the engine applied it."""

    rule_id: str
    name: str
    mode: str
    window_ms: int
    mute_symptoms: bool = False
    auto_clear_with_root: bool = False
    min_count: int = 0
    show_as_single: bool = False
    representative: str = ""


@dataclass(frozen=True, slots=True, kw_only=True)
class CorrelationDecision:
    """The correlation engine's answer to one accepted FAILED report (upstream's result).

    Recorded for the traced fault's own reports and for the symptoms it was root cause of.
    """

    t_ns: int
    fault_code: str
    should_mute: bool
    is_root_cause: bool
    root_cause_code: str
    rule: RuleFacts | None
    delay_ms: int
    cluster_id: str
    retroactive_mute_codes: tuple[str, ...] = ()


@dataclass(frozen=True, slots=True, kw_only=True)
class TracedReport:
    """A report the manager handled (its record) with where it came from and the fault after it.

    ``entity_prefix`` is the entity_thresholds prefix whose band applied (None: the global one).
    """

    record: ReportRecord
    message: RecordedMessage | None
    state: FaultSnapshot | None
    entity_prefix: str | None
    healing_enabled: bool


@dataclass(frozen=True, slots=True, kw_only=True)
class TracedTransition:
    """A status change of the fault, with the fault after it."""

    record: Transition
    state: FaultSnapshot | None


@dataclass(frozen=True, slots=True, kw_only=True)
class TracedEvent:
    """A FaultEvent published for the fault (or, with auto-clears, naming it)."""

    record: FaultEvent


@dataclass(frozen=True, slots=True, kw_only=True)
class TracedClear:
    """A ClearFault of the fault, or of a root that auto-cleared it."""

    record: ClearRecord


TraceItem = (
    TracedReport | TracedTransition | TracedEvent | TracedClear | HeldRequest | CorrelationDecision
)


def item_time(item: TraceItem) -> int:
    """The bag time of a trace item."""
    if isinstance(item, HeldRequest | CorrelationDecision):
        return item.t_ns
    return item.record.t_ns


@dataclass(frozen=True, slots=True, kw_only=True)
class StateAt:
    """The fault as the manager held it at one instant (``--at``).

    ``t_ns`` is the instant; ``state`` None when the fault was not known yet. ``counter``,
    ``muted`` and ``clusters`` are the manager's and the correlation engine's at that instant.
    """

    t_ns: int
    state: FaultSnapshot | None
    counter: int | None
    muted: MutedFault | None
    clusters: tuple[Cluster, ...]


@dataclass(slots=True, kw_only=True)
class FaultTrace:
    """Everything the replay did with one fault code, in the order it happened.

    Attributes:
        fault_code: the traced code.
        at_offset_ns: where ``state_at`` is taken, in ns from the recording's start (``--at``);
            None: not asked.
        origin_ns: the recording's start as the replay knew it on its first message: the
            earliest start an input declares, or that first message's time.
        items: reports, held requests, correlation decisions, transitions, events and clears,
            from ``from_offset_ns`` (``--from``) to ``at_offset_ns``, at most ``limit``.
        state_at: the fault at ``origin_ns + at_offset_ns`` (set once the replay got there),
            or at the last message when no ``--at`` was asked.
        before: items before ``--from``, not kept; ``after``: items past ``--at``, not kept.
        left_out: items past ``limit``, not kept; ``left_out_from_ns`` the first one's time.
    """

    fault_code: str
    at_offset_ns: int | None = None
    from_offset_ns: int | None = None
    limit: int = DEFAULT_STORY_LIMIT
    origin_ns: int | None = None
    items: list[TraceItem] = field(default_factory=list)
    state_at: StateAt | None = None
    before: int = 0
    after: int = 0
    left_out: int = 0
    left_out_from_ns: int | None = None

    @property
    def at_ns(self) -> int | None:
        """The bag time of ``--at``, once the recording's start is known."""
        if self.at_offset_ns is None or self.origin_ns is None:
            return None
        return self.origin_ns + self.at_offset_ns

    @property
    def from_ns(self) -> int | None:
        """The bag time of ``--from``, once the recording's start is known."""
        if self.from_offset_ns is None or self.origin_ns is None:
            return None
        return self.origin_ns + self.from_offset_ns

    @property
    def seen(self) -> int:
        """Items the replay made for the code, kept or not (0: the code never appeared)."""
        return len(self.items) + self.before + self.after + self.left_out

    def takes(self, t_ns: int) -> bool:
        """Whether an item at ``t_ns`` lies in the stretch told and the story has room for it;
        if not, it is counted (the caller need not build it)."""
        at_ns, from_ns = self.at_ns, self.from_ns
        if at_ns is not None and t_ns > at_ns:
            self.after += 1
            return False
        if from_ns is not None and t_ns < from_ns:
            self.before += 1
            return False
        if len(self.items) >= self.limit:
            if self.left_out == 0:
                self.left_out_from_ns = t_ns
            self.left_out += 1
            return False
        return True

    def add(self, item: TraceItem, at: int | None = None) -> None:
        """Keep ``item`` (at position ``at``, else last) if :meth:`takes` its time."""
        if not self.takes(item_time(item)):
            return
        if at is None:
            self.items.append(item)
        else:
            self.items.insert(at, item)
