"""Wires config, inputs, bridges and the engine into one replay that returns a Result.

The only place the layers meet (besides the commands, which call this).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING, Any

from medkit_replay.config.effective import effective_config
from medkit_replay.config.fault_manager import fault_manager_config
from medkit_replay.config.params import load_parameters
from medkit_replay.config.release import release_of
from medkit_replay.config.replay_options import replay_options
from medkit_replay.config.snapshots import snapshot_config
from medkit_replay.engine.manager import FaultManager
from medkit_replay.engine.timeline import Timeline
from medkit_replay.errors import InputError
from medkit_replay.evidence import EvidenceOptions, collect_evidence
from medkit_replay.inputs import is_remote, open_recording
from medkit_replay.model import (
    EVENT_ROWS,
    TRANSITION_ROWS,
    FaultEvent,
    Phase,
    Progress,
    Transition,
)
from medkit_replay.parity import compare, compare_responses, suggest_action_sources
from medkit_replay.pipeline.assemble import assemble_result
from medkit_replay.pipeline.consumption import consumption
from medkit_replay.pipeline.loop import replay_loop
from medkit_replay.pipeline.meter import Meter
from medkit_replay.pipeline.routing import Gate, Request, Router, recorded_report_codes
from medkit_replay.pipeline.spooled import spooled_logs
from medkit_replay.result import LOG_BRIDGE_HINT

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Sequence

    from medkit_replay.history import FaultHistory
    from medkit_replay.inputs.follow import Follow
    from medkit_replay.inputs.remote.store import Tally
    from medkit_replay.model import InputSummary, Loss, ReportSink
    from medkit_replay.pipeline.loop import Clock
    from medkit_replay.pipeline.routing import Handler
    from medkit_replay.pipeline.tracing import Tracer
    from medkit_replay.result import Consumption, Result
    from medkit_replay.spool import Row, SpillListener, Spool
    from medkit_replay.trace import FaultTrace

__all__ = ["PROGRESS_EVERY", "Pass", "Phase", "Progress", "replay", "replay_pass"]

PROGRESS_EVERY = 2048
"""Messages read between two calls of a replay's ``progress`` callback (by default)."""


def replay(
    inputs: Sequence[str | Path],
    configs: Iterable[str | Path] = (),
    *,
    progress: Callable[[Progress], None] | None = None,
    progress_every: int = PROGRESS_EVERY,
    trace: FaultTrace | None = None,
    follow: Follow | None = None,
    live: Callable[[Transition | FaultEvent], None] | None = None,
    live_start: Callable[[int], None] | None = None,
    evidence: EvidenceOptions | None = None,
    spill_listener: SpillListener | None = None,
    history: FaultHistory | None = None,
) -> Result:
    """Replay inputs (merged as one recording) through the bridges and the fault manager.

    Args:
        inputs: rosbag2 directories, ``.mcap`` or ``.db3`` files, ROS 1 ``.bag`` files, JSON-lines
            scripts.
        configs: ROS 2 parameter files, later ones overriding earlier ones key by key.
        progress: called with a :class:`Progress` at the start of each pass over the
            recording, every ``progress_every`` messages read, and once at its end
            (``done``). Passes: ``prescan`` (recorded ReportFault calls; bags only), then
            ``replay``. The result does not depend on it; what it raises propagates.
        progress_every: messages between two calls.
        trace: fill this FaultTrace with what the replay does with its fault code (the
            requests and the messages behind them, held requests, correlation decisions,
            transitions, events, clears, the state at ``trace.at_offset_ns``). The Result
            does not depend on it.
        follow: read the inputs while they are written (``medkit-replay follow``), as it
            says; the replay ends when they are finished or it stops. Recorded ReportFault
            codes are then learnt as they arrive; should a bridge have reported one of them
            first, a finished recording is replayed once more as it stands (said in
            ``follow.notes``), so the result is always that of the finished recording.
        live: called with every transition and FaultEvent as the manager records it.
        live_start: called before the first of them with the recording's start (the first
            message read, as ``summary.start_ns``), which people's times count from.
        evidence: the node graph and where to write black-box recordings (freeze frames
            and recordings are listed in the result whatever it says).
        history: fill this FaultHistory with every state each fault went through and the
            correlation view after each change (``serve`` answers any moment from it). The
            Result does not depend on it.
        spill_listener: told of every chunk of events, transitions, reports and clears
            spilled to disk (to encode them elsewhere meanwhile); the Result does not
            depend on it.

    Raises:
        InputError: an input cannot be used at all.
        ConfigError: a config file is missing, invalid, or holds a value upstream refuses.
    """
    if not inputs:
        raise InputError("no input given")
    paths = [p if is_remote(p) else Path(p) for p in inputs]
    configs = tuple(configs)  # read twice when a followed recording is replayed again
    params = load_parameters(Path(c) for c in configs)
    release = release_of(params)
    manager_config, warnings = fault_manager_config(params.node("fault_manager"), release)
    options, option_warnings = replay_options(params, release)
    warnings += option_warnings
    snapshots, snapshot_warnings = snapshot_config(params.node("fault_manager"), release)
    warnings += snapshot_warnings

    spools = spooled_logs(spill_listener)
    events, transitions, reports, clears = spools
    output = spools.output()
    manager = FaultManager(manager_config, output)
    # Rows straight into the spools' tails; the loop settles them now and then.
    event_sink, transition_sink = events.row_sink(), transitions.row_sink()
    timeline = Timeline(manager)
    if live is not None:
        if live_start is not None:
            live = _started(live, live_start, timeline)
        event_sink = _tee(event_sink, EVENT_ROWS.decode, live)
        transition_sink = _tee(transition_sink, TRANSITION_ROWS.decode, live)
    manager.set_row_sinks(reports.row_sink(), event_sink, transition_sink)
    router = Router(options)
    tracer = None
    if trace is not None:  # explain's hooks, loaded only for it
        from medkit_replay.pipeline.tracing import Tracer  # noqa: PLC0415

        tracer = Tracer(trace, timeline, router)
    if history is not None:  # serve's index, loaded only for it
        from medkit_replay.pipeline.history import HistoryRecorder  # noqa: PLC0415

        HistoryRecorder(history, manager, router.log)
    tallies: dict[str, Tally] = {}  # bytes fetched from remote inputs, both passes
    run = replay_pass(
        paths,
        router,
        timeline,
        timeline.apply,
        manager.report_fields,
        (reports, events, transitions),
        progress,
        progress_every,
        follow=follow,
        tracer=tracer,
        tallies=tallies,
    )
    gate, messages, summaries = run.gate, run.messages, run.summaries
    warnings += run.warnings
    if follow is not None and gate.late_codes:
        late = ", ".join(sorted(gate.late_codes))
        if follow.finished:
            follow.notes.append(
                f"recorded ReportFault calls for {late} came after a bridge had reported "
                "them; the report is a replay of the finished recording (the lines printed "
                "live applied those bridge reports)"
            )
            return replay(inputs, configs, progress=progress, progress_every=progress_every)
        warnings.append(
            f"recorded ReportFault calls for {late} came after a bridge had reported them; "
            "those bridge reports were applied (a replay of the finished recording withholds "
            "them: rule: recorded service traffic wins per fault code)"
        )
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
    consumed = run.consumed
    if messages == 0:
        rosout_topic = consumed.rosout_topic
        logs = sum(use.messages for use in consumed.unread if use.origin == "log_bridge")
        off = (
            f"; {rosout_topic} holds {logs} log message(s), which the log bridge would read, "
            f"but it is off (add a log_bridge section to the config, or set {LOG_BRIDGE_HINT})"
            if logs
            else ""
        )
        warnings.append(
            "no topic the replay reads was found (action status, "
            f"{consumed.diagnostics_topic}, ReportFault/ClearFault service events, fault manager "
            "events"
            + (f", {rosout_topic}" if consumed.log_bridge else "")
            + "); the report is empty"
            + off
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
    if spill_listener is not None:
        # A spool that spilled already hands the listener its last records too (one that
        # never did is short: the report writes it at once).
        for spool in spools:
            if spool.batch_count > 1:
                spool.spill()
    config = effective_config(manager_config, options, tuple(str(f) for f in params.files))
    result = assemble_result(
        manager,
        timeline,
        output,
        summaries,
        messages,
        warnings,
        parity,
        spools,
        config,
        consumed,
    )
    found = collect_evidence(
        snapshots,
        evidence if evidence is not None else EvidenceOptions(),
        paths,
        transitions,
        reports,
        sorted({t.topic for s in summaries for t in s.topics}),
    )
    fetched = {name: (t.fetched, t.size) for name, t in tallies.items()}
    return dataclasses.replace(
        result,
        snapshots=found.snapshots,
        recordings=found.recordings,
        evidence_notes=found.notes,
        evidence_refused=found.refused,
        fetched=fetched,
        losses=run.losses,
    )


def _started(
    live: Callable[[Transition | FaultEvent], None],
    live_start: Callable[[int], None],
    timeline: Timeline,
) -> Callable[[Transition | FaultEvent], None]:
    """``live``, told the timeline's start once, before the first record after it is known."""
    told = False

    def show(record: Transition | FaultEvent) -> None:
        nonlocal told
        if not told and timeline.t0_ns is not None:
            told = True
            live_start(timeline.t0_ns)
        live(record)

    return show


def _tee(
    sink: Callable[[Row], None],
    decode: Callable[[Row], Transition | FaultEvent],
    live: Callable[[Transition | FaultEvent], None],
) -> Callable[[Row], None]:
    """A row sink that also hands each record, decoded, to ``live``."""

    def both(row: Row) -> None:
        sink(row)
        live(decode(row))

    return both


@dataclasses.dataclass(frozen=True, slots=True)
class Pass:
    """What one pass over a recording leaves besides the engine's records.

    Attributes:
        messages: messages read.
        gate: the double-counting gate, with what it withheld.
        warnings: the recording's own warnings (damage, refusals).
        summaries: one summary per input.
        consumed: which paths into the fault manager took how much of the recording.
        losses: what the damage warned of cost, one per damage warning.
    """

    messages: int
    gate: Gate
    warnings: list[str]
    summaries: tuple[InputSummary, ...]
    consumed: Consumption
    losses: tuple[Loss, ...] = ()


def replay_pass(
    paths: Sequence[Path | str],
    router: Router,
    clock: Clock,
    apply: Callable[[Request], object],
    report_fields: ReportSink,
    spools: Sequence[Spool[Any]] = (),
    progress: Callable[[Progress], None] | None = None,
    progress_every: int = PROGRESS_EVERY,
    *,
    follow: Follow | None = None,
    tracer: Tracer | None = None,
    tallies: dict[str, Tally] | None = None,
) -> Pass:
    """Read the recording once, in time order, through the router's bridges into the engine.

    The engine is whatever ``clock``, ``apply`` and ``report_fields`` drive: one manager's
    Timeline (``replay``), or several managers fed the same requests (a sweep's fan-out).
    ``spools`` are settled as the loop goes. With ``follow`` the recording is read while it
    is written (recorded ReportFault codes learnt as they arrive); a ``tracer`` (``explain``)
    watches the pass. Bytes fetched from remote inputs are counted in ``tallies``.
    """
    recorded_codes = (
        recorded_report_codes(paths, progress, progress_every, tallies) if follow is None else set()
    )
    gate = Gate(apply, report_fields, recorded_codes, learn=follow is not None)
    if tracer is not None:
        tracer.attach(gate)
    rosout_topic = router.log.topic if router.log is not None else "/rosout"
    with open_recording(
        paths,
        rosout=router.log is not None,
        diagnostics_topics=(router.diagnostic.topic,),
        rosout_topic=rosout_topic,
        follow=follow,
        tallies=tallies,
        release=router.release,
    ) as recording:
        meter = (
            Meter(progress, "replay", recording, progress_every) if progress is not None else None
        )
        routes: dict[tuple[str, str, str], Handler | None] = {}
        messages = replay_loop(recording, meter, clock, router, gate, spools, tracer, routes)
        if meter is not None:
            meter.finish(messages, clock.last_ns)
        summaries = recording.inputs
        consumed = consumption(router, routes, summaries, messages)
        return Pass(
            messages,
            gate,
            list(recording.warnings),
            summaries,
            consumed,
            tuple(recording.losses),
        )
