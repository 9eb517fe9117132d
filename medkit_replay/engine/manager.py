"""The fault manager node on bag time: validation, debounce, correlation, FaultEvents, clears.

Pure: consumes timestamped requests and ticks, appends records to an EngineOutput.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, TypeAlias, TypeVar

from medkit_replay.engine.correlation.engine import CorrelationEngine, severity_name
from medkit_replay.engine.debounce import DebounceConfig, sanitize, unchanged
from medkit_replay.engine.storage import (
    DEFAULT_NEAR_MISS_BOUND,
    DEFAULT_STORAGE_TYPE,
    FaultRecord,
    FaultStorage,
)
from medkit_replay.engine.thresholds import EntityOverride, EntityThresholdResolver
from medkit_replay.engine.validation import fault_code_error, report_error
from medkit_replay.model import (
    EVENT_ROWS,
    NS_PER_SEC,
    REPORT_ROWS,
    TRANSITION_ROWS,
    Cause,
    ClearRecord,
    ClearRequest,
    EngineOutput,
    EventKind,
    EventType,
    FaultSnapshot,
    ReportRequest,
    RetroactiveMute,
    Status,
)
from medkit_replay.releases import Release, default_release

if TYPE_CHECKING:
    from collections.abc import Callable

    from medkit_replay.engine.correlation.engine import CorrelationResult
    from medkit_replay.engine.correlation.rules import CorrelationConfig
    from medkit_replay.model import Origin, RecordLog, ReportFields
    from medkit_replay.rows import RecordRows

_T = TypeVar("_T")
_EVENT_NAMES = {event.value: event.name for event in EventType}
_MAX_CACHED_SOURCES = 65536

Row = tuple[object, ...]
if TYPE_CHECKING:
    FieldsReporter: TypeAlias = Callable[[*ReportFields], bool]
    """A ReportSink that answers ``accepted`` (the manager's :attr:`FaultManager.report_fields`)."""
    CorrelationWatcher: TypeAlias = Callable[[int, str, CorrelationResult], None]


def _row_sink(log: RecordLog[_T], rows: RecordRows[_T]) -> Callable[[Row], None]:
    """Appends rows to a log: directly to a spool that takes rows, else as rebuilt records."""
    append_row: Callable[[Row], None] | None = getattr(log, "append_row", None)
    if append_row is not None:
        return append_row
    decode, append = rows.decode, log.append

    def sink(row: Row) -> None:
        append(decode(row))

    return sink


@dataclass(frozen=True, slots=True, kw_only=True)
class FaultManagerConfig:
    """Fault manager parameters after upstream's sanitising (fault-manager.md §1.2)."""

    debounce: DebounceConfig = field(default_factory=DebounceConfig)
    auto_confirm_after_ns: int = 0
    near_miss_bound: int = DEFAULT_NEAR_MISS_BOUND
    entity_overrides: tuple[EntityOverride, ...] = ()
    correlation: CorrelationConfig | None = None
    cleanup_interval_ns: int = 5 * NS_PER_SEC
    release: Release = field(default_factory=default_release)
    """The upstream release modelled: which of the rules that changed between releases apply."""
    storage_type: str = DEFAULT_STORAGE_TYPE
    """Upstream's storage backend, "sqlite" or "memory": they decide a status differently at
    0.6.0 (``Release.backends_share_status_rule``) and alike from 0.7.0."""


class FaultManager:
    """Upstream's FaultManagerNode with an in-memory storage, driven by bag time."""

    def __init__(self, config: FaultManagerConfig, output: EngineOutput | None = None) -> None:
        self.config = config
        self.output = output if output is not None else EngineOutput()
        release = config.release
        self.storage = FaultStorage(config.near_miss_bound, release, config.storage_type)
        if config.auto_confirm_after_ns > 0:
            self.storage.track_prefailed()
        # A release without the sanitiser uses thresholds as written (0 stays 0).
        self._settle = sanitize if release.sanitize_thresholds else unchanged
        self.resolver = EntityThresholdResolver(
            self._settle(config.debounce),
            config.entity_overrides,
            sanitize_entries=release.sanitize_thresholds,
        )
        self.correlation = (
            CorrelationEngine(config.correlation)
            if config.correlation is not None and config.correlation.enabled
            else None
        )
        self._configs: dict[str, DebounceConfig] = {}  # sanitised config per source_id
        self._valid_codes: set[str] = set()  # codes validation accepts
        # Where report_fields puts its records (set_row_sinks swaps in faster ones).
        self.report_row = _row_sink(self.output.reports, REPORT_ROWS)
        self.event_row = _row_sink(self.output.events, EVENT_ROWS)
        self.transition_row = _row_sink(self.output.transitions, TRANSITION_ROWS)
        self.correlation_watcher: CorrelationWatcher | None = None
        self.report_fields: FieldsReporter = self._fields_reporter()
        """Handle one ReportFault request given field by field; returns ``accepted``.

        The one implementation of the node's report handling: validation, per-entity band,
        storage, correlation, FaultEvents. Records leave as rows (a spool stores them as they
        are; a list gets the rebuilt records), so the replay builds no objects per request.
        """

    # -- ReportFault -----------------------------------------------------------------------

    def report(self, request: ReportRequest) -> bool:
        """Handle one ReportFault request; returns the response's ``accepted``.

        An adapter over :attr:`report_fields`, the one implementation.
        """
        return self.report_fields(*request.as_fields())

    def set_row_sinks(
        self,
        report: Callable[[Row], None],
        event: Callable[[Row], None],
        transition: Callable[[Row], None],
    ) -> None:
        """Where the manager puts its report, event and transition rows (a spool's ``row_sink``)."""
        self.report_row, self.event_row, self.transition_row = report, event, transition
        self.report_fields = self._fields_reporter()

    def watch_correlation(self, watcher: CorrelationWatcher) -> None:
        """Hand every correlation decision (bag time, fault code, upstream's result) to
        ``watcher`` as it is made; it changes nothing (``explain`` records them)."""
        self.correlation_watcher = watcher
        self.report_fields = self._fields_reporter()

    def _fields_reporter(self) -> FieldsReporter:
        """Build :attr:`report_fields` with what it reads bound as locals (it runs per status)."""
        valid_codes, configs, output = self._valid_codes, self._configs, self.output
        faults, storage, resolver, correlation = (
            self.storage.faults,
            self.storage,
            self.resolver,
            self.correlation,
        )
        report_row, transition_row = self.report_row, self.transition_row
        event, watcher = self._event, self.correlation_watcher
        settle, heal_event = self._settle, self.config.release.heal_event
        max_length = self.config.release.max_fault_code_length

        def report_fields(
            t_ns: int,
            origin: Origin,
            topic: str | None,
            fault_code: str,
            event_type: int,
            severity: int,
            description: str,
            source_id: str,
        ) -> bool:
            # The ReportFields named, not *request: this runs per status (no tuple per call).
            if fault_code in valid_codes:  # only the checks that do not depend on the code
                valid = source_id and (event_type == 1 or (event_type == 0 and severity <= 3))
                reason = (
                    None
                    if valid
                    else report_error(fault_code, event_type, severity, source_id, max_length)
                )
            else:
                reason = report_error(fault_code, event_type, severity, source_id, max_length)
                if reason is None and len(valid_codes) < _MAX_CACHED_SOURCES:
                    valid_codes.add(fault_code)
            if reason is not None:
                name = _EVENT_NAMES.get(event_type, str(event_type))
                report_row(
                    (t_ns, origin, topic, fault_code, name, severity, description, source_id,
                     False, reason, None, None, None, None, None)
                )  # fmt: skip
                return False
            config = configs.get(source_id)
            if config is None:
                config = settle(resolver.resolve(source_id))
                if len(configs) < _MAX_CACHED_SOURCES:
                    configs[source_id] = config
            output.reports_accepted += 1
            conf, heal = config.confirmation_threshold, config.healing_threshold
            name = "FAILED" if event_type == 0 else "PASSED"
            before, after, is_new = storage.report(
                fault_code, event_type, severity, description, source_id, t_ns, config
            )
            fault = faults.get(fault_code)
            if fault is None:  # a PASSED for an unknown fault: accepted, nothing stored
                report_row(
                    (t_ns, origin, topic, fault_code, name, severity, description, source_id,
                     True, None, None, None, conf, heal, None)
                )  # fmt: skip
                return True
            if before != after:
                transition_row((t_ns, fault_code, before, after, "report", source_id))
            muted = False
            if correlation is not None and event_type == 0:
                result = correlation.process_fault(fault_code, severity_name(severity), t_ns)
                muted = result.should_mute
                if watcher is not None:
                    watcher(t_ns, fault_code, result)
                if result.retroactive_mute_codes:
                    output.retroactive_mutes.append(
                        RetroactiveMute(
                            t_ns=t_ns,
                            cluster_id=result.cluster_id,
                            fault_codes=result.retroactive_mute_codes,
                        )
                    )
            kind: EventKind | None = None
            withheld: EventKind | None = None
            if after == "CONFIRMED":
                again = not is_new and before == "CONFIRMED"
                kind = "fault_updated" if again else "fault_confirmed"
                if muted:
                    withheld, kind = kind, None
                    counts = output.withheld_by_code.setdefault(fault_code, {})
                    counts[withheld] = counts.get(withheld, 0) + 1
            report_row(
                (t_ns, origin, topic, fault_code, name, severity, description, source_id,
                 True, None, fault.status, fault.counter, conf, heal, withheld)
            )  # fmt: skip
            if kind is not None:
                event(t_ns, kind, fault)
            if heal_event and after == "HEALED" and not is_new and before != "HEALED":
                event(t_ns, "fault_cleared", fault)
            return True

        return report_fields

    # -- ClearFault ------------------------------------------------------------------------

    def clear(self, request: ClearRequest) -> bool:
        """Handle one ClearFault request; returns the response's ``success``."""
        code = request.fault_code
        reason = fault_code_error(code, self.config.release.max_fault_code_length)
        if reason is not None:
            self._clear_record(request, success=False, message=reason, auto=())
            return False
        auto: list[str] = []
        if self.correlation is not None and not request.skip_correlation_auto_clear:
            auto = self.correlation.process_clear(code)
        before = self._status(code)
        if not self.storage.clear(code):
            self._clear_record(request, success=False, message=f"Fault not found: {code}", auto=())
            return False
        if before != "CLEARED":
            self._transition(request.t_ns, code, before, "CLEARED", "clear", None)
        for symptom in auto:
            symptom_before = self._status(symptom)
            if self.storage.clear(symptom) and symptom_before != "CLEARED":
                self._transition(
                    request.t_ns, symptom, symptom_before, "CLEARED", "auto_clear", None
                )
        message = f"Fault cleared: {code}"
        if auto:
            message += f" (auto-cleared {len(auto)} symptoms)"
        self._clear_record(request, success=True, message=message, auto=tuple(auto))
        self._event(request.t_ns, "fault_cleared", self.storage.faults[code], tuple(auto))
        return True

    # -- timers ----------------------------------------------------------------------------

    def auto_confirm_tick(self, now_ns: int) -> list[str]:
        """One tick of the 1 Hz time-based confirmation: silent PREFAILED → CONFIRMED (§1.7)."""
        if self.config.auto_confirm_after_ns <= 0:
            return []
        due = self.storage.take_due_for_auto_confirm(now_ns, self.config.auto_confirm_after_ns)
        for code in due:
            self.confirm_by_timer(code, now_ns)
        return due

    def confirm_by_timer(self, code: str, now_ns: int) -> None:
        """Confirm one PREFAILED fault from the timer: no FaultEvent, as upstream (§1.7)."""
        self.storage.faults[code].status = "CONFIRMED"
        self._transition(now_ns, code, "PREFAILED", "CONFIRMED", "auto_confirm", None)

    def cleanup_tick(self, now_ns: int) -> None:
        """The correlation cleanup timer."""
        if self.correlation is not None:
            self.correlation.cleanup_expired(now_ns)

    # -- views -----------------------------------------------------------------------------

    def snapshot(self, fault: FaultRecord) -> FaultSnapshot:
        """The public state of one fault, with its correlation view."""
        entry = self.correlation.muted_entry(fault.fault_code) if self.correlation else None
        clusters = self.correlation.cluster_ids_of(fault.fault_code) if self.correlation else ()
        return FaultSnapshot(
            fault_code=fault.fault_code,
            severity=fault.severity,
            description=fault.description,
            first_occurred_ns=fault.first_occurred_ns,
            last_occurred_ns=fault.last_occurred_ns,
            last_passed_ns=fault.last_passed_ns,
            occurrence_count=fault.occurrence_count,
            status=fault.status,
            reporting_sources=fault.sorted_sources(),
            muted=entry is not None,
            root_cause_code=entry.root_cause_code if entry is not None else None,
            cluster_ids=clusters,
        )

    def faults(self) -> list[FaultSnapshot]:
        """Every known fault in fault_code byte order."""
        codes = sorted(self.storage.faults, key=lambda c: c.encode("utf-8"))
        return [self.snapshot(self.storage.faults[c]) for c in codes]

    def _status(self, code: str) -> Status | None:
        fault = self.storage.faults.get(code)
        return fault.status if fault is not None else None

    def _transition(
        self,
        t_ns: int,
        code: str,
        before: Status | None,
        after: Status,
        cause: Cause,
        source_id: str | None,
    ) -> None:
        self.transition_row((t_ns, code, before, after, cause, source_id))

    def _event(
        self, t_ns: int, kind: EventKind, fault: FaultRecord, auto: tuple[str, ...] = ()
    ) -> None:
        """Count and record a FaultEvent: the fault's state now, with its correlation view."""
        counts = self.output.event_counts
        counts[kind] = counts.get(kind, 0) + 1
        code = fault.fault_code
        counts = self.output.published_by_code.setdefault(code, {})
        counts[kind] = counts.get(kind, 0) + 1
        correlation = self.correlation
        if correlation is not None:
            entry = correlation.muted_entry(code)
            muted, root = entry is not None, entry.root_cause_code if entry is not None else None
            clusters = correlation.cluster_ids_of(code)
        else:
            muted, root, clusters = False, None, ()
        self.event_row(
            (t_ns, kind, code, fault.severity, fault.description, fault.first_occurred_ns,
             fault.last_occurred_ns, fault.last_passed_ns, fault.occurrence_count, fault.status,
             fault.sorted_sources(), muted, root, clusters, auto)
        )  # fmt: skip

    def _clear_record(
        self, request: ClearRequest, *, success: bool, message: str, auto: tuple[str, ...]
    ) -> None:
        self.output.clears.append(
            ClearRecord(
                t_ns=request.t_ns,
                fault_code=request.fault_code,
                skip_correlation_auto_clear=request.skip_correlation_auto_clear,
                success=success,
                message=message,
                auto_cleared_codes=auto,
            )
        )
