"""Black-box recordings: each planned recording's messages counted and, on request, copied
byte for byte (types, definitions, log times) into a rosbag2 folder; never decoded.
"""

from __future__ import annotations

import contextlib
import shutil
from typing import TYPE_CHECKING

from rosbags.rosbag2 import StoragePlugin, Writer

from medkit_replay.errors import MedkitReplayError
from medkit_replay.inputs.typestore import message_store
from medkit_replay.model import EvidenceRecording, RecordingTopic
from medkit_replay.msgdefs import DefinitionError

if TYPE_CHECKING:
    from collections.abc import Iterator
    from pathlib import Path

    from rosbags.interfaces import Connection

    from medkit_replay.evidence.plan import PlannedRecording
    from medkit_replay.evidence.source import EvidenceSource, RawMessage, TopicInfo

_NO_HASH = "RIHS01_" + "0" * 64
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
) -> EvidenceRecording:
    """Count the recording's messages; with ``target``, write them there as a rosbag2 folder."""
    counts: dict[str, int] = {}
    size = 0
    writer = _ClipWriter(target, fmt, source) if target is not None else None
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
    """A rosbag2 folder written beside its final name, then moved into place."""

    def __init__(self, target: Path, fmt: str, source: EvidenceSource) -> None:
        self.target = target
        self.partial = target.parent / PARTIAL / target.name
        if self.partial.exists():
            shutil.rmtree(self.partial)
        self.partial.parent.mkdir(parents=True, exist_ok=True)
        self.source = source
        self.writer = Writer(self.partial, version=9, storage_plugin=storage_plugin(fmt))
        self.writer.open()
        self.connections: dict[str, Connection] = {}

    def _connection(self, topic: str, info: TopicInfo) -> Connection:
        try:
            store = message_store(info.type, info.definition)
            digest = store.hash_rihs01(info.type)
        except (DefinitionError, Exception):  # a definition rosbags cannot hash
            store, digest = None, _NO_HASH
        if info.definition.text.strip():
            return self.writer.add_connection(
                topic,
                info.type,
                msgdef=info.definition.text,
                rihs01=digest,
                serialization_format=info.serialization_format,
            )
        if store is None:
            raise MedkitReplayError(f"{topic}: no definition of {info.type} to record it with")
        return self.writer.add_connection(topic, info.type, typestore=store)

    def write(self, message: RawMessage) -> None:
        connection = self.connections.get(message.topic)
        if connection is None:
            connection = self._connection(message.topic, self.source.topics[message.topic])
            self.connections[message.topic] = connection
        self.writer.write(connection, message.t_ns, message.data)

    def close(self) -> None:
        self.writer.close()
        if self.target.exists():
            if not (self.target / "metadata.yaml").is_file():
                raise MedkitReplayError(
                    "exists and is not a recording this tool wrote; not replaced",
                    path=str(self.target),
                )
            shutil.rmtree(self.target)
        self.partial.rename(self.target)
        _remove_if_empty(self.partial.parent)

    def abort(self) -> None:
        try:
            self.writer.close()
        finally:
            shutil.rmtree(self.partial, ignore_errors=True)
            _remove_if_empty(self.partial.parent)


def _remove_if_empty(directory: Path) -> None:
    with contextlib.suppress(OSError):
        directory.rmdir()
