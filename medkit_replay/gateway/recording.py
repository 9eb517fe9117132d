"""What ``serve`` answers from: one replay's result, its fault history, the entities and the clips.

Built once before the server starts; every request reads it and nothing changes it after.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.gateway.entities import discover
from medkit_replay.model import NS_PER_SEC
from medkit_replay.releases import release_named

if TYPE_CHECKING:
    from medkit_replay.captures import SnapshotCapture
    from medkit_replay.evidence.graph import NodeGraph
    from medkit_replay.gateway.entities import Entities
    from medkit_replay.history import FaultHistory
    from medkit_replay.result import Result


@dataclass(frozen=True, slots=True)
class ServedRecording:
    """One replayed recording, ready to answer the gateway's read-only routes.

    ``origin_ns`` is the recording's start (``at=0``), ``end_ns`` its last message; ``clips``
    maps a black-box recording's id to the storage file the replay wrote for it (the only
    files ever served); ``default_at_ns`` is ``--at`` (None: the end); ``retain_on_clear``:
    ``snapshots.retain_on_clear`` as the replay applied it.
    """

    result: Result
    history: FaultHistory
    entities: Entities
    origin_ns: int
    end_ns: int
    clips: dict[str, Path]
    default_at_ns: int | None = None
    rosbag_format: str = "mcap"
    bag_sizes: dict[str, int] = dataclasses.field(default_factory=dict)
    max_code_length: int = 256
    retain_on_clear: bool = False

    def moment(self, seconds: float | None) -> int:
        """Bag time of ``seconds`` from the start; None: ``--at``, else the end.

        A moment past the end is the end; one before the start is the start (nothing yet).
        """
        if seconds is None:
            return self.default_at_ns if self.default_at_ns is not None else self.end_ns
        t_ns = self.origin_ns + round(seconds * NS_PER_SEC)
        return max(self.origin_ns, min(t_ns, self.end_ns))

    def captures_at(self, code: str, t_ns: int) -> list[SnapshotCapture]:
        """The freeze frames and snapshots of ``code`` taken by ``t_ns``, with their flags:
        the detail body shows those the manager keeps (a clear can drop a capture's rows yet
        keep it as the fault's compact freeze frame)."""
        return [c for c in self.result.snapshots if c.fault_code == code and c.t_ns <= t_ns]

    def recording_facts(self) -> dict[str, object]:
        """The ``x-medkit`` route's body: the recording served, its span and the release."""
        result = self.result
        return {
            "tool": "medkit-replay",
            "tool_version": result.tool_version,
            "upstream_release": result.upstream_release,
            "inputs": [  # as the report lists them, without the topics
                {f.name: getattr(s, f.name) for f in dataclasses.fields(s) if f.name != "topics"}
                for s in result.inputs
            ],
            "start_ns": self.origin_ns,
            "end_ns": self.end_ns,
            "duration_sec": (self.end_ns - self.origin_ns) / NS_PER_SEC,
            "default_at_sec": (
                (self.default_at_ns - self.origin_ns) / NS_PER_SEC
                if self.default_at_ns is not None
                else None
            ),
            "faults": len(result.faults),
            "events": len(result.events),
            "recordings": len(result.recordings),
            "warnings": list(result.warnings),
        }


_FORMATS = {".mcap": "mcap", ".db3": "sqlite3"}
"""A clip's storage file by suffix, and the format the gateway names it by."""


def served_recording(
    result: Result,
    history: FaultHistory,
    graph: NodeGraph | None,
    at_sec: float | None,
    *,
    retain_on_clear: bool = False,
) -> ServedRecording:
    """What ``serve`` answers from, once the replay (with ``history``) is done.

    Entities come from the graph's nodes, every reporting source the replay saw and the nodes
    that logged on /rosout (when the log bridge reads it); a clip is
    served from the storage file inside the folder the replay wrote for it.
    """
    first, last = result.span()
    origin = first if first is not None else 0
    end = last if last is not None else origin
    clips: dict[str, Path] = {}
    sizes: dict[str, int] = {}
    for recording in result.recordings:
        if recording.path is not None:
            folder = [p for p in Path(recording.path).iterdir() if p.is_file()]
            files = sorted(p for p in folder if p.suffix in _FORMATS)
            if len(files) == 1:
                clips[recording.recording_id] = files[0]
                # The gateway's size_bytes: the bag folder's files on disk.
                sizes[recording.recording_id] = sum(p.stat().st_size for p in folder)
    formats = {_FORMATS[p.suffix] for p in clips.values()}
    served = ServedRecording(
        result=result,
        history=history,
        entities=discover(history.sources, graph),  # joined with the graph's nodes there
        origin_ns=origin,
        end_ns=end,
        clips=clips,
        rosbag_format=formats.pop() if len(formats) == 1 else "mcap",
        bag_sizes=sizes,
        max_code_length=release_named(result.upstream_release).max_fault_code_length,
        retain_on_clear=retain_on_clear,
    )
    if at_sec is not None:
        return dataclasses.replace(served, default_at_ns=served.moment(at_sec))
    return served
