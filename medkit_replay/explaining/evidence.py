"""The evidence steps of a fault's story: each freeze frame captured and each black-box recording.

Read from the Result's ``snapshots`` and ``recordings`` (the evidence planner decided them).
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING

from medkit_replay.explaining.entries import when
from medkit_replay.explaining.lines import Entry, Line, part

if TYPE_CHECKING:
    from medkit_replay.captures import EvidenceRecording, SnapshotCapture
    from medkit_replay.explaining.lines import JSON
    from medkit_replay.result import Result

MAX_VALUE_TEXT = 200
"""Characters of a captured message shown on one detail line (the JSON holds it whole)."""


def evidence_entries(result: Result, code: str, origin_ns: int) -> list[Entry]:
    """The captures and recordings of ``code``, in time order (a recording at its start)."""
    entries = [_capture(c, origin_ns) for c in result.snapshots if c.fault_code == code]
    recordings = [r for r in result.recordings if code in r.fault_codes]
    if recordings:
        confirmed = [
            t.t_ns
            for t in result.transitions
            if t.fault_code == code and t.to_status == "CONFIRMED"
        ]
        for recording in recordings:
            inside = [t for t in confirmed if recording.start_ns <= t <= recording.end_ns]
            told_at = max(inside, default=recording.start_ns)
            entries.append(_recording(recording, code, origin_ns, told_at))
    return sorted(entries, key=lambda e: e.t_ns)


def _capture(capture: SnapshotCapture, origin_ns: int) -> Entry:
    topics = [t.topic for t in capture.topics]
    fate = (
        "the live manager still holds it at the end"
        if capture.retained
        else "dropped later (cleared or evicted)"
    )
    line: Line = (
        part("capture ", "kind"),
        part(f"freeze frame {capture.capture_id}: ", "plain"),
        part(", ".join(topics) if topics else "no topic sampled", "topic"),
        part(f"; {fate}" + ("; the fault's freeze frame" if capture.freeze_frame else ""), "dim"),
    )
    details: list[Line] = []
    for topic in capture.topics:
        shown = json.dumps(topic.data, ensure_ascii=True, sort_keys=False)
        if len(shown) > MAX_VALUE_TEXT:
            shown = shown[:MAX_VALUE_TEXT] + " ..."
        details.append(
            (
                part(f"  {topic.topic}", "topic"),
                part(f" ({topic.message_type}, at {when(topic.message_t_ns, origin_ns)}) ", "dim"),
                part(shown, "text"),
            )
        )
    fields: dict[str, JSON] = {
        "t_ns": capture.t_ns,
        "offset_ns": capture.t_ns - origin_ns,
        "kind": "capture",
        "text": "".join(text for text, _ in line),
        "capture_id": capture.capture_id,
        "retained": capture.retained,
        "freeze_frame": capture.freeze_frame,
        "topics": [
            {
                "topic": t.topic,
                "message_type": t.message_type,
                "message_t_ns": t.message_t_ns,
                "data": _json(t.data),
            }
            for t in capture.topics
        ],
    }
    return Entry(
        t_ns=capture.t_ns, kind="capture", line=line, details=tuple(details), fields=fields
    )


def _recording(recording: EvidenceRecording, code: str, origin_ns: int, told_at: int) -> Entry:
    """A recording, told where the fault's confirmation in its window is (else at its start)."""
    shared = [c for c in recording.fault_codes if c != code]
    where = recording.path if recording.path is not None else "not written"
    deleted = (
        f"; the live manager deletes it at {when(recording.deleted_ns, origin_ns)}: "
        f"{recording.deleted_reason}"
        if recording.deleted_ns is not None
        else ""
    )
    line: Line = (
        part("recording ", "kind"),
        part(recording.recording_id, "code"),
        part(
            f" over {when(recording.start_ns, origin_ns)} - {when(recording.end_ns, origin_ns)}: "
            f"{recording.messages} message(s) on {len(recording.topics)} topic(s), "
            f"{recording.bytes} bytes ({where})",
            "plain",
        ),
        part(("; shared with " + ", ".join(shared)) if shared else "", "dim"),
        part(deleted, "dim"),
    )
    fields: dict[str, JSON] = {
        "t_ns": told_at,
        "offset_ns": told_at - origin_ns,
        "kind": "recording",
        "text": "".join(text for text, _ in line),
        "recording_id": recording.recording_id,
        "fault_codes": list(recording.fault_codes),
        "start_ns": recording.start_ns,
        "end_ns": recording.end_ns,
        "messages": recording.messages,
        "bytes": recording.bytes,
        "topics": [
            {"topic": t.topic, "type": t.type, "messages": t.messages} for t in recording.topics
        ],
        "deleted_ns": recording.deleted_ns,
        "deleted_reason": recording.deleted_reason,
        "path": recording.path,
    }
    return Entry(t_ns=told_at, kind="recording", line=line, fields=fields)


def _json(value: object) -> JSON:
    """A captured message's rendering (already JSON values: upstream's serializer output)."""
    return json.loads(json.dumps(value, allow_nan=False))  # type: ignore[no-any-return]
