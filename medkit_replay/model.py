"""Values that cross layers: requests into the engine, records out of it.

Neutral ground: every layer may import this module; of ours it imports only the row codec (rows).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum
from typing import TYPE_CHECKING, Literal, Protocol, TypeVar, get_args

from medkit_replay.rows import RecordRows, spoolable

if TYPE_CHECKING:
    from collections.abc import Iterable, Iterator

Origin = Literal[
    "report_fault", "diagnostic_bridge", "action_status_bridge", "log_bridge", "script"
]
Cause = Literal["report", "auto_confirm", "clear", "auto_clear"]
EventKind = Literal["fault_confirmed", "fault_updated", "fault_cleared"]
Status = Literal["PREFAILED", "PREPASSED", "CONFIRMED", "HEALED", "CLEARED"]

STATUSES: tuple[Status, ...] = get_args(Status)
"""Every fault status, in the order the debounce moves through them."""
EVENT_KINDS: tuple[EventKind, ...] = get_args(EventKind)
"""Every FaultEvent type upstream publishes."""

NS_PER_SEC = 1_000_000_000
NS_PER_MS = 1_000_000

POLL_MIN_S = 0.05
POLL_MAX_S = 5.0
"""Bounds of ``follow``'s poll interval (seconds): fast enough to follow, slow enough to cost
nothing; the command line checks them before the tailing input clamps to them."""
POLL_DEFAULT_S = 0.5


LOG_LEVELS: dict[int, str] = {10: "DEBUG", 20: "INFO", 30: "WARN", 40: "ERROR", 50: "FATAL"}
"""rcl_interfaces/msg/Log's severity levels by number."""
LOG_LEVEL_WARN = 30
"""A log line's WARN level: the log bridge's default severity floor."""


class Severity(IntEnum):
    """Fault severities with ros2_medkit_msgs/Fault's numbers."""

    INFO = 0
    WARN = 1
    ERROR = 2
    CRITICAL = 3


SEVERITY_NAMES: tuple[str, ...] = tuple(severity.name for severity in Severity)
"""How every output names a fault's severity 0-3 (ros2_medkit_msgs/Fault's SEVERITY_* names).
Upstream's correlation engine spells 1 ``WARNING``; that spelling stays where it reaches the
report (a cluster's ``representative_severity``), as the contract shows."""


class EventType(IntEnum):
    """ReportFault request event types with the service's numbers."""

    FAILED = 0
    PASSED = 1


@spoolable
@dataclass(frozen=True, slots=True, kw_only=True)
class ReportRequest:
    """A ReportFault request as the fault manager receives it, stamped with bag time.

    ``event_type`` and ``severity`` are raw uint8 values: out-of-range ones are
    rejected by the manager's validation, as upstream does.
    """

    t_ns: int
    fault_code: str
    event_type: int
    severity: int = 0
    description: str = ""
    source_id: str
    origin: Origin = "script"
    topic: str | None = None

    @classmethod
    def of(cls, *request: *ReportFields) -> ReportRequest:
        """The request object of a request given field by field."""
        t_ns, origin, topic, fault_code, event_type, severity, description, source_id = request
        return cls(
            t_ns=t_ns,
            fault_code=fault_code,
            event_type=event_type,
            severity=severity,
            description=description,
            source_id=source_id,
            origin=origin,
            topic=topic,
        )

    def as_fields(self) -> ReportFields:
        """This request field by field, for a :class:`ReportSink`."""
        return (
            self.t_ns, self.origin, self.topic, self.fault_code, self.event_type, self.severity,
            self.description, self.source_id,
        )  # fmt: skip


ReportFields = tuple[int, Origin, str | None, str, int, int, str, str]
"""A ReportFault request as the replay hands it on, field by field (no object per request):
``(t_ns, origin, topic, fault_code, event_type, severity, description, source_id)``; the one
spelling of the signature every sink takes."""


class ReportSink(Protocol):
    """Takes one ReportFault request field by field (:data:`ReportFields`): what a bridge
    reports to. ``FaultManager.report_fields`` is the one that handles it; the others (the
    double-counting gate, a sweep's fan-out, ``explain``'s tracer, a list) pass it on."""

    def __call__(self, *request: *ReportFields) -> object:
        """Handle the request (what it returns is not used)."""


@spoolable
@dataclass(frozen=True, slots=True, kw_only=True)
class ClearRequest:
    """A ClearFault request stamped with bag time."""

    t_ns: int
    fault_code: str
    skip_correlation_auto_clear: bool = False
    origin: Origin = "script"
    topic: str | None = None


Request = ReportRequest | ClearRequest


@spoolable
@dataclass(frozen=True, slots=True, kw_only=True)
class FaultSnapshot:
    """One fault's public state at an instant (ros2_medkit_msgs/Fault plus correlation)."""

    fault_code: str
    severity: int
    description: str
    first_occurred_ns: int
    last_occurred_ns: int
    last_passed_ns: int
    occurrence_count: int
    status: Status
    reporting_sources: tuple[str, ...]
    muted: bool
    root_cause_code: str | None
    cluster_ids: tuple[str, ...]


@spoolable
@dataclass(frozen=True, slots=True, kw_only=True)
class FaultEvent:
    """A FaultEvent the live manager would have published."""

    t_ns: int
    event_type: EventKind
    fault: FaultSnapshot
    auto_cleared_codes: tuple[str, ...] = ()


@spoolable
@dataclass(frozen=True, slots=True, kw_only=True)
class Transition:
    """One status change of one fault."""

    t_ns: int
    fault_code: str
    from_status: Status | None
    to_status: Status
    cause: Cause
    source_id: str | None


@dataclass(frozen=True, slots=True, kw_only=True)
class RequestRecord:
    """The fields of ReportFields, named, with the event type as its name (FAILED, PASSED):
    what every record of one request starts with."""

    t_ns: int
    origin: Origin
    topic: str | None
    fault_code: str
    event_type: str
    severity: int
    description: str
    source_id: str


@spoolable
@dataclass(frozen=True, slots=True, kw_only=True)
class ReportRecord(RequestRecord):
    """A ReportFault request that reached the manager, with its verdict."""

    accepted: bool
    reject_reason: str | None
    # Beyond the contract: the fault after this report, for counter traces ("how close").
    status: Status | None = None
    debounce_counter: int | None = None
    confirmation_threshold: int | None = None
    healing_threshold: int | None = None
    withheld_event: EventKind | None = None  # the event correlation muting suppressed


@spoolable
@dataclass(frozen=True, slots=True, kw_only=True)
class ClearRecord:
    """A ClearFault request with the response the manager would have sent."""

    t_ns: int
    fault_code: str
    skip_correlation_auto_clear: bool
    success: bool
    message: str
    auto_cleared_codes: tuple[str, ...]


SNAPSHOT_ROWS = RecordRows(FaultSnapshot)
EVENT_ROWS = RecordRows(FaultEvent, ("fault", SNAPSHOT_ROWS))
TRANSITION_ROWS = RecordRows(Transition)
REPORT_ROWS = RecordRows(ReportRecord)
CLEAR_ROWS = RecordRows(ClearRecord)


@dataclass(frozen=True, slots=True, kw_only=True)
class MutedFault:
    """ros2_medkit_msgs/MutedFaultInfo."""

    fault_code: str
    root_cause_code: str
    rule_id: str
    delay_ms: int


@dataclass(frozen=True, slots=True, kw_only=True)
class Cluster:
    """ros2_medkit_msgs/ClusterInfo with bag times."""

    cluster_id: str
    rule_id: str
    rule_name: str
    label: str
    representative_code: str
    representative_severity: str
    fault_codes: tuple[str, ...]
    count: int
    first_at_ns: int
    last_at_ns: int


@spoolable
@dataclass(frozen=True, slots=True, kw_only=True)
class NearMiss:
    """A FAILED report after which the fault was not CONFIRMED."""

    fault_code: str
    t_ns: int
    debounce_counter: int
    confirmation_threshold: int
    severity: int
    source_id: str
    resulting_status: Status


@dataclass(frozen=True, slots=True, kw_only=True)
class RetroactiveMute:
    """Codes upstream computes as 'retroactively muted' at cluster activation (log only)."""

    t_ns: int
    cluster_id: str
    fault_codes: tuple[str, ...]


@dataclass(frozen=True, slots=True, kw_only=True)
class TopicSummary:
    """One topic of one input."""

    topic: str
    type: str
    role: str | None
    messages: int


@dataclass(frozen=True, slots=True, kw_only=True)
class Loss:
    """Part of an input skipped as damaged, or the total of several: what it cost (None: unknown).

    Attributes:
        input: the input it belongs to, as given (empty in a total over several inputs).
        messages: messages skipped; bytes: bytes of the file skipped.
        start_ns, end_ns: the bag (log) time span the skipped part covered.
        more_messages, more_bytes, more_span: a total to which losses of unknown size (or
            unknown span) add more.
    """

    input: str = ""
    messages: int | None = None
    bytes: int | None = None
    start_ns: int | None = None
    end_ns: int | None = None
    more_messages: bool = False
    more_bytes: bool = False
    more_span: bool = False

    @property
    def nothing(self) -> bool:
        """Damage that cost no message (nothing else said of it)."""
        return self.messages == 0 and self.bytes is None and self.start_ns is None

    def text(self) -> str:
        """``1,234 messages (3.4 MB) from bag time 12.000 s to 14.500 s skipped``, with
        ``unknown`` (or ``at least``) where the reader could not tell."""
        if self.bytes is None and (self.start_ns is None or self.end_ns is None):
            if self.messages is None:
                return "how much was lost is unknown"
            if self.messages == 0 and not self.more_messages:
                return "no message lost"
        if self.messages is None:
            messages = "an unknown number of messages"
        else:
            plural = "" if self.messages == 1 else "s"
            least = "at least " if self.more_messages else ""
            messages = f"{least}{self.messages:,} message{plural}"
        if self.bytes is None:
            size = "size unknown"
        else:
            size = ("at least " if self.more_bytes else "") + _size_text(self.bytes)
        if self.start_ns is None or self.end_ns is None:
            span = "at unknown bag times"
        else:
            span = f"from bag time {_sec(self.start_ns)} s to {_sec(self.end_ns)} s"
            span += " and at unknown bag times" if self.more_span else ""
        return f"{messages} ({size}) {span} skipped"


def _sec(ns: int) -> str:
    return f"{ns / NS_PER_SEC:.3f}"


def _size_text(count: int) -> str:
    return f"{count / 1e6:,.1f} MB" if count >= 100_000 else f"{count:,} bytes"


def total_loss(losses: Iterable[Loss], input: str = "") -> Loss:
    """All of ``losses`` as one: the known counts summed (``at least`` when some are unknown),
    the span from the earliest known start to the latest known end. A loss of no message (a
    damaged index read around) adds nothing unknown."""
    items = [loss for loss in losses if not loss.nothing]
    if not items:
        return Loss(input=input, messages=0)
    messages = [loss.messages for loss in items if loss.messages is not None]
    sizes = [loss.bytes for loss in items if loss.bytes is not None]
    starts = [loss.start_ns for loss in items if loss.start_ns is not None]
    ends = [loss.end_ns for loss in items if loss.end_ns is not None]
    return Loss(
        input=input,
        messages=sum(messages) if messages else None,
        bytes=sum(sizes) if sizes else None,
        start_ns=min(starts) if starts and ends else None,
        end_ns=max(ends) if starts and ends else None,
        more_messages=bool(messages) and len(messages) < len(items),
        more_bytes=bool(sizes) and len(sizes) < len(items),
        more_span=bool(starts and ends)
        and not all(loss.start_ns is not None and loss.end_ns is not None for loss in items),
    )


def losses_by_input(losses: Iterable[Loss]) -> tuple[Loss, ...]:
    """One total per input that lost anything, in the order their first loss was met."""
    grouped: dict[str, list[Loss]] = {}
    for loss in losses:
        grouped.setdefault(loss.input, []).append(loss)
    return tuple(total_loss(group, name) for name, group in grouped.items())


def read_in_part(loss: Loss) -> str:
    """One line saying what an input's damage cost, in total (``loss`` from losses_by_input)."""
    return f"{loss.input}: read only in part: {loss.text()}"


def strict_failure(loss: Loss) -> str:
    """The one line with which ``--strict`` fails a recording read only in part."""
    return f"{read_in_part(loss)} (--strict fails it)"


@dataclass(frozen=True, slots=True, kw_only=True)
class InputSummary:
    """What one input file held."""

    path: str
    storage: str
    start_ns: int | None
    end_ns: int | None
    message_count: int
    topics: tuple[TopicSummary, ...] = ()


T = TypeVar("T")


class RecordLog(Protocol[T]):
    """An append-only sequence of records: a list, or a Spool that keeps memory bounded."""

    def append(self, item: T, /) -> None:
        """Add a record at the end."""

    def __len__(self) -> int: ...

    def __iter__(self) -> Iterator[T]: ...

    def __getitem__(self, index: int, /) -> T: ...


EventTally = tuple[dict[str, dict[str, int]], dict[str, dict[str, int]]]
"""Per fault code, its FaultEvents by kind: (published, withheld by correlation muting)."""


@dataclass(slots=True, kw_only=True)
class EngineOutput:
    """Everything the engine produced during one replay, in production order."""

    events: RecordLog[FaultEvent] = field(default_factory=list)
    transitions: RecordLog[Transition] = field(default_factory=list)
    reports: RecordLog[ReportRecord] = field(default_factory=list)
    clears: RecordLog[ClearRecord] = field(default_factory=list)
    retroactive_mutes: list[RetroactiveMute] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    # Running counts, so that a summary never has to read spooled records back.
    event_counts: dict[str, int] = field(default_factory=dict)
    reports_accepted: int = 0
    # Per fault code, its FaultEvents by kind: published, and withheld by correlation muting.
    published_by_code: dict[str, dict[str, int]] = field(default_factory=dict)
    withheld_by_code: dict[str, dict[str, int]] = field(default_factory=dict)


Phase = Literal["prescan", "replay"]
"""``prescan``: the pass over recorded ReportFault calls only; ``replay``: the replay itself."""


@dataclass(frozen=True, slots=True)
class Progress:
    """How far a pass over the recording has got; given to ``replay(progress=...)``.

    Attributes:
        phase: which pass over the recording this is (see :data:`Phase`).
        messages: messages read so far in this pass (selected topics only).
        t_ns: bag time of the last message read (None before the first).
        start_ns: first log time of the recording, when the inputs declare it up front.
        end_ns: last log time of the recording, likewise (see ``Recording.span``).
        done: the pass has read everything (sent once, last, for every pass).
    """

    phase: Phase
    messages: int
    t_ns: int | None
    start_ns: int | None
    end_ns: int | None
    done: bool = False

    @property
    def fraction(self) -> float | None:
        """Share of the recording's bag time read, 0.0 to 1.0; None when the span is unknown."""
        if self.done:
            return 1.0
        if self.start_ns is None or self.end_ns is None or self.t_ns is None:
            return None
        if self.end_ns <= self.start_ns:
            return 0.0
        return min(max((self.t_ns - self.start_ns) / (self.end_ns - self.start_ns), 0.0), 1.0)
