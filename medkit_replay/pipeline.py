"""Wires config, inputs, bridges and the engine into one replay that returns a Result.

The only place the layers meet (besides the CLI, which calls this).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.bridges.action_status import ActionStatusBridge
from medkit_replay.bridges.diagnostic import DiagnosticBridge
from medkit_replay.bridges.log import LogBridge
from medkit_replay.bridges.service_calls import ServiceCallReplayer
from medkit_replay.config.effective import effective_config
from medkit_replay.config.fault_manager import fault_manager_config
from medkit_replay.config.params import load_parameters
from medkit_replay.config.replay_options import ReplayOptions, replay_options
from medkit_replay.engine.manager import FaultManager
from medkit_replay.engine.timeline import Timeline
from medkit_replay.errors import InputError
from medkit_replay.inputs import Message, open_recording
from medkit_replay.inputs.selection import LOG_TYPE
from medkit_replay.model import (
    CLEAR_ROWS,
    EVENT_ROWS,
    REPORT_ROWS,
    TRANSITION_ROWS,
    ClearRecord,
    ClearRequest,
    EngineOutput,
    FaultEvent,
    InputSummary,
    Phase,
    Progress,
    ReportRecord,
    ReportRequest,
    Transition,
)
from medkit_replay.parity import (
    RecordedEvent,
    compare,
    compare_responses,
    recorded_event,
    suggest_action_sources,
)
from medkit_replay.result import EVENT_KINDS, STATUSES, Result, Summary
from medkit_replay.spool import Spool
from medkit_replay.version import __version__

if TYPE_CHECKING:
    from collections.abc import Iterable, Sequence

    from medkit_replay.bridges.base import ReportSink
    from medkit_replay.inputs import Recording
    from medkit_replay.model import Origin

__all__ = ["PROGRESS_EVERY", "Phase", "Progress", "replay"]

Request = ReportRequest | ClearRequest
_Handler = Callable[[int, str, object, "ReportSink"], None]
_BRIDGE_ORIGINS = ("diagnostic_bridge", "action_status_bridge", "log_bridge")

PROGRESS_EVERY = 2048
"""Messages read between two calls of a replay's ``progress`` callback (by default)."""

SETTLE_EVERY = 1024
"""Messages between two spills of the records the fast path piled up (bounds memory)."""


class _Meter:
    """Calls a progress callback every ``every`` messages of one pass (cheap to tick)."""

    __slots__ = ("callback", "end_ns", "every", "next_at", "phase", "start_ns")

    def __init__(
        self,
        callback: Callable[[Progress], None],
        phase: Phase,
        recording: Recording,
        every: int,
    ) -> None:
        self.callback = callback
        self.phase: Phase = phase
        span = recording.span
        self.start_ns: int | None = span[0] if span is not None else None
        self.end_ns: int | None = span[1] if span is not None else None
        self.every = max(every, 1)
        self.next_at = self.every
        callback(Progress(phase, 0, None, self.start_ns, self.end_ns))

    def tick(self, messages: int, t_ns: int) -> None:
        """Report; called by the loop when ``messages`` reaches ``next_at``."""
        self.next_at = messages + self.every
        self.callback(Progress(self.phase, messages, t_ns, self.start_ns, self.end_ns))

    def finish(self, messages: int, t_ns: int | None) -> None:
        """Report the end of the pass."""
        self.callback(Progress(self.phase, messages, t_ns, self.start_ns, self.end_ns, done=True))


class _Router:
    """Hands each message to the bridge for its role and collects what they say."""

    def __init__(self, options: ReplayOptions) -> None:
        self.diagnostic = DiagnosticBridge(options.diagnostic)
        self.action = ActionStatusBridge(
            options.action_status, action_sources=options.action_sources
        )
        self.log = LogBridge(options.log) if options.log_bridge else None
        self.services = ServiceCallReplayer()
        self.recorded_events: Spool[RecordedEvent] = Spool()

    def requests(self, message: Message) -> Sequence[Request]:
        """What a message without a bridge handler carries: script requests, recorded service
        calls; recorded FaultEvents are kept for parity."""
        role, t_ns, topic, msg = message.role, message.t_ns, message.topic, message.msg
        if role == "script":
            assert isinstance(msg, ReportRequest | ClearRequest)
            return (msg,)
        if role in ("report_fault", "clear_fault"):
            return self.services.on_message(t_ns, topic, message.msgtype, msg)
        if role == "fault_events":
            self.recorded_events.append(recorded_event(t_ns, topic, msg))
        return ()

    def handler(self, role: str, topic: str, msgtype: str) -> _Handler | None:
        """The bridge that takes messages of this role, topic and type, if any (None: the
        message goes to :meth:`requests`)."""
        if role == "diagnostics" and self.diagnostic.wants(topic, msgtype):
            return self.diagnostic.feed
        if role == "rosout" and self.log is not None and self.log.wants(topic, msgtype):
            return self.log.feed
        if role == "action_status":
            return self.action.feed
        return None


def _recorded_report_codes(
    inputs: Sequence[Path],
    progress: Callable[[Progress], None] | None,
    every: int,
) -> set[str]:
    """Fault codes present in recorded ReportFault traffic (a pre-pass over those topics only)."""
    services = ServiceCallReplayer()
    codes: set[str] = set()
    bags = [p for p in inputs if p.suffix != ".jsonl"]
    if not bags:
        return codes
    with open_recording(bags, only_roles=("report_fault",)) as recording:
        meter = _Meter(progress, "prescan", recording, every) if progress is not None else None
        next_at = meter.next_at if meter is not None else 0
        messages = 0
        last_t: int | None = None
        for message in recording.messages():
            messages += 1
            last_t = message.t_ns
            if messages == next_at and meter is not None:
                meter.tick(messages, last_t)
                next_at = meter.next_at
            for request in services.on_message(
                message.t_ns, message.topic, message.msgtype, message.msg
            ):
                codes.add(request.fault_code)
        if meter is not None:
            meter.finish(messages, last_t)
    return codes


def replay(
    inputs: Sequence[str | Path],
    configs: Iterable[str | Path] = (),
    *,
    progress: Callable[[Progress], None] | None = None,
    progress_every: int = PROGRESS_EVERY,
) -> Result:
    """Replay inputs (merged as one recording) through the bridges and the fault manager.

    Args:
        inputs: rosbag2 directories, ``.mcap`` or ``.db3`` files, JSON-lines scripts.
        configs: ROS 2 parameter files, later ones overriding earlier ones key by key.
        progress: called with a :class:`Progress` at the start of each pass over the
            recording, every ``progress_every`` messages read, and once at its end
            (``done``). Passes: ``prescan`` (recorded ReportFault calls; bags only), then
            ``replay``. The result does not depend on it; what it raises propagates.
        progress_every: messages between two calls.

    Raises:
        InputError: an input cannot be used at all.
        ConfigError: a config file is missing, invalid, or holds a value upstream refuses.
    """
    if not inputs:
        raise InputError("no input given")
    paths = [Path(p) for p in inputs]
    params = load_parameters(Path(c) for c in configs)
    manager_config, warnings = fault_manager_config(params.node("fault_manager"))
    options, option_warnings = replay_options(params)
    warnings += option_warnings

    events: Spool[FaultEvent] = Spool(codec=EVENT_ROWS)
    transitions: Spool[Transition] = Spool(codec=TRANSITION_ROWS)
    reports: Spool[ReportRecord] = Spool(codec=REPORT_ROWS)
    clears: Spool[ClearRecord] = Spool(codec=CLEAR_ROWS)
    output = EngineOutput(events=events, transitions=transitions, reports=reports, clears=clears)
    manager = FaultManager(manager_config, output)
    # Rows straight into the spools' tails; the loop settles them now and then.
    manager.set_row_sinks(reports.row_sink(), events.row_sink(), transitions.row_sink())
    timeline = Timeline(manager)
    router = _Router(options)
    recorded_codes = _recorded_report_codes(paths, progress, progress_every)
    gate = _Gate(timeline, recorded_codes)
    rosout = router.log is not None
    rosout_topic = router.log.topic if router.log is not None else "/rosout"
    with open_recording(
        paths,
        rosout=rosout,
        diagnostics_topics=(router.diagnostic.topic,),
        rosout_topic=rosout_topic,
    ) as recording:
        meter = (
            _Meter(progress, "replay", recording, progress_every) if progress is not None else None
        )
        messages = _replay_loop(recording, meter, timeline, router, gate)
        warnings += recording.warnings
        summaries = recording.inputs
        if meter is not None:
            meter.finish(messages, timeline.last_ns)
    for origin, count in sorted(gate.withheld.items()):
        codes = len(gate.withheld_codes[origin])
        warnings.append(
            f"double counting avoided: {count} request(s) of the simulated {origin} for "
            f"{codes} code(s) also in recorded ReportFault traffic were not "
            "applied; the recorded calls were (rule: recorded service traffic wins per fault code)"
        )
    for topic, count in sorted(router.services.metadata_only.items()):
        if count:
            warnings.append(
                f"{topic}: {count} call(s) recorded without their request (metadata-only service "
                "introspection); they cannot be replayed"
            )
    if messages == 0:
        logs = sum(
            t.messages
            for s in summaries
            for t in s.topics
            if t.topic == rosout_topic and t.type == LOG_TYPE
        )
        off = (
            f"; {rosout_topic} holds {logs} log message(s), which the log bridge would read, "
            "but it is off (add a log_bridge section to the config, or set medkit_replay: "
            "{enable_log_bridge: true})"
            if logs and not rosout
            else ""
        )
        warnings.append(
            "no topic the replay reads was found (action status, "
            f"{router.diagnostic.topic}, ReportFault/ClearFault service events, fault manager "
            "events" + (f", {rosout_topic}" if rosout else "") + "); the report is empty" + off
        )
    parity: dict[str, object] | None = None
    if len(router.recorded_events):
        parity = compare(router.recorded_events, events)
        suggestion = suggest_action_sources(router.recorded_events, router.action, options)
        if suggestion:
            parity["suggested_action_sources"] = suggestion
            warnings.append(
                "the live manager saw other reporting sources for action faults; set "
                "medkit_replay.action_sources to "
                + ", ".join(f"{a}: {n}" for a, n in suggestion.items())
            )
    if router.services.responses:
        parity = parity if parity is not None else {}
        parity["service_responses"] = compare_responses(router.services.responses, reports, clears)
    config = effective_config(manager_config, options, tuple(str(f) for f in params.files))
    return _result(
        manager,
        timeline,
        output,
        summaries,
        messages,
        warnings,
        parity,
        (events, transitions, reports, clears),
        config,
    )


class _Gate:
    """The double-counting rule between bridges and the manager: recorded service traffic wins.

    A bridge's request for a code also present in recorded ReportFault calls is withheld.
    """

    def __init__(self, timeline: Timeline, recorded_codes: set[str]) -> None:
        self.timeline = timeline
        self.recorded_codes = recorded_codes
        self.withheld: Counter[str] = Counter()
        self.withheld_codes: dict[str, set[str]] = {}
        report_fields = timeline.manager.report_fields
        self.report: ReportSink = self._report_gated if recorded_codes else report_fields
        self._report_fields = report_fields

    def _withhold(self, origin: str, fault_code: str) -> None:
        self.withheld[origin] += 1
        self.withheld_codes.setdefault(origin, set()).add(fault_code)

    def apply(self, request: Request) -> None:
        """One request object (a script's, a recorded service call's)."""
        if request.origin in _BRIDGE_ORIGINS and request.fault_code in self.recorded_codes:
            self._withhold(request.origin, request.fault_code)
        elif isinstance(request, ReportRequest):
            self._report_fields(
                request.t_ns, request.origin, request.topic, request.fault_code,
                request.event_type, request.severity, request.description, request.source_id,
            )  # fmt: skip
        else:
            self.timeline.apply(request)

    def _report_gated(
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
        # Only bridges report through here.
        if fault_code in self.recorded_codes:
            self._withhold(origin, fault_code)
            return
        self._report_fields(
            t_ns, origin, topic, fault_code, event_type, severity, description, source_id
        )


def _replay_loop(
    recording: Recording, meter: _Meter | None, timeline: Timeline, router: _Router, gate: _Gate
) -> int:
    """Every message, in time order, to its bridge (field by field into the manager, which
    records rows) or as request objects to the gate; timers run before each message's time."""
    messages = 0
    next_at = meter.next_at if meter is not None else 0  # 0: never reached
    settle_at = SETTLE_EVERY
    output = timeline.manager.output
    logs = (output.reports, output.events, output.transitions)
    spools = [log for log in logs if isinstance(log, Spool)]
    report, apply = gate.report, gate.apply
    handlers: dict[tuple[str, str, str], _Handler | None] = {}
    due = timeline.due_ns()
    t_ns: int | None = None
    for t_ns, input_index, topic, msgtype, role, msg in recording.message_tuples():
        messages += 1
        if messages == next_at and meter is not None:
            meter.tick(messages, t_ns)
            next_at = meter.next_at
        if messages == settle_at:
            settle_at += SETTLE_EVERY
            for spool in spools:
                spool.settle()
        if t_ns >= due:
            timeline.advance(t_ns)
            due = timeline.due_ns()
        key = (role, topic, msgtype)
        try:
            handler = handlers[key]
        except KeyError:
            handler = handlers[key] = router.handler(role, topic, msgtype)
        if handler is not None:
            handler(t_ns, topic, msg, report)
        else:
            message = Message(t_ns, input_index, topic, msgtype, role, msg)
            for request in router.requests(message):
                apply(request)
    if t_ns is not None:
        timeline.last_ns = t_ns  # what each advance(t) before the due time would have noted
    return messages


def _result(
    manager: FaultManager,
    timeline: Timeline,
    output: EngineOutput,
    summaries: Sequence[InputSummary],
    messages: int,
    warnings: list[str],
    parity: dict[str, object] | None,
    logs: tuple[Spool[FaultEvent], Spool[Transition], Spool[ReportRecord], Spool[ClearRecord]],
    config: dict[str, object],
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
    )
