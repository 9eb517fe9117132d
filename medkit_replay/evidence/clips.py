"""Black-box recordings: each planned recording's messages counted and, on request, copied
byte for byte (types, definitions, log times) into a rosbag2 folder; never decoded.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import sqlite3
import tempfile
from contextlib import contextmanager, nullcontext
from pathlib import Path
from typing import TYPE_CHECKING

import yaml
from rosbags.rosbag2 import StoragePlugin, Writer, WriterError

from medkit_replay.captures import EvidenceRecording, RecordingTopic
from medkit_replay.errors import MedkitReplayError
from medkit_replay.evidence.folder import (
    MARKER,
    MARKER_TEXT,
    STAGING_PREFIX,
    folder_names,
    foreign,
    is_ours,
)
from medkit_replay.inputs.typestore import message_store

if TYPE_CHECKING:
    from collections.abc import Iterator

    from rosbags.interfaces import Connection

    from medkit_replay.evidence import EvidenceOptions
    from medkit_replay.evidence.plan import Plan, PlannedRecording
    from medkit_replay.evidence.rules import RosbagConfig
    from medkit_replay.evidence.source import EvidenceSource, RawMessage, TopicInfo

_NO_HASH = "RIHS01_" + "0" * 64
_MESSAGE_OVERHEAD = 64  # record headers and index entries per message, roughly
_WRITE_ERRORS = (OSError, sqlite3.Error, WriterError)  # a full disk, as each storage says it


def write_recordings(
    plan: Plan, rosbag: RosbagConfig, options: EvidenceOptions, source: EvidenceSource
) -> tuple[tuple[EvidenceRecording, ...], tuple[str, ...]]:
    """Every planned recording counted, and written when ``options`` asks; with the clip
    folders left unwritten because the evidence folder holds something else under their names.

    Whether to write is decided before any clip is: when one folder is not this tool's, none
    is written, and each recording keeps the path it would have had (the report is the same).

    Raises:
        MedkitReplayError: the evidence folder or a clip cannot be written (nothing half
            written is left behind).
    """
    directory = options.directory
    folders = folder_names([r.name for r in plan.recordings])
    targets = [
        directory / folder
        if directory is not None and (recording.deleted is None or options.everything)
        else None
        for recording, folder in zip(plan.recordings, folders, strict=True)
    ]
    wanted = [t for t in targets if t is not None]
    refused = tuple(str(path) for path in foreign(wanted))
    recordings: list[EvidenceRecording] = []
    writing = _staging(directory) if directory is not None and wanted and not refused else None
    with writing if writing is not None else nullcontext() as staging:
        for recording, target in zip(plan.recordings, targets, strict=True):
            try:
                recordings.append(
                    evidence_recording(
                        recording,
                        plan.subscribed,
                        source,
                        target,
                        staging,
                        rosbag.format,
                        rosbag.max_bag_size_mb * 1024 * 1024,
                    )
                )
            except _WRITE_ERRORS as err:
                reason = (err.strerror if isinstance(err, OSError) else None) or str(err)
                raise MedkitReplayError(
                    f"cannot write recording: {reason} (no part of it was left)",
                    path=str(target),
                ) from None
    return tuple(recordings), refused


@contextmanager
def _staging(directory: Path) -> Iterator[Path]:
    """A new folder in ``directory`` (made if missing), never an existing path nor through a
    link, removed with whatever is left in it however the block ends."""
    try:
        directory.mkdir(parents=True, exist_ok=True)
        path = Path(tempfile.mkdtemp(prefix=STAGING_PREFIX, dir=directory))
    except OSError as err:
        raise MedkitReplayError(
            f"cannot write in the evidence folder: {err.strerror or err}", path=str(directory)
        ) from None
    try:
        yield path
    finally:
        shutil.rmtree(path, ignore_errors=True)


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
    staging: Path | None,
    fmt: str,
    max_bytes: int,
) -> EvidenceRecording:
    """Count the recording's messages; with ``target`` and ``staging``, write them as a rosbag2
    folder in ``staging`` and move it to ``target`` (the recording's path, written or not)."""
    counts: dict[str, int] = {}
    size = 0
    writer = (
        _ClipWriter(target, staging, fmt, source, max_bytes)
        if target is not None and staging is not None
        else None
    )
    try:
        for message in clip_messages(recording, subscribed, source):
            counts[message.topic] = counts.get(message.topic, 0) + 1
            size += len(message.data)
            if writer is not None:
                writer.write(message)
        if writer is not None:
            writer.close()
    except BaseException:
        if writer is not None:
            writer.abort()
        raise
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
    """A rosbag2 folder written in the run's staging folder, marked as ours, then moved into
    place (the staging folder, removed by its owner, takes what a failure leaves).

    Split into files of about ``max_bytes`` (``<name>_0.mcap``, ``<name>_1.mcap``...) as
    rosbag2 splits a bag at ``max_bagfile_size``: a new file once the current one is full.
    """

    def __init__(
        self, target: Path, staging: Path, fmt: str, source: EvidenceSource, max_bytes: int
    ) -> None:
        self.target = target
        self.work = staging / target.name
        self.work.mkdir()
        self.source = source
        self.plugin = storage_plugin(fmt)
        self.max_bytes = max_bytes
        self.parts: list[Path] = []
        self.writer: Writer | None = None
        self.connections: dict[str, Connection] = {}
        self.part_bytes = 0

    def _close_part(self) -> None:
        if self.writer is not None:
            self.writer.close()
            self.writer = None

    def _next_part(self) -> Writer:
        self._close_part()
        part = self.work / f"{self.target.name}_{len(self.parts)}"
        self.parts.append(part)
        writer = Writer(part, version=9, storage_plugin=self.plugin)
        writer.open()
        self.writer = writer
        self.connections = {}
        self.part_bytes = 0
        return writer

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
        if not self.parts:
            self._next_part()  # a recording with no message is still a bag (upstream writes one)
        self._close_part()  # a full disk is often first met here, as the file's index is written
        folder = self.work / "bag"
        folder.mkdir()
        merged = merge_metadata(self.parts, folder)
        (folder / "metadata.yaml").write_text(merged, encoding="utf-8")
        (folder / MARKER).write_text(MARKER_TEXT, encoding="utf-8")
        _install(folder, self.target, self.work / "replaced")

    def abort(self) -> None:
        """Let go of the open storage file; the error being raised is the one to report."""
        with contextlib.suppress(Exception):
            self._close_part()
        self.writer = None


def _install(folder: Path, target: Path, aside: Path) -> None:
    """Move ``folder`` to ``target``; a clip of ours already there is first moved ``aside``
    (into the staging folder, removed with it), and back should the move fail."""
    replaced = os.path.lexists(target)
    if replaced:
        if not is_ours(target):  # checked before any clip was written: it appeared since
            raise MedkitReplayError(
                "appeared while the clips were written and is not one this tool wrote; "
                "not replaced",
                path=str(target),
            )
        target.rename(aside)
    try:
        folder.rename(target)
    except OSError:
        if replaced:
            with contextlib.suppress(OSError):
                aside.rename(target)
        raise


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
