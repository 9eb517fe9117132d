"""A replay written plainly: rosbags reads and decodes the messages, bridges and the manager
handle request and record objects one by one (the shape of the replay before speed work).

An oracle for ``medkit_replay.replay``: the report sections the engine produces must agree.
A recording rosbags reads whole is read with ``rosbags.rosbag2.Reader`` and every payload
deserialized by rosbags (``Typestore.deserialize_cdr``), from the definition the product would
choose: the recorded one (as ``inputs.typestore`` builds its store), else the bundled one, the
first that fits kept. Not ``AnyReader``: it parses every recorded definition with rosbags' own
parser and refuses rosbag2's service-event definitions, which the replay reads. What rosbags
cannot read (damaged files, bare files without a readable layout, JSON-lines scripts) goes
through the product's reader with every MCAP chunk read whole, and so through its generated
decoders: for those the oracle checks the engine, not the decoding.
"""

from __future__ import annotations

import heapq
from itertools import count
from typing import TYPE_CHECKING

from rosbags.interfaces import MessageDefinitionFormat
from rosbags.rosbag1 import Reader as Reader1
from rosbags.rosbag2 import Reader

from medkit_replay.bridges.action_status import ActionStatusBridge
from medkit_replay.bridges.diagnostic import DiagnosticBridge
from medkit_replay.bridges.log import LogBridge
from medkit_replay.bridges.service_calls import ServiceCallReplayer
from medkit_replay.config.fault_manager import fault_manager_config
from medkit_replay.config.params import load_parameters
from medkit_replay.config.release import release_of
from medkit_replay.config.replay_options import replay_options
from medkit_replay.engine.manager import FaultManager
from medkit_replay.engine.timeline import Timeline
from medkit_replay.inputs import Message, Selection, open_recording
from medkit_replay.inputs.ros1.messages import TRANSLATIONS, ros1_typestore
from medkit_replay.inputs.typestore import _recorded_store
from medkit_replay.model import ClearRequest, ReportRequest
from medkit_replay.msgdefs import NO_DEFINITION, Definition, base_typestore, normalize_typename
from medkit_replay.outputs.json_report import (
    clear_dict,
    cluster_dict,
    event_dict,
    fault_dict,
    muted_dict,
    near_miss_dict,
    report_dict,
    transition_dict,
)
from tests.oracle.bridges import oracle_diagnostic, oracle_log
from tests.oracle.manager import oracle_report

if TYPE_CHECKING:
    from collections.abc import Iterator, Sequence
    from pathlib import Path

    from rosbags.interfaces import Connection
    from rosbags.typesys.store import Typestore

ENGINE_SECTIONS = (
    "faults",
    "events",
    "transitions",
    "reports",
    "clears",
    "muted_faults",
    "clusters",
    "near_misses",
    "summary",
)
"""The report's keys the oracle reproduces: everything the engine concludes."""

_BRIDGES = ("diagnostic_bridge", "action_status_bridge", "log_bridge")


def oracle_sections(inputs: Sequence[Path], configs: Sequence[Path]) -> dict[str, object]:
    """The engine's report sections for ``inputs`` under ``configs``, computed plainly."""
    params = load_parameters(configs)
    release = release_of(params)
    manager_config, _ = fault_manager_config(params.node("fault_manager"), release)
    options, _ = replay_options(params, release)
    manager = FaultManager(manager_config)  # records as objects in plain lists
    timeline = Timeline(manager)
    diagnostic = DiagnosticBridge(options.diagnostic)
    action = ActionStatusBridge(
        options.action_status, action_sources=options.action_sources, release=release
    )
    log = LogBridge(options.log) if options.log_bridge else None
    services = ServiceCallReplayer()
    recorded = _recorded_codes(inputs)
    messages = 0
    selection = Selection(
        rosout=log is not None,
        diagnostics_topics=(diagnostic.topic,),
        rosout_topic=log.topic if log is not None else "/rosout",
    )
    for message in oracle_messages(inputs, selection):
        messages += 1
        timeline.advance(message.t_ns)
        t_ns, topic, msg = message.t_ns, message.topic, message.msg
        requests: Sequence[ReportRequest | ClearRequest | tuple[object, ...]] = ()
        if message.role == "script":
            assert isinstance(msg, ReportRequest | ClearRequest)
            requests = (msg,)
        elif message.role == "action_status":
            requests = action.on_message(t_ns, topic, msg)
        elif message.role in ("report_fault", "clear_fault"):
            requests = services.on_message(t_ns, topic, message.msgtype, msg)
        elif diagnostic.wants(topic, message.msgtype):
            requests = oracle_diagnostic(diagnostic, t_ns, topic, msg)
        elif log is not None and log.wants(topic, message.msgtype):
            requests = oracle_log(log, t_ns, topic, msg)
        for request in requests:
            _apply(manager, _as_request(request), recorded)
    out = manager.output
    faults = manager.faults()
    correlation = manager.correlation
    accepted = out.reports_accepted
    by_status = dict.fromkeys(("PREFAILED", "PREPASSED", "CONFIRMED", "HEALED", "CLEARED"), 0)
    for fault in faults:
        by_status[fault.status] += 1
    kinds = ("fault_confirmed", "fault_updated", "fault_cleared")
    near = [
        near_miss_dict(entry)
        for code in sorted(manager.storage.near_misses, key=lambda c: c.encode("utf-8"))
        for entry in manager.storage.near_misses[code]
    ]
    start, end = timeline.t0_ns, timeline.last_ns
    return {
        "faults": [fault_dict(f) for f in faults],
        "events": [event_dict(e) for e in out.events],
        "transitions": [transition_dict(t) for t in out.transitions],
        "reports": [report_dict(r) for r in out.reports],
        "clears": [clear_dict(c) for c in out.clears],
        "muted_faults": [muted_dict(m) for m in correlation.muted_faults()] if correlation else [],
        "clusters": [cluster_dict(c) for c in correlation.clusters()] if correlation else [],
        "near_misses": near,
        "summary": {
            "messages_read": messages,
            "reports": len(out.reports),
            "reports_accepted": accepted,
            "reports_rejected": len(out.reports) - accepted,
            "clears": len(out.clears),
            "events": {kind: out.event_counts.get(kind, 0) for kind in kinds},
            "faults": len(faults),
            "faults_by_status": by_status,
            "transitions": len(out.transitions),
            "start_ns": start,
            "end_ns": end,
            "duration_ns": end - start if start is not None and end is not None else 0,
        },
    }


def _recorded_codes(inputs: Sequence[Path]) -> set[str]:
    """Codes in recorded ReportFault calls: the bridges' requests for them are not applied."""
    bags = [path for path in inputs if path.suffix != ".jsonl"]
    if not bags:
        return set()
    services = ServiceCallReplayer()
    codes: set[str] = set()
    for message in oracle_messages(bags, Selection(only_roles=frozenset({"report_fault"}))):
        for request in services.on_message(
            message.t_ns, message.topic, message.msgtype, message.msg
        ):
            codes.add(request.fault_code)
    return codes


def _as_request(
    request: ReportRequest | ClearRequest | tuple[object, ...],
) -> ReportRequest | ClearRequest:
    if not isinstance(request, tuple):
        return request
    t_ns, origin, topic, code, event_type, severity, description, source_id = request
    return ReportRequest(
        t_ns=t_ns,  # type: ignore[arg-type]
        origin=origin,  # type: ignore[arg-type]
        topic=topic,  # type: ignore[arg-type]
        fault_code=code,  # type: ignore[arg-type]
        event_type=event_type,  # type: ignore[arg-type]
        severity=severity,  # type: ignore[arg-type]
        description=description,  # type: ignore[arg-type]
        source_id=source_id,  # type: ignore[arg-type]
    )


def _apply(
    manager: FaultManager, request: ReportRequest | ClearRequest, recorded: set[str]
) -> None:
    if request.origin in _BRIDGES and request.fault_code in recorded:
        return  # recorded service traffic wins for this code
    if isinstance(request, ReportRequest):
        oracle_report(manager, request)
    else:
        manager.clear(request)


def oracle_messages(inputs: Sequence[Path], selection: Selection) -> Iterator[Message]:
    """The selected messages of every input, merged by (log time, input, order read)."""
    streams = [_rosbags_messages(path, index, selection) for index, path in enumerate(inputs)]
    for index, path in enumerate(inputs):
        if streams[index] is None:
            streams[index] = _product_messages(path, index, selection)
    serial = count()
    keyed = [[(m.t_ns, m.input_index, next(serial), m) for m in stream or []] for stream in streams]
    return (item[3] for item in heapq.merge(*keyed))


def _product_messages(path: Path, index: int, selection: Selection) -> list[Message]:
    """The product's reader, every chunk read whole (for what rosbags cannot read)."""
    roles = tuple(selection.only_roles) if selection.only_roles is not None else None
    with open_recording(
        [path],
        rosout=selection.rosout,
        rosout_topic=selection.rosout_topic,
        diagnostics_topics=selection.diagnostics_topics,
        extra_topics=selection.extra_topics,
        only_roles=roles,
        use_index=False,
    ) as recording:
        return [m._replace(input_index=index) for m in recording.messages()]


def _rosbags_messages(path: Path, index: int, selection: Selection) -> list[Message] | None:
    """Every selected message rosbags reads and decodes, or None if rosbags cannot read it."""
    if path.suffix == ".jsonl":
        return None
    if path.suffix == ".bag":
        return _rosbag1_messages(path, index, selection)
    decoders: dict[int, _RosbagsDecoder | None] = {}
    out: list[Message] = []
    try:
        with Reader(path) as reader:
            read = 0
            for connection, t_ns, raw in reader.messages():
                read += 1
                if connection.id not in decoders:
                    decoders[connection.id] = _decoder_for(connection, selection)
                decoder = decoders[connection.id]
                if decoder is None:
                    continue
                msg = decoder.decode(raw)
                if msg is not None:
                    role = decoder.role
                    topic, msgtype = connection.topic, decoder.msgtype
                    out.append(Message(t_ns, index, topic, msgtype, role, msg))  # type: ignore[arg-type]
            if read != reader.message_count:  # read short without a word (seen on zstd chunks)
                return None
    except Exception:  # rosbags cannot read it: the product's reader then
        return None
    return out


def _rosbag1_messages(path: Path, index: int, selection: Selection) -> list[Message] | None:
    """A ROS 1 bag as rosbags' rosbag1 Reader reads it (through its index, time-sorted) and its
    ROS 1 deserializer decodes it; the three bridge types mapped by the product's conversions."""
    store = ros1_typestore()
    out: list[Message] = []
    try:
        with Reader1(path) as reader:
            for connection, t_ns, raw in reader.messages():
                ros1_type = normalize_typename(connection.msgtype)
                translation = TRANSLATIONS.get(ros1_type)
                topic, msgtype = connection.topic, ros1_type
                if translation is not None:
                    topic, msgtype = translation.topic(topic), translation.ros2_type
                role, _ = selection.classify(topic, msgtype)
                if role is None:
                    continue
                msg = store.deserialize_ros1(raw, ros1_type)
                if translation is not None:
                    msg = translation.convert(msg)
                out.append(Message(t_ns, index, topic, msgtype, role, msg))
    except Exception:  # rosbags cannot read it (unindexed, damaged): the product's reader then
        return None
    return out


class _RosbagsDecoder:
    """rosbags' deserializer over the candidate definitions, the first that fits kept."""

    def __init__(self, role: str, msgtype: str, stores: list[Typestore]) -> None:
        self.role, self.msgtype, self.stores = role, msgtype, stores

    def decode(self, raw: bytes) -> object | None:
        for index, store in enumerate(self.stores):
            try:
                msg = store.deserialize_cdr(raw, self.msgtype)
            except Exception:  # rosbags refuses: the next definition
                continue
            self.stores.insert(0, self.stores.pop(index))
            return msg
        return None  # skipped, as the replay skips a payload no definition fits


def _decoder_for(connection: Connection, selection: Selection) -> _RosbagsDecoder | None:
    msgtype = normalize_typename(connection.msgtype)
    role, _ = selection.classify(connection.topic, msgtype)
    serialization = getattr(connection.ext, "serialization_format", "cdr")
    if role is None or serialization != "cdr":
        return None
    kind = {MessageDefinitionFormat.MSG: "ros2msg", MessageDefinitionFormat.IDL: "ros2idl"}
    definition = (
        Definition(kind[connection.msgdef.format], connection.msgdef.data)
        if connection.msgdef.format in kind
        else NO_DEFINITION
    )
    stores: list[Typestore] = []
    if definition.text.strip():
        recorded = _recorded_store(msgtype, definition)
        if not isinstance(recorded, str):
            stores.append(recorded[1])
    if msgtype in base_typestore().fielddefs:
        stores.append(base_typestore())
    return _RosbagsDecoder(role, msgtype, stores) if stores else None
