"""Evidence: the freeze frames and black-box recordings the live fault manager would have captured.

Planned from the replay's transitions (plan), read in a second pass over the recording by topic
and time range (source), freeze frames decoded and rendered (frames), recordings copied (clips).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.evidence.folder import refuse_folder_overlap
from medkit_replay.evidence.frames import freeze_frames
from medkit_replay.evidence.graph import NodeGraph, load_graph
from medkit_replay.evidence.plan import plan_evidence
from medkit_replay.evidence.rules import RosbagConfig, SnapshotConfig

if TYPE_CHECKING:
    from collections.abc import Iterable

    from medkit_replay.captures import EvidenceRecording, SnapshotCapture
    from medkit_replay.evidence.plan import Plan
    from medkit_replay.evidence.source import EvidenceSource
    from medkit_replay.model import ReportRecord, Transition

__all__ = [
    "Evidence",
    "EvidenceOptions",
    "NodeGraph",
    "RosbagConfig",
    "SnapshotConfig",
    "collect_evidence",
    "load_graph",
]


@dataclass(frozen=True, slots=True, kw_only=True)
class EvidenceOptions:
    """How the evidence of one replay is gathered and where recordings go.

    Attributes:
        graph: the robot's node graph (entity-default freeze frames, entity-scoped recordings).
        directory: write each recording there as a rosbag2 folder (None: only list them).
        everything: also write the recordings the live manager would have deleted.
    """

    graph: NodeGraph | None = None
    directory: Path | None = None
    everything: bool = False


@dataclass(frozen=True, slots=True)
class Evidence:
    """What a replay's captures produced."""

    snapshots: tuple[SnapshotCapture, ...] = ()
    recordings: tuple[EvidenceRecording, ...] = ()
    notes: tuple[str, ...] = field(default_factory=tuple)
    refused: tuple[str, ...] = ()
    """Clip folders not written: the evidence folder held something else under their names."""


def collect_evidence(
    config: SnapshotConfig,
    options: EvidenceOptions,
    inputs: Iterable[Path | str],
    transitions: Iterable[Transition],
    reports: Iterable[ReportRecord],
    recorded_topics: Iterable[str],
) -> Evidence:
    """Plan the captures from the transitions, then read what they would have taken.

    Raises:
        MedkitReplayError: the evidence folder overlaps an input, or cannot be written.
    """
    inputs = list(inputs)
    if options.directory is not None:  # the command refused it before the replay already
        local = [path for path in inputs if isinstance(path, Path)]
        refuse_folder_overlap(options.directory, local)
    unused = (
        ("--evidence is given but snapshots.rosbag.enabled is false: no recording to write",)
        if options.directory is not None and not config.rosbag.enabled
        else ()
    )
    if not config.captures:
        return Evidence(notes=unused)
    source: EvidenceSource | None = None

    def opened() -> EvidenceSource:
        nonlocal source
        if source is None:
            # The reader of recordings' topic ranges, loaded only when a capture reads one.
            from medkit_replay.evidence.source import EvidenceSource  # noqa: PLC0415

            source = EvidenceSource(inputs)
        return source

    def probe(topics: Iterable[str], start_ns: int, end_ns: int) -> bool:
        return opened().any_between(topics, start_ns, end_ns)

    try:
        plan = plan_evidence(config, transitions, reports, recorded_topics, options.graph, probe)
        if plan.captures or plan.recordings:
            found = _gather(plan, config, options, opened())
        else:
            found = Evidence(notes=tuple(plan.notes))
    finally:
        if source is not None:
            source.close()
    return dataclasses.replace(found, notes=(*found.notes, *unused)) if unused else found


def _gather(
    plan: Plan, config: SnapshotConfig, options: EvidenceOptions, source: EvidenceSource
) -> Evidence:
    notes = list(plan.notes)
    cut: list[int] = []
    snapshots = freeze_frames(plan, config, source, cut)
    if cut:
        notes.append(
            f"{len(cut)} freeze-frame capture(s) held in part (capture ids "
            f"{', '.join(map(str, cut[:20]))}{' ...' if len(cut) > 20 else ''}): the fault "
            f"reached snapshots.max_per_fault ({config.max_per_fault}) rows during the capture, "
            "and this release keeps a fault's first rows"
        )
    recordings: tuple[EvidenceRecording, ...] = ()
    refused: tuple[str, ...] = ()
    if plan.recordings:
        # rosbags' writers load only for a replay that plans recordings.
        from medkit_replay.evidence.clips import write_recordings  # noqa: PLC0415

        recordings, refused = write_recordings(plan, config.rosbag, options, source)
    if source.skipped:  # after the reads: damage met inside a capture's window is listed too
        notes.append("evidence could not be read from: " + "; ".join(source.skipped))
    return Evidence(snapshots, recordings, tuple(notes), refused)
