"""The live manager's evidence as values: freeze-frame captures and black-box recordings.

Neutral ground, like ``model``: every layer may import this module; it imports nothing of ours.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True, kw_only=True)
class SnapshotTopic:
    """One topic's value in a freeze frame: the message as upstream's serializer renders it."""

    topic: str
    message_type: str
    message_t_ns: int
    data: object


@dataclass(frozen=True, slots=True, kw_only=True)
class SnapshotCapture:
    """One freeze-frame capture the live manager would have run at a report-driven confirmation.

    ``retained``: its rows would still be stored at the end (not dropped on clear, not evicted
    by ``max_per_fault``); ``freeze_frame``: it is the fault's compact freeze frame at the end.
    """

    fault_code: str
    capture_id: int
    t_ns: int
    retained: bool
    freeze_frame: bool
    topics: tuple[SnapshotTopic, ...]


@dataclass(frozen=True, slots=True, kw_only=True)
class RecordingTopic:
    """One topic of a black-box recording."""

    topic: str
    type: str
    messages: int


@dataclass(frozen=True, slots=True, kw_only=True)
class EvidenceRecording:
    """One black-box recording (rosbag2 folder) the live manager would have written.

    ``fault_codes``: the primary fault first, then those that confirmed in its post-roll;
    ``bytes``: the payload bytes of its messages; ``deleted_ns``/``deleted_reason``: when and
    why the live manager would have deleted it (None: it would still hold it at the end);
    ``path``: where it was written, or None.
    """

    recording_id: str
    fault_codes: tuple[str, ...]
    start_ns: int
    end_ns: int
    topics: tuple[RecordingTopic, ...]
    messages: int
    bytes: int
    deleted_ns: int | None
    deleted_reason: str | None
    path: str | None
