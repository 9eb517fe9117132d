"""The bodies of the gateway's fault routes, its fault event stream and its bulk-data routes,
built from a replay's state at one moment: plain JSON-ready values, no web framework, no I/O.

Upstream: ros2_medkit at 505bc2d5 — fault_handlers.cpp (status filter, lists, the detail with
build_status_object and build_sovd_fault_response), core/faults/fault_scope.cpp (per-entity
scope), ros2/conversions/fault_msg_conversions.cpp and ros2_fault_service_transport.cpp (the
fault and correlation JSON), sse_fault_handler.cpp (event frames), bulkdata_handlers.cpp
(categories, rosbag descriptors, download checks), and the fault manager's GetFault, GetRosbag
and ListRosbags. Bag time stands where the live gateway shows its wall clock.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from typing import TYPE_CHECKING

from medkit_replay.engine.queries import list_faults
from medkit_replay.engine.validation import fault_code_error
from medkit_replay.gateway.errors import (
    ERR_RESOURCE_NOT_FOUND,
    ERR_SERVICE_UNAVAILABLE,
    ID_FIELDS,
    GatewayError,
    bulk_data_not_found,
    bulk_data_not_in_scope,
    invalid_parameter,
)
from medkit_replay.model import NS_PER_SEC, SEVERITY_NAMES

if TYPE_CHECKING:
    from collections.abc import Collection, Container, Iterable, Mapping, Sequence

    from medkit_replay.history import CorrelationState
    from medkit_replay.model import (
        Cluster,
        EvidenceRecording,
        FaultEvent,
        FaultSnapshot,
        MutedFault,
        SnapshotCapture,
        Status,
    )

JsonObject = dict[str, object]

STATUS_VALUES = ("pending", "confirmed", "cleared", "healed", "all")
"""Every ``status`` query value the fault routes accept."""
_ALLOWED_STATUS_TEXT = "pending, confirmed, cleared, healed, all"
_MAX_ROUTE_CODE = 256  # the detail handler's own bound on a fault code, before the manager's
_RECORDING_ID_EXTRA = 32  # a recording id may be this much longer than a fault code

KEEPALIVE = ":keepalive\n\n"
"""The comment the fault stream sends when nothing happened for KEEPALIVE_INTERVAL_SEC."""
KEEPALIVE_INTERVAL_SEC = 30
BUFFERED_EVENTS = 100
"""How many events the live stream keeps for a client resuming with Last-Event-ID."""

_MIMETYPES = {"mcap": "application/x-mcap", "sqlite3": "application/x-sqlite3"}

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


# -- times -------------------------------------------------------------------------------------


def _time_msg(t_ns: int) -> tuple[int, int]:
    """builtin_interfaces/Time of a nanosecond count: (sec, nanosec)."""
    return divmod(t_ns, NS_PER_SEC)


def unix_seconds(t_ns: int) -> float:
    """A fault time as the fault JSON writes it: ``sec + nanosec / 1e9``."""
    sec, nanosec = _time_msg(t_ns)
    return sec + nanosec / 1e9


def _event_seconds(t_ns: int) -> float:
    # The stream's own conversion multiplies by 1e-9, which can differ in the last bit.
    sec, nanosec = _time_msg(t_ns)
    return float(sec) + float(nanosec) * 1e-9


def iso8601(t_ns: int) -> str:
    """``2026-02-04T10:30:00.123Z``: UTC to the millisecond, truncated (format_timestamp_ns)."""
    seconds = abs(t_ns) // NS_PER_SEC * (1 if t_ns >= 0 else -1)
    millis = int((t_ns - seconds * NS_PER_SEC) / 1_000_000)
    try:
        moment = datetime(1970, 1, 1, tzinfo=UTC) + timedelta(seconds=seconds)
    except OverflowError:
        return "1970-01-01T00:00:00.000Z"
    return f"{moment.strftime('%Y-%m-%dT%H:%M:%S')}.{millis:03d}Z"


# -- the status filter -------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class StatusFilter:
    """Which statuses a fault list asks the manager for (absent ``status``: the defaults)."""

    include_pending: bool = True
    include_confirmed: bool = True
    include_cleared: bool = False
    include_healed: bool = False

    @property
    def statuses(self) -> tuple[Status, ...]:
        """The ListFaults request's statuses: ``healed`` asks for PREPASSED too."""
        wanted: list[Status] = []
        if self.include_pending:
            wanted.append("PREFAILED")
        if self.include_confirmed:
            wanted.append("CONFIRMED")
        if self.include_cleared:
            wanted.append("CLEARED")
        if self.include_healed:
            wanted += ["HEALED", "PREPASSED"]
        return tuple(wanted)


_FILTERS = {
    "pending": StatusFilter(True, False, False, False),
    "confirmed": StatusFilter(False, True, False, False),
    "cleared": StatusFilter(False, False, True, True),
    "healed": StatusFilter(False, False, False, True),
    "all": StatusFilter(True, True, True, True),
}


def parse_status_filter(
    value: str | None, extra_params: Mapping[str, object] | None = None
) -> StatusFilter:
    """The filter of a ``status`` query value (None: absent). An unknown value, an empty one
    included, raises the 400 the handler answers; ``extra_params`` join its parameters (the
    per-entity route adds ``{"app_id": id}`` and the like)."""
    if value is None:
        return StatusFilter()
    found = _FILTERS.get(value)
    if found is None:
        params: JsonObject = {
            "allowed_values": _ALLOWED_STATUS_TEXT,
            "parameter": "status",
            "value": value,
        }
        params.update(extra_params or {})
        raise invalid_parameter("Invalid status parameter value", params)
    return found


def query_bool(value: str | None) -> bool:
    """A boolean query parameter: ``true`` or ``1`` in any case; anything else is false."""
    return value is not None and value.lower() in ("true", "1")


# -- fault JSON --------------------------------------------------------------------------------


def severity_label(severity: int) -> str:
    """INFO, WARN, ERROR, CRITICAL; UNKNOWN beyond them."""
    return SEVERITY_NAMES[severity] if 0 <= severity < len(SEVERITY_NAMES) else "UNKNOWN"


def fault_json(fault: FaultSnapshot) -> JsonObject:
    """One fault as the lists and the stream carry it; ``last_passed`` only once it passed."""
    item: JsonObject = {
        "fault_code": fault.fault_code,
        "severity": fault.severity,
        "description": fault.description,
        "first_occurred": unix_seconds(fault.first_occurred_ns),
        "last_occurred": unix_seconds(fault.last_occurred_ns),
    }
    if fault.last_passed_ns != 0:
        item["last_passed"] = unix_seconds(fault.last_passed_ns)
    item["occurrence_count"] = fault.occurrence_count
    item["status"] = fault.status
    item["reporting_sources"] = list(fault.reporting_sources)
    item["severity_label"] = severity_label(fault.severity)
    return item


def _muted_json(muted: MutedFault) -> JsonObject:
    return {
        "fault_code": muted.fault_code,
        "root_cause_code": muted.root_cause_code,
        "rule_id": muted.rule_id,
        "delay_ms": muted.delay_ms,
    }


def _cluster_json(cluster: Cluster) -> JsonObject:
    return {
        "cluster_id": cluster.cluster_id,
        "rule_id": cluster.rule_id,
        "rule_name": cluster.rule_name,
        "label": cluster.label,
        "representative_code": cluster.representative_code,
        "representative_severity": cluster.representative_severity,
        "fault_codes": list(cluster.fault_codes),
        "count": len(cluster.fault_codes),
        "first_at": unix_seconds(cluster.first_at_ns),
        "last_at": unix_seconds(cluster.last_at_ns),
    }


def _listed(
    faults: Iterable[FaultSnapshot],
    correlation: CorrelationState,
    status: StatusFilter,
    include_muted: bool,
) -> list[FaultSnapshot]:
    """ListFaults: the statuses asked for, in code order; muted symptoms left out unless asked."""
    selected = list_faults(faults, status.statuses)
    if include_muted or not correlation.muted:
        return selected
    muted = {m.fault_code for m in correlation.muted}
    return [fault for fault in selected if fault.fault_code not in muted]


def fault_list_body(
    faults: Iterable[FaultSnapshot],
    correlation: CorrelationState,
    status: StatusFilter,
    *,
    include_muted: bool = False,
    include_clusters: bool = False,
) -> JsonObject:
    """``GET /faults``: the items and the x-medkit counts; the muted and cluster details only
    when asked for and not empty. With correlation off, ``correlation`` is empty and the
    counts are 0, as the manager answers without an engine."""
    items = [fault_json(f) for f in _listed(faults, correlation, status, include_muted)]
    extension: JsonObject = {
        "count": len(items),
        "muted_count": len(correlation.muted),
        "cluster_count": len(correlation.clusters),
    }
    if include_muted and correlation.muted:
        extension["muted_faults"] = [_muted_json(m) for m in correlation.muted]
    if include_clusters and correlation.clusters:
        extension["clusters"] = [_cluster_json(c) for c in correlation.clusters]
    return {"items": items, "x-medkit": extension}


# -- per-entity scope --------------------------------------------------------------------------


def _source_in_scope(source: str, scope: Collection[str]) -> bool:
    for fqn in scope:
        if source == fqn or (source.startswith(fqn) and source[len(fqn) : len(fqn) + 1] == "/"):
            return True
    return False


def in_scope(reporting_sources: Sequence[str], sources: Collection[str]) -> bool:
    """Whether a fault belongs to an entity: it has reporting sources, and every one is one of
    the entity's sources or a path below one (``/a/b`` is below ``/a``, ``/ab`` is not)."""
    if not sources or not reporting_sources:
        return False
    return all(_source_in_scope(source, sources) for source in reporting_sources)


def entity_fault_list_body(
    faults: Iterable[FaultSnapshot],
    correlation: CorrelationState,
    status: StatusFilter,
    *,
    kind: str,
    entity_id: str,
    sources: frozenset[str],
    source_id: str = "",
    component_count: int = 0,
) -> JsonObject:
    """``GET /{kind}/{id}/faults``: the faults in the entity's scope (muted ones always left
    out), with the x-medkit block of its kind.

    ``kind`` is the route collection (``apps``...), ``sources`` the entity's reporting-source
    FQNs; ``source_id`` (apps) is the app's FQN; ``component_count`` (areas) the components
    directly in the area.
    """
    listed = _listed(faults, correlation, status, include_muted=False)
    items = [fault_json(f) for f in listed if in_scope(f.reporting_sources, sources)]
    extension: JsonObject
    if kind == "apps":
        extension = {
            "entity_id": entity_id,
            "source_id": source_id,
            "count": len(items),
            "muted_count": len(correlation.muted),
            "cluster_count": len(correlation.clusters),
        }
        return {"items": items, "x-medkit": extension}
    extension = {"entity_id": entity_id, "aggregated": True}
    if kind == "functions":
        extension["aggregation_level"] = "function"
        extension["host_count"] = len(sources)
    elif kind == "components":
        extension["aggregation_level"] = "component"
        extension["app_count"] = len(sources)
    else:
        extension["aggregation_level"] = "area"
        extension["component_count"] = component_count
        extension["app_count"] = len(sources)
    if sources:
        extension["aggregation_sources"] = sorted(sources, key=lambda s: s.encode("utf-8"))
    extension["count"] = len(items)
    return {"items": items, "x-medkit": extension}


# -- the fault detail --------------------------------------------------------------------------


def scoped_fault(
    code: str,
    fault: FaultSnapshot | None,
    *,
    kind: str,
    entity_id: str,
    sources: frozenset[str],
    max_code_length: int,
) -> FaultSnapshot:
    """The fault ``GET /{kind}/{id}/faults/{code}`` shows, or the error the handler answers.

    ``fault`` is what the manager holds under ``code`` (None: nothing); ``max_code_length``
    the release's bound on a code. A code the manager refuses as malformed answers 503, as the
    gateway passes on any GetFault failure that does not say "not found".
    """
    id_field = ID_FIELDS[kind]
    if not code or len(code.encode("utf-8", "surrogateescape")) > _MAX_ROUTE_CODE:
        raise invalid_parameter(
            "Invalid fault code",
            {"details": f"Fault code must be between 1 and {_MAX_ROUTE_CODE} characters"},
        )
    reason = fault_code_error(code, max_code_length)
    if reason is not None:
        raise GatewayError(
            503,
            ERR_SERVICE_UNAVAILABLE,
            "Failed to get fault",
            {"details": reason, id_field: entity_id, "fault_code": code},
        )
    if fault is None:
        raise GatewayError(
            404,
            ERR_RESOURCE_NOT_FOUND,
            "Fault not found",
            {"details": f"Fault not found: {code}", id_field: entity_id, "fault_code": code},
        )
    if not in_scope(fault.reporting_sources, sources):
        raise GatewayError(
            404,
            ERR_RESOURCE_NOT_FOUND,
            "Fault not found",
            {
                "details": "Fault is not in scope for this entity: every reporting source must "
                "be one of the entity's owned apps, and a mixed-source fault that includes any "
                "out-of-entity reporter is rejected to prevent cross-entity disclosure",
                id_field: entity_id,
                "fault_code": code,
            },
        )
    return fault


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


def _order_recordings(recordings: Iterable[EvidenceRecording]) -> list[EvidenceRecording]:
    """Newest first: by the time each was stored (its end), later ones first on a tie."""
    indexed = list(enumerate(recordings))
    indexed.sort(key=lambda pair: (pair[1].end_ns, pair[0]), reverse=True)
    return [recording for _, recording in indexed]


def _bag_size(recording: EvidenceRecording, bag_sizes: Mapping[str, int] | None) -> int:
    if bag_sizes is not None and recording.recording_id in bag_sizes:
        return bag_sizes[recording.recording_id]
    return recording.bytes


def _duration_sec(recording: EvidenceRecording) -> float:
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
    for recording in _order_recordings(r for r in recordings if code in r.fault_codes):
        snapshots.append(
            {
                "type": "rosbag",
                "name": f"rosbag_{recording.recording_id}",
                "bulk_data_uri": f"{entity_path}/bulk-data/rosbags/{recording.recording_id}",
                "size_bytes": _bag_size(recording, bag_sizes),
                "duration_sec": _duration_sec(recording),
                "format": rosbag_format,
                "x-medkit": {"captured_at": iso8601(recording.end_ns)},
            }
        )

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


# -- the fault stream --------------------------------------------------------------------------


def sse_event(event: FaultEvent, event_id: int, *, app_id: str | None = None) -> str:
    """One server-sent event: ``id``, ``event`` and ``data`` lines and the blank line.

    ``app_id``: the app the fault's first reporting source resolves to (event_app_id); the
    data then names it under ``x-medkit``.
    """
    kind = event.event_type.replace("\r", "").replace("\n", "")
    data: JsonObject = {
        "event_type": kind,
        "fault": fault_json(event.fault),
        "timestamp": _event_seconds(event.t_ns),
    }
    if event.auto_cleared_codes:
        data["auto_cleared_codes"] = list(event.auto_cleared_codes)
    if app_id is not None:
        data["x-medkit"] = {"entity_type": "apps", "entity_id": app_id}
    text = json.dumps(
        data, separators=(",", ":"), sort_keys=True, ensure_ascii=False, allow_nan=False
    )
    return f"id: {event_id}\nevent: {kind}\ndata: {text}\n\n"


def event_app_id(
    fault: FaultSnapshot,
    app_ids: Container[str],
    node_to_app: Mapping[str, str] | None = None,
) -> str | None:
    """The app an event's fault is shown under: its first reporting source's app (by the
    node-to-app links when given, else the app named like the node, else
    ``<namespace with _ for />_<node>``); None when no app matches."""
    if not fault.reporting_sources or not fault.reporting_sources[0]:
        return None
    fqn = fault.reporting_sources[0]
    if node_to_app:
        linked = node_to_app.get(fqn) or (node_to_app.get(fqn[1:]) if fqn[0] == "/" else None)
        if linked:
            return linked
    cut = fqn.rfind("/")
    name = fqn[cut + 1 :]
    if name and name in app_ids:
        return name
    if cut > 0:
        namespaced = fqn[1:cut].replace("/", "_") + "_" + name
        if namespaced in app_ids:
            return namespaced
    return None


def parse_last_event_id(value: str | None, newest_id: int) -> int:
    """The id a resuming client last saw: digits only (else 0), at most ``newest_id``."""
    if not value or not value.isascii() or not value.isdigit():
        return 0
    number = int(value)
    if number >= 1 << 64:
        return 0
    return min(number, newest_id)


# -- bulk data ---------------------------------------------------------------------------------


def bulk_categories_body() -> JsonObject:
    """``GET /{kind}/{id}/bulk-data``: only ``rosbags`` (a replay has no upload store)."""
    return {"items": ["rosbags"]}


def rosbag_mimetype(fmt: str) -> str:
    """The MIME type of a bag in ``fmt`` (``mcap``, ``sqlite3``)."""
    return _MIMETYPES.get("sqlite3" if fmt == "db3" else fmt, "application/octet-stream")


def bulk_source_filters(kind: str, sources: frozenset[str], fallback: str) -> list[str]:
    """The sources whose bags an entity lists: its fault sources in byte order; without any,
    ``fallback`` (its FQN, else namespace) except for a function, which then lists none."""
    if sources:
        return sorted(sources, key=lambda s: s.encode("utf-8"))
    if kind == "functions" or not fallback:
        return []
    return [fallback]


def rosbag_descriptors_body(
    recordings: Sequence[EvidenceRecording],
    faults: Mapping[str, FaultSnapshot],
    source_filters: Sequence[str],
    *,
    rosbag_format: str,
    bag_sizes: Mapping[str, int] | None = None,
) -> JsonObject:
    """``GET /{kind}/{id}/bulk-data/rosbags``: one descriptor per recording of a fault that
    one of ``source_filters`` (bulk_source_filters) reports, exactly that source.

    ``recordings``: those held at the moment served (recordings_held_at); ``faults``: the
    faults held then, by code. Per source, the newest rows come first; a
    recording appears once, at its first row, with the codes of its listed rows.
    """
    rows: list[tuple[int, int, str, EvidenceRecording]] = []  # (stored at, seq, code, bag)
    for recording in recordings:
        for code in recording.fault_codes:
            rows.append((recording.end_ns, len(rows), code, recording))
    found: dict[str, tuple[EvidenceRecording, set[str]]] = {}
    for source in source_filters:
        if not source:
            continue
        mine = [
            row for row in rows if row[2] in faults and source in faults[row[2]].reporting_sources
        ]
        mine.sort(key=lambda row: (row[0], row[1]), reverse=True)
        for _, _, code, recording in mine:
            found.setdefault(recording.recording_id, (recording, set()))[1].add(code)
    items = []
    for recording, codes in found.values():
        created = iso8601(recording.end_ns)
        items.append(
            {
                "id": recording.recording_id,
                "name": f"{recording.recording_id} recording {created}",
                "mimetype": rosbag_mimetype(rosbag_format),
                "size": _bag_size(recording, bag_sizes),
                "creation_date": created,
                "x-medkit": {
                    "fault_codes": sorted(codes, key=lambda c: c.encode("utf-8")),
                    "duration_sec": _duration_sec(recording),
                    "format": rosbag_format,
                    "recording_id": recording.recording_id,
                },
            }
        )
    return {"items": items}


@dataclass(frozen=True, slots=True)
class RosbagDownload:
    """What ``GET /{kind}/{id}/bulk-data/rosbags/{bulk_data_id}`` serves."""

    recording: EvidenceRecording
    mimetype: str
    filename: str  # for Content-Disposition


def rosbag_download(
    recordings: Sequence[EvidenceRecording],
    faults: Mapping[str, FaultSnapshot],
    bulk_data_id: str,
    *,
    entity_id: str,
    scope: Collection[str],
    rosbag_format: str,
    max_code_length: int,
) -> RosbagDownload:
    """The recording a bulk-data id names for an entity, or the 404 the gateway answers.

    The id is a recording id, else (older clients) a fault code meaning its newest recording.
    The entity must own one of the recording's faults (and the fault code asked for, on the
    second path); ``scope`` is its bulk_source_filters. A recording that was not written (no
    ``path``) answers as a bag missing from disk does. ``recordings``: those held at the
    moment served (recordings_held_at); ``faults``: the faults held then, by code.
    """
    if fault_code_error(bulk_data_id, max_code_length + _RECORDING_ID_EXTRA) is not None:
        raise bulk_data_not_found(bulk_data_id)
    recording = next((r for r in recordings if r.recording_id == bulk_data_id), None)
    if recording is None:
        if fault_code_error(bulk_data_id, max_code_length) is not None:
            raise bulk_data_not_found(bulk_data_id)
        requested = faults.get(bulk_data_id)
        newest = next(
            (r for r in _order_recordings(recordings) if bulk_data_id in r.fault_codes), None
        )
        if requested is None or newest is None or newest.path is None:
            raise bulk_data_not_found(bulk_data_id)
        if not in_scope(requested.reporting_sources, scope):
            raise bulk_data_not_in_scope(entity_id)
        recording = newest
    elif recording.path is None:
        raise bulk_data_not_found(bulk_data_id)
    owned = any(
        code in faults and in_scope(faults[code].reporting_sources, scope)
        for code in recording.fault_codes
    )
    if not owned:
        raise bulk_data_not_in_scope(entity_id)
    filename = f"{recording.recording_id}.{rosbag_format}".replace('"', "_")
    return RosbagDownload(recording, rosbag_mimetype(rosbag_format), filename)
