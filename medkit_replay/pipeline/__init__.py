"""Wires config, inputs, bridges and the engine into one replay that returns a Result.

The only place the layers meet (besides the commands, which call this).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.config.effective import effective_config
from medkit_replay.config.fault_manager import fault_manager_config
from medkit_replay.config.params import load_parameters
from medkit_replay.config.replay_options import replay_options
from medkit_replay.engine.manager import FaultManager
from medkit_replay.engine.timeline import Timeline
from medkit_replay.errors import InputError
from medkit_replay.inputs import is_remote, open_recording
from medkit_replay.inputs.selection import LOG_TYPE
from medkit_replay.model import (
    CLEAR_ROWS,
    EVENT_ROWS,
    REPORT_ROWS,
    TRANSITION_ROWS,
    ClearRecord,
    EngineOutput,
    FaultEvent,
    Phase,
    Progress,
    ReportRecord,
    Transition,
)
from medkit_replay.parity import compare, compare_responses, suggest_action_sources
from medkit_replay.pipeline.assemble import assemble_result
from medkit_replay.pipeline.loop import replay_loop
from medkit_replay.pipeline.meter import Meter
from medkit_replay.pipeline.routing import Gate, Router, recorded_report_codes
from medkit_replay.spool import Spool

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Sequence

    from medkit_replay.inputs.remote_store import Tally
    from medkit_replay.result import Result

__all__ = ["PROGRESS_EVERY", "Phase", "Progress", "replay"]

PROGRESS_EVERY = 2048
"""Messages read between two calls of a replay's ``progress`` callback (by default)."""


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
    paths = [p if is_remote(p) else Path(p) for p in inputs]
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
    router = Router(options)
    tallies: dict[str, Tally] = {}  # bytes fetched from remote inputs, both passes
    recorded_codes = recorded_report_codes(paths, progress, progress_every, tallies)
    gate = Gate(timeline, recorded_codes)
    rosout = router.log is not None
    rosout_topic = router.log.topic if router.log is not None else "/rosout"
    with open_recording(
        paths,
        rosout=rosout,
        diagnostics_topics=(router.diagnostic.topic,),
        rosout_topic=rosout_topic,
        tallies=tallies,
    ) as recording:
        meter = (
            Meter(progress, "replay", recording, progress_every) if progress is not None else None
        )
        messages = replay_loop(recording, meter, timeline, router, gate)
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
    result = assemble_result(
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
    if tallies:
        fetched = {name: (t.fetched, t.size) for name, t in tallies.items()}
        result = dataclasses.replace(result, fetched=fetched)
    return result
