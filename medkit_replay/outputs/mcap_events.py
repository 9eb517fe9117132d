"""An MCAP recording of what the replayed fault manager published, to view beside the robot's bag.

Two topics, each message stamped with the bag time of the change (log time = publish time):

- ``/fault_manager/events``: ``ros2_medkit_msgs/msg/FaultEvent``, exactly the events the live
  manager would have published (``timestamp`` = bag time; the fault's times likewise), in the
  message layout of the release modelled (0.6.0's Fault has no ``last_passed``);
- ``/medkit_replay/transitions``: ``medkit_replay_msgs/msg/FaultTransition``, every status change
  (also the silent ones, e.g. auto-confirmation), a small message type of medkit-replay's own.

``builtin_interfaces/Time`` has an int32 ``sec``, as upstream's: a bag time it cannot hold
(before 1901-12-13 20:45:52 or after 2038-01-19 03:14:07 UTC) is saturated to its nearest end,
``sec`` -2^31 with ``nanosec`` 0 or ``sec`` 2^31-1 with ``nanosec`` 999999999; the log and publish
times (uint64 nanoseconds) keep the exact bag time. One warning says how many stamps were.

The file is a rosbag2 MCAP (profile ``ros2``, CDR, schemas as ``ros2msg`` text with their
dependencies appended in rosbag2's ``====`` / ``MSG:`` layout), so Foxglove, rosbags, the ``mcap``
tools and medkit-replay itself read it without any ROS package installed. Same result, same bytes.
"""

from __future__ import annotations

import heapq
from functools import cache
from typing import IO, TYPE_CHECKING, Any, BinaryIO, Protocol, cast

from mcap.writer import CompressionType, Writer
from rosbags.typesys import Stores, get_typestore

from medkit_replay.model import NS_PER_SEC
from medkit_replay.msgdefs import MEDKIT_PACKAGE, Definition, bundled_text, types_from_definition
from medkit_replay.outputs.atomic import atomic_binary
from medkit_replay.outputs.console import warn as warn_stderr
from medkit_replay.releases import release_named
from medkit_replay.version import __version__

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator
    from pathlib import Path

    from rosbags.typesys.store import MsgType, Typestore

    from medkit_replay.model import FaultEvent, FaultSnapshot, Transition
    from medkit_replay.result import Result

EVENTS_TOPIC = "/fault_manager/events"
FAULT_EVENT_TYPE = f"{MEDKIT_PACKAGE}/msg/FaultEvent"
TRANSITIONS_TOPIC = "/medkit_replay/transitions"
TRANSITION_TYPE = "medkit_replay_msgs/msg/FaultTransition"

TIME_MSG = """\
# builtin_interfaces/msg/Time: ROS time, seconds and nanoseconds.
int32 sec
uint32 nanosec
"""

TRANSITION_MSG = """\
# A status change of one fault, as medkit-replay found it (not an upstream ros2_medkit message).
# Published on /medkit_replay/transitions at the bag time of the change.
string CAUSE_REPORT = "report"
string CAUSE_AUTO_CONFIRM = "auto_confirm"
string CAUSE_CLEAR = "clear"
string CAUSE_AUTO_CLEAR = "auto_clear"

# Bag time of the change.
builtin_interfaces/Time stamp
string fault_code
# Status before the change; empty when the change created the fault.
string from_status
# PREFAILED, PREPASSED, CONFIRMED, HEALED or CLEARED.
string to_status
# One of the CAUSE_ constants.
string cause
# The reporting source of the request that caused it; empty unless cause is "report".
string source_id
"""

DEFAULT_QOS = """\
- history: keep_last
  depth: 10
  reliability: reliable
  durability: volatile
  deadline:
    sec: 9223372036
    nsec: 854775807
  lifespan:
    sec: 9223372036
    nsec: 854775807
  liveliness: automatic
  liveliness_lease_duration:
    sec: 9223372036
    nsec: 854775807
  avoid_ros_namespace_conventions: false
"""
"""rclcpp's default QoS, offered on both topics (rosbag2's ``offered_qos_profiles`` layout)."""

_RULE = "=" * 80
SEC_MIN = -(2**31)
SEC_MAX = 2**31 - 1
"""builtin_interfaces/Time.sec is an int32."""
UINT64_MAX = 2**64 - 1
UINT32_MAX = 2**32 - 1


class _McapWriter(Protocol):
    """The part of ``mcap.writer.Writer`` used here, typed (the library leaves it untyped)."""

    def start(self, profile: str, library: str) -> None: ...
    def register_schema(self, name: str, encoding: str, data: bytes) -> int: ...
    def register_channel(
        self, topic: str, message_encoding: str, schema_id: int, metadata: dict[str, str]
    ) -> int: ...
    def add_message(
        self, channel_id: int, log_time: int, data: bytes, publish_time: int, sequence: int
    ) -> None: ...
    def finish(self) -> None: ...


def _concatenated(text: str, dependencies: list[tuple[str, str]]) -> str:
    """A definition with its dependencies appended as rosbag2 stores it (``MSG: pkg/Name``)."""
    parts = [text.rstrip("\n")]
    for name, body in dependencies:
        parts.append(f"{_RULE}\nMSG: {name}\n{body.rstrip(chr(10))}")
    return "\n".join(parts) + "\n"


@cache
def schemas(definitions: str = "") -> dict[str, str]:
    """The ``ros2msg`` schema text embedded for each type written, dependencies included;
    ``definitions``: the release's ros2_medkit_msgs (``Release.msg_definitions``)."""
    time = ("builtin_interfaces/Time", TIME_MSG)
    fault = (f"{MEDKIT_PACKAGE}/Fault", bundled_text("Fault", definitions))
    return {
        FAULT_EVENT_TYPE: _concatenated(bundled_text("FaultEvent", definitions), [fault, time]),
        TRANSITION_TYPE: _concatenated(TRANSITION_MSG, [time]),
    }


@cache
def message_store(definitions: str = "") -> Typestore:
    """A typestore built from exactly the schema text embedded, so data and schema agree."""
    store = get_typestore(Stores.EMPTY)
    for name, text in schemas(definitions).items():
        store.register(types_from_definition(name, Definition("ros2msg", text)))
    return store


def time_fields(t_ns: int) -> tuple[int, int, bool]:
    """``sec`` and ``nanosec`` of a builtin_interfaces/Time for a bag time, and whether it had
    to be saturated to int32 seconds (see the module's docstring)."""
    sec, nanosec = divmod(t_ns, NS_PER_SEC)
    if sec < SEC_MIN:
        return SEC_MIN, 0, True
    if sec > SEC_MAX:
        return SEC_MAX, NS_PER_SEC - 1, True
    return sec, nanosec, False


def saturated_stamps(result: Result) -> int:
    """How many stamps of the file ``time_fields`` saturates."""
    on_wire = _has_last_passed(_definitions(result))
    count = sum(time_fields(t.t_ns)[2] for t in result.transitions)
    for event in result.events:
        fault = event.fault
        for t_ns in (event.t_ns, fault.first_occurred_ns, fault.last_occurred_ns):
            count += time_fields(t_ns)[2]
        if on_wire:
            count += time_fields(fault.last_passed_ns)[2]
    return count


def _definitions(result: Result) -> str:
    """The ros2_medkit_msgs of the release the result modelled."""
    return release_named(result.upstream_release).msg_definitions


def _time(store: Typestore, t_ns: int) -> MsgType:
    sec, nanosec, _ = time_fields(t_ns)
    return store.types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec)


def _text(value: str) -> str:
    """Text CDR can carry (UTF-8): a lone surrogate is written as its escape, ``\\udcff``."""
    return value if value.isascii() else value.encode("utf-8", "backslashreplace").decode()


def _texts(values: tuple[str, ...]) -> list[str]:
    return [_text(value) for value in values]


def _fault(store: Typestore, fault: FaultSnapshot, definitions: str) -> MsgType:
    fields: dict[str, Any] = {
        "fault_code": _text(fault.fault_code),
        "severity": fault.severity,
        "description": _text(fault.description),
        "first_occurred": _time(store, fault.first_occurred_ns),
        "last_occurred": _time(store, fault.last_occurred_ns),
        "occurrence_count": fault.occurrence_count,
        "status": fault.status,
        "reporting_sources": _texts(fault.reporting_sources),
    }
    if _has_last_passed(definitions):  # not on 0.6.0's wire (cd8c19b0, #573)
        fields["last_passed"] = _time(store, fault.last_passed_ns)
    return store.types[f"{MEDKIT_PACKAGE}/msg/Fault"](**fields)


@cache
def _has_last_passed(definitions: str) -> bool:
    fault = message_store(definitions).fielddefs[f"{MEDKIT_PACKAGE}/msg/Fault"]
    return any(name == "last_passed" for name, _ in fault[1])


def fault_event_cdr(event: FaultEvent, definitions: str = "") -> bytes:
    """One replayed FaultEvent as the CDR payload the live manager would have published, in
    the layout of the release's ros2_medkit_msgs (``Release.msg_definitions``)."""
    store = message_store(definitions)
    message = store.types[FAULT_EVENT_TYPE](
        event_type=event.event_type,
        fault=_fault(store, event.fault, definitions),
        timestamp=_time(store, event.t_ns),
        auto_cleared_codes=_texts(event.auto_cleared_codes),
    )
    return bytes(store.serialize_cdr(message, FAULT_EVENT_TYPE))


def transition_cdr(transition: Transition) -> bytes:
    """One status change as a ``medkit_replay_msgs/msg/FaultTransition`` CDR payload."""
    store = message_store()
    message = store.types[TRANSITION_TYPE](
        stamp=_time(store, transition.t_ns),
        fault_code=_text(transition.fault_code),
        from_status=transition.from_status or "",
        to_status=transition.to_status,
        cause=transition.cause,
        source_id=_text(transition.source_id or ""),
    )
    return bytes(store.serialize_cdr(message, TRANSITION_TYPE))


def _timeline(result: Result) -> Iterator[tuple[int, int, str, bytes]]:
    """(t_ns, order, topic, payload) in bag-time order; a change before the event it caused."""
    definitions = _definitions(result)
    transitions = ((t.t_ns, 0, TRANSITIONS_TOPIC, t) for t in result.transitions)
    events = ((e.t_ns, 1, EVENTS_TOPIC, e) for e in result.events)
    for t_ns, order, topic, item in heapq.merge(transitions, events, key=lambda x: x[:2]):
        if topic == EVENTS_TOPIC:
            yield t_ns, order, topic, fault_event_cdr(cast("FaultEvent", item), definitions)
        else:
            yield t_ns, order, topic, transition_cdr(cast("Transition", item))


def write_mcap_stream(result: Result, stream: BinaryIO | IO[bytes]) -> dict[str, int]:
    """Write the MCAP to an open binary stream; returns the messages written per topic."""
    writer = cast("_McapWriter", Writer(stream, compression=CompressionType.ZSTD))
    writer.start(profile="ros2", library=f"medkit-replay {__version__}")
    channels: dict[str, int] = {}
    texts = schemas(_definitions(result))
    for topic, msgtype in ((EVENTS_TOPIC, FAULT_EVENT_TYPE), (TRANSITIONS_TOPIC, TRANSITION_TYPE)):
        schema = writer.register_schema(msgtype, "ros2msg", texts[msgtype].encode("utf-8"))
        channels[topic] = writer.register_channel(
            topic, "cdr", schema, {"offered_qos_profiles": DEFAULT_QOS}
        )
    counts = dict.fromkeys(channels, 0)
    for t_ns, _, topic, payload in _timeline(result):
        counts[topic] += 1
        log_time = min(max(t_ns, 0), UINT64_MAX)
        sequence = counts[topic] & UINT32_MAX
        writer.add_message(channels[topic], log_time, payload, log_time, sequence)
    writer.finish()
    return counts


def write_mcap(
    result: Result, path: Path, *, warn: Callable[[str], None] = warn_stderr
) -> dict[str, int]:
    """Write the replayed FaultEvents and status changes to an MCAP file at ``path``, through a
    temporary file renamed into place (whole or not at all).

    Stamps that builtin_interfaces/Time cannot hold are saturated (module docstring), with one
    warning for the file.

    Returns:
        Messages written per topic.

    Raises:
        OSError: the file cannot be written.
    """
    with atomic_binary(path) as stream:
        counts = write_mcap_stream(result, stream)
    saturated = saturated_stamps(result)
    if saturated:
        warn(
            f"{path}: {saturated:,} stamp(s) outside builtin_interfaces/Time's int32 "
            f"seconds (before 1901-12-13 or after 2038-01-19 UTC) saturated to sec {SEC_MIN} or "
            f"{SEC_MAX}; log times and the JSON report hold the exact bag times"
        )
    return counts
