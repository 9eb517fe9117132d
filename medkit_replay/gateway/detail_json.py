"""The body of the gateway's fault detail route: the fault's SOVD status, its freeze frames and
the black-box recordings the manager holds for it, as plain JSON-ready values (no I/O).

Upstream: ros2_medkit at 505bc2d5 — fault_handlers.cpp (build_status_object,
build_sovd_fault_response) and the fault manager's snapshot and rosbag storage. Bag time stands
where the live gateway shows its wall clock.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.gateway.faults_json import JsonObject, iso8601, severity_label
from medkit_replay.model import NS_PER_SEC

if TYPE_CHECKING:
    from collections.abc import Iterable, Mapping, Sequence

    from medkit_replay.captures import EvidenceRecording, SnapshotCapture
    from medkit_replay.model import FaultSnapshot

# Primary field shown as a freeze frame's ``data`` for common message types.
_PRIMARY_FIELDS = {
    "std_msgs/msg/Float64": "data",
    "std_msgs/msg/Float32": "data",
    "std_msgs/msg/Int32": "data",
    "std_msgs/msg/Int64": "data",
    "std_msgs/msg/Bool": "data",
    "std_msgs/msg/String": "data",
    "sensor_msgs/msg/Temperature": "temperature",
    "sensor_msgs/msg/BatteryState": "percentage",
    "sensor_msgs/msg/FluidPressure": "fluid_pressure",
    "sensor_msgs/msg/Range": "range",
    "geometry_msgs/msg/Twist": "linear",
    "nav_msgs/msg/Odometry": "pose",
}


def status_object(status: str) -> JsonObject:
    """The SOVD status of a fault status (build_status_object)."""
    aggregated, failed, confirmed, pending = {
        "CONFIRMED": ("active", True, True, False),
        "PREFAILED": ("passive", True, False, True),
        "PREPASSED": ("passive", False, False, True),
    }.get(status, ("cleared", False, False, False))
    return {
        "aggregatedStatus": aggregated,
        "testFailed": "1" if failed else "0",
        "confirmedDTC": "1" if confirmed else "0",
        "pendingDTC": "1" if pending else "0",
    }


def _primary_value(message_type: str, data: object) -> object:
    field = _PRIMARY_FIELDS.get(message_type)
    if field is not None and isinstance(data, dict) and field in data:
        return data[field]
    return data


def _freeze_frame(name: str, topic: str, message_type: str, data: object, at_ns: int) -> JsonObject:
    return {
        "type": "freeze_frame",
        "name": name,
        "data": _primary_value(message_type, data),
        "x-medkit": {
            "topic": topic,
            "message_type": message_type,
            "full_data": data,
            "captured_at": iso8601(at_ns),
        },
    }


def _topic_name(topic: str) -> str:
    """A topic's last path segment (the fault manager's snapshot name)."""
    cut = topic.rfind("/")
    return topic[cut + 1 :] if cut != -1 and cut < len(topic) - 1 else topic


def _snapshot_rows(captures: Sequence[SnapshotCapture]) -> list[JsonObject]:
    """The held captures' per-topic rows, newest capture first (storage's order)."""
    rows = [(c.capture_id, t.message_t_ns, t) for c in captures if c.retained for t in c.topics]
    rows.sort(key=lambda row: (row[0], row[1]), reverse=True)
    return [
        _freeze_frame(_topic_name(t.topic), t.topic, t.message_type, t.data, t.message_t_ns)
        for _, _, t in rows
    ]


def _compact_frame(capture: SnapshotCapture) -> JsonObject:
    data = {t.topic: t.data for t in sorted(capture.topics, key=lambda t: t.topic.encode())}
    # Stored once the capture ends: when its last topic's message came, at the earliest.
    at_ns = max([capture.t_ns, *(t.message_t_ns for t in capture.topics)])
    return _freeze_frame("freeze_frame", "", "", data, at_ns)


def recordings_held_at(
    recordings: Iterable[EvidenceRecording], t_ns: int
) -> list[EvidenceRecording]:
    """The recordings the manager holds once bag time ``t_ns`` has passed: stored when their
    post-roll ended, until deleted; in the order they were stored."""
    return [
        r for r in recordings if r.end_ns <= t_ns and (r.deleted_ns is None or r.deleted_ns > t_ns)
    ]


def ordered_recordings(recordings: Iterable[EvidenceRecording]) -> list[EvidenceRecording]:
    """Newest first: by the time each was stored (its end), later ones first on a tie."""
    indexed = list(enumerate(recordings))
    indexed.sort(key=lambda pair: (pair[1].end_ns, pair[0]), reverse=True)
    return [recording for _, recording in indexed]


def bag_size(recording: EvidenceRecording, bag_sizes: Mapping[str, int] | None) -> int:
    """A bag's ``size_bytes``: its bytes on disk when known, else its messages' payload."""
    if bag_sizes is not None and recording.recording_id in bag_sizes:
        return bag_sizes[recording.recording_id]
    return recording.bytes


def duration_sec(recording: EvidenceRecording) -> float:
    """A bag's ``duration_sec``: the span it was open (buffered history plus post-roll)."""
    return (recording.end_ns - recording.start_ns) / NS_PER_SEC


def fault_detail_body(
    fault: FaultSnapshot,
    captures: Sequence[SnapshotCapture],
    recordings: Sequence[EvidenceRecording],
    *,
    kind: str,
    entity_id: str,
    rosbag_format: str,
    retain_on_clear: bool = False,
    bag_sizes: Mapping[str, int] | None = None,
) -> JsonObject:
    """``GET /{kind}/{id}/faults/{code}``: item, environment_data and x-medkit.

    ``captures``: freeze-frame captures, their ``retained`` and ``freeze_frame`` flags saying
    what the manager holds at the moment served (those of other faults are skipped).
    ``recordings``: those held at that moment (recordings_held_at); the fault's are shown.
    ``bag_sizes``: bytes on disk by recording id (default: the messages' payload bytes).
    """
    code = fault.fault_code
    captures = [c for c in captures if c.fault_code == code]
    item: JsonObject = {"code": code}
    if fault.description:
        item["fault_name"] = fault.description
    item["severity"] = fault.severity
    item["status"] = status_object(fault.status)

    snapshots = _snapshot_rows(captures)
    if not snapshots or retain_on_clear:
        frame = next((c for c in captures if c.freeze_frame), None)
        if frame is not None:
            snapshots.append(_compact_frame(frame))
    entity_path = f"/{kind}/{entity_id}"
    for recording in ordered_recordings(r for r in recordings if code in r.fault_codes):
        bag: JsonObject = {
            "type": "rosbag",
            "name": f"rosbag_{recording.recording_id}",
            "bulk_data_uri": f"{entity_path}/bulk-data/rosbags/{recording.recording_id}",
            "size_bytes": bag_size(recording, bag_sizes),
            "duration_sec": duration_sec(recording),
            "format": rosbag_format,
        }
        if recording.end_ns > 0:  # a zero stamp is left out rather than shown as 1970
            bag["x-medkit"] = {"captured_at": iso8601(recording.end_ns)}
        snapshots.append(bag)

    extension: JsonObject = {"occurrence_count": fault.occurrence_count}
    if fault.reporting_sources:
        extension["reporting_sources"] = list(fault.reporting_sources)
    extension["severity_label"] = severity_label(fault.severity)
    extension["status_raw"] = fault.status
    return {
        "item": item,
        "environment_data": {
            "extended_data_records": {
                "first_occurrence": iso8601(fault.first_occurred_ns),
                "last_occurrence": iso8601(fault.last_occurred_ns),
            },
            "snapshots": snapshots,
        },
        "x-medkit": extension,
    }
