"""The gateway's bulk-data routes for black-box recordings: the categories, the rosbag
descriptors an entity lists, and which recording a download serves (or the 404 it answers).

Upstream: ros2_medkit at 505bc2d5 — bulkdata_handlers.cpp (list_categories, list_descriptors,
fold_rosbag_rows_into_descriptors, download), the fault manager's ListRosbags and GetRosbag.
The bytes themselves are served by the app, from the file the replay wrote.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from medkit_replay.engine.validation import fault_code_error
from medkit_replay.gateway.detail_json import bag_size, duration_sec, ordered_recordings
from medkit_replay.gateway.errors import bulk_data_not_found, bulk_data_not_in_scope
from medkit_replay.gateway.faults_json import JsonObject, in_scope, iso8601

if TYPE_CHECKING:
    from collections.abc import Collection, Mapping, Sequence

    from medkit_replay.captures import EvidenceRecording
    from medkit_replay.model import FaultSnapshot

_MIMETYPES = {"mcap": "application/x-mcap", "sqlite3": "application/x-sqlite3"}
_RECORDING_ID_EXTRA = 32  # a recording id may be this much longer than a fault code


def bulk_categories_body() -> JsonObject:
    """``GET /{kind}/{id}/bulk-data``: only ``rosbags`` (a replay has no upload store)."""
    return {"items": ["rosbags"]}


def rosbag_mimetype(fmt: str) -> str:
    """The MIME type of a bag in ``fmt`` (``mcap``, ``sqlite3``)."""
    return _MIMETYPES.get(fmt, "application/octet-stream")


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
    faults held then, by code. Per source, the newest rows come first; a recording appears
    once, at its first row, with the codes of its listed rows.
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
                "size": bag_size(recording, bag_sizes),
                "creation_date": created,
                "x-medkit": {
                    "fault_codes": sorted(codes, key=lambda c: c.encode("utf-8")),
                    "duration_sec": duration_sec(recording),
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
            (r for r in ordered_recordings(recordings) if bulk_data_id in r.fault_codes), None
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
