"""Black-box recordings: each planned recording's messages counted and, on request, copied
byte for byte (types, definitions, log times) into a rosbag2 folder; never decoded.
"""

from __future__ import annotations

import contextlib
import shutil
from typing import TYPE_CHECKING

import yaml
from rosbags.rosbag2 import StoragePlugin, Writer

from medkit_replay.errors import MedkitReplayError
from medkit_replay.inputs.typestore import message_store
from medkit_replay.model import EvidenceRecording, RecordingTopic

if TYPE_CHECKING:
    from collections.abc import Iterator
    from pathlib import Path

    from rosbags.interfaces import Connection

    from medkit_replay.evidence.plan import PlannedRecording
    from medkit_replay.evidence.source import EvidenceSource, RawMessage, TopicInfo

_NO_HASH = "RIHS01_" + "0" * 64
_MESSAGE_OVERHEAD = 64  # record headers and index entries per message, roughly
PARTIAL = ".medkit-replay-partial"
"""Where recordings are written before they move into place (removed when done)."""


def clip_messages(
    recording: PlannedRecording, subscribed: list[str], source: EvidenceSource
) -> Iterator[RawMessage]:
    """The recording's messages in time order: each segment's topics over its span."""
    everything = set(subscribed)
    for segment in recording.segments:
        topics = everything if segment.topics is None else segment.topics & everything
        if topics and segment.start_ns <= segment.end_ns:
            yield from source.read(topics, segment.start_ns, segment.end_ns)


def storage_plugin(fmt: str) -> StoragePlugin:
    """``mcap``, else sqlite3 (upstream's fallback for an unknown format)."""
    return StoragePlugin.MCAP if fmt == "mcap" else StoragePlugin.SQLITE3


def evidence_recording(
    recording: PlannedRecording,
    subscribed: list[str],
    source: EvidenceSource,
    target: Path | None,
    fmt: str,
    max_bytes: int,
) -> EvidenceRecording:
    """Count the recording's messages; with ``target``, write them there as a rosbag2 folder."""
    counts: dict[str, int] = {}
    size = 0
    writer = _ClipWriter(target, fmt, source, max_bytes) if target is not None else None
    try:
        for message in clip_messages(recording, subscribed, source):
            counts[message.topic] = counts.get(message.topic, 0) + 1
            size += len(message.data)
            if writer is not None:
                writer.write(message)
    except BaseException:
        if writer is not None:
            writer.abort()
        raise
    if writer is not None:
        writer.close()
    return EvidenceRecording(
        recording_id=recording.name,
        fault_codes=recording.fault_codes,
        start_ns=recording.start_ns,
        end_ns=recording.end_ns,
        topics=tuple(
            RecordingTopic(topic=t, type=source.topics[t].type, messages=n)
            for t, n in sorted(counts.items())
        ),
        messages=sum(counts.values()),
        bytes=size,
        deleted_ns=recording.deleted[0] if recording.deleted else None,
        deleted_reason=recording.deleted[1] if recording.deleted else None,
        path=str(target) if target is not None else None,
    )


class _ClipWriter:
    """A rosbag2 folder written beside its final name, then moved into place.

    Split into files of about ``max_bytes`` (``<name>_0.mcap``, ``<name>_1.mcap``...) as
    rosbag2 splits a bag at ``max_bagfile_size``: a new file once the current one is full.
    """

    def __init__(self, target: Path, fmt: str, source: EvidenceSource, max_bytes: int) -> None:
        self.target = target
        self.staging = target.parent / PARTIAL / target.name
        if self.staging.exists():
            shutil.rmtree(self.staging)
        self.staging.mkdir(parents=True)
        self.source = source
        self.plugin = storage_plugin(fmt)
        self.max_bytes = max_bytes
        self.parts: list[Path] = []
        self.writer: Writer | None = None
        self.connections: dict[str, Connection] = {}
        self.part_bytes = 0

    def _next_part(self) -> Writer:
        if self.writer is not None:
            self.writer.close()
        part = self.staging / f"{self.target.name}_{len(self.parts)}"
        self.parts.append(part)
        self.writer = Writer(part, version=9, storage_plugin=self.plugin)
        self.writer.open()
        self.connections = {}
        self.part_bytes = 0
        return self.writer

    def _connection(self, writer: Writer, topic: str, info: TopicInfo) -> Connection:
        try:
            store = message_store(info.type, info.definition)
            digest = store.hash_rihs01(info.type)
        except Exception:  # a definition rosbags cannot hash
            store, digest = None, _NO_HASH
        if info.definition.text.strip():
            return writer.add_connection(
                topic,
                info.type,
                msgdef=info.definition.text,
                rihs01=digest,
                serialization_format=info.serialization_format,
            )
        if store is None:
            raise MedkitReplayError(f"{topic}: no definition of {info.type} to record it with")
        return writer.add_connection(topic, info.type, typestore=store)

    def write(self, message: RawMessage) -> None:
        writer = self.writer
        if writer is None or self.part_bytes >= self.max_bytes:
            writer = self._next_part()
        connection = self.connections.get(message.topic)
        if connection is None:
            connection = self._connection(writer, message.topic, self.source.topics[message.topic])
            self.connections[message.topic] = connection
        writer.write(connection, message.t_ns, message.data)
        self.part_bytes += len(message.data) + len(message.topic) + _MESSAGE_OVERHEAD

    def close(self) -> None:
        if self.writer is None:
            self._next_part()  # a recording with no message is still a bag (upstream writes one)
        assert self.writer is not None
        self.writer.close()
        folder = self.staging / "bag"
        folder.mkdir()
        merged = merge_metadata(self.parts, folder)
        (folder / "metadata.yaml").write_text(merged, encoding="utf-8")
        if self.target.exists():
            if not (self.target / "metadata.yaml").is_file():
                raise MedkitReplayError(
                    "exists and is not a recording this tool wrote; not replaced",
                    path=str(self.target),
                )
            shutil.rmtree(self.target)
        folder.rename(self.target)
        shutil.rmtree(self.staging)
        _remove_if_empty(self.staging.parent)

    def abort(self) -> None:
        try:
            if self.writer is not None:
                self.writer.close()
        finally:
            shutil.rmtree(self.staging, ignore_errors=True)
            _remove_if_empty(self.staging.parent)


def merge_metadata(parts: list[Path], folder: Path) -> str:
    """Move each part's storage file into ``folder``; the metadata.yaml of them all."""
    infos = []
    for part in parts:
        loaded = yaml.safe_load((part / "metadata.yaml").read_text(encoding="utf-8"))
        info = loaded["rosbag2_bagfile_information"]
        for name in info["relative_file_paths"]:
            (part / name).rename(folder / name)
        infos.append(info)
    merged = dict(infos[0])
    merged["relative_file_paths"] = [n for i in infos for n in i["relative_file_paths"]]
    merged["files"] = [f for i in infos for f in i["files"]]
    merged["message_count"] = sum(i["message_count"] for i in infos)
    spans = [
        (f["starting_time"]["nanoseconds_since_epoch"], f["duration"]["nanoseconds"])
        for f in merged["files"]
        if f["message_count"]
    ]
    if spans:
        start = min(s for s, _ in spans)
        merged["starting_time"] = {"nanoseconds_since_epoch": start}
        merged["duration"] = {"nanoseconds": max(s + d for s, d in spans) - start}
    topics: dict[str, dict[str, object]] = {}
    for info in infos:
        for entry in info["topics_with_message_count"]:
            name = entry["topic_metadata"]["name"]
            if name in topics:
                count = topics[name]["message_count"]
                assert isinstance(count, int)
                topics[name]["message_count"] = count + entry["message_count"]
            else:
                topics[name] = dict(entry)
    merged["topics_with_message_count"] = list(topics.values())
    return yaml.safe_dump(
        {"rosbag2_bagfile_information": merged}, sort_keys=False, default_flow_style=False
    )


def _remove_if_empty(directory: Path) -> None:
    with contextlib.suppress(OSError):
        directory.rmdir()
