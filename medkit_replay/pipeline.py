"""Wires config, inputs, bridges and the engine into one replay that returns a Result.

The only place the layers meet (besides the CLI, which calls this).
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.config.fault_manager import fault_manager_config
from medkit_replay.config.params import load_parameters
from medkit_replay.engine.manager import FaultManager
from medkit_replay.engine.timeline import Timeline
from medkit_replay.errors import InputError
from medkit_replay.inputs.jsonl import open_script
from medkit_replay.model import (
    ClearRecord,
    ClearRequest,
    EngineOutput,
    FaultEvent,
    InputSummary,
    ReportRecord,
    ReportRequest,
    Transition,
)
from medkit_replay.result import EVENT_KINDS, STATUSES, Result, Summary
from medkit_replay.spool import Spool
from medkit_replay.version import __version__

if TYPE_CHECKING:
    from collections.abc import Iterable, Iterator, Sequence

Request = ReportRequest | ClearRequest


@dataclass(frozen=True, slots=True)
class _Item:
    """One message of the merged stream and the requests it yields."""

    t_ns: int
    input_index: int
    position: int
    requests: tuple[Request, ...]


class _ScriptSource:
    """A JSON-lines script as a stream of items, with its summary filled as it is read."""

    def __init__(self, path: Path, index: int) -> None:
        self.path = path
        self.index = index
        self.count = 0
        self.start_ns: int | None = None
        self.end_ns: int | None = None

    def items(self) -> Iterator[_Item]:
        for position, line in enumerate(open_script(self.path)):
            t_ns = line.request.t_ns
            if self.start_ns is None:
                self.start_ns = t_ns
            self.end_ns = t_ns
            self.count += 1
            yield _Item(t_ns, self.index, position, (line.request,))

    def summary(self) -> InputSummary:
        return InputSummary(
            path=str(self.path),
            storage="jsonl",
            start_ns=self.start_ns,
            end_ns=self.end_ns,
            message_count=self.count,
        )


def _open_source(path: Path, index: int) -> _ScriptSource:
    if path.suffix == ".jsonl":
        if not path.is_file():
            raise InputError("input not found", path=str(path))
        return _ScriptSource(path, index)
    raise InputError(
        "unsupported input (expected a .jsonl script, a rosbag2 directory, a .mcap or a .db3 file)",
        path=str(path),
    )


def replay(inputs: Sequence[str | Path], configs: Iterable[str | Path] = ()) -> Result:
    """Replay inputs (merged as one recording) through the fault manager.

    Args:
        inputs: JSON-lines scripts, rosbag2 directories, ``.mcap`` or ``.db3`` files.
        configs: ROS 2 parameter files, later ones overriding earlier ones key by key.

    Raises:
        InputError: an input cannot be used at all.
        ConfigError: a config file is missing, invalid, or holds a value upstream refuses.
    """
    if not inputs:
        raise InputError("no input given")
    params = load_parameters(Path(c) for c in configs)
    manager_config, warnings = fault_manager_config(params.node("fault_manager"))
    events: Spool[FaultEvent] = Spool()
    transitions: Spool[Transition] = Spool()
    reports: Spool[ReportRecord] = Spool()
    clears: Spool[ClearRecord] = Spool()
    output = EngineOutput(events=events, transitions=transitions, reports=reports, clears=clears)
    manager = FaultManager(manager_config, output)
    timeline = Timeline(manager)
    sources = [_open_source(Path(p), i) for i, p in enumerate(inputs)]
    merged = heapq.merge(
        *(s.items() for s in sources), key=lambda it: (it.t_ns, it.input_index, it.position)
    )
    messages = 0
    for item in merged:
        messages += 1
        timeline.advance(item.t_ns)
        for request in item.requests:
            timeline.apply(request)
    faults = manager.faults()
    correlation = manager.correlation
    near_misses = [
        entry
        for code in sorted(manager.storage.near_misses, key=lambda c: c.encode("utf-8"))
        for entry in manager.storage.near_misses[code]
    ]
    by_status = dict.fromkeys(STATUSES, 0)
    for fault in faults:
        by_status[fault.status] += 1
    by_event = dict.fromkeys(EVENT_KINDS, 0)
    for event in output.events:
        by_event[event.event_type] += 1
    accepted = sum(1 for r in output.reports if r.accepted)
    summary = Summary(
        messages_read=messages,
        reports=len(output.reports),
        reports_accepted=accepted,
        reports_rejected=len(output.reports) - accepted,
        clears=len(output.clears),
        events=by_event,
        faults=len(faults),
        faults_by_status=by_status,
        transitions=len(output.transitions),
        start_ns=timeline.t0_ns,
        end_ns=timeline.last_ns,
    )
    return Result(
        tool_version=__version__,
        inputs=tuple(s.summary() for s in sources),
        faults=tuple(faults),
        events=events,
        transitions=transitions,
        reports=reports,
        clears=clears,
        muted_faults=tuple(correlation.muted_faults()) if correlation else (),
        clusters=tuple(correlation.clusters()) if correlation else (),
        near_misses=tuple(near_misses),
        retroactive_mutes=tuple(output.retroactive_mutes),
        warnings=tuple(warnings + output.warnings),
        summary=summary,
    )
