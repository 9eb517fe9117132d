"""ROS 1 messages in their ROS 2 shape: the three kinds the bridges read, and their topic names.

Pure: maps decoded ROS 1 messages onto the bundled ROS 2 types (README "ROS 1 bags"); no I/O.
"""

from __future__ import annotations

import uuid
from functools import cache, lru_cache
from typing import TYPE_CHECKING, NamedTuple, Protocol, cast

import numpy as np
from rosbags.typesys import Stores, get_typestore

from medkit_replay.inputs.selection import ACTION_STATUS_SUFFIX
from medkit_replay.msgdefs import base_typestore

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from numpy.typing import NDArray
    from rosbags.typesys.store import Msg, Typestore

ROS1_DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"
ROS1_GOAL_STATUS_ARRAY = "actionlib_msgs/msg/GoalStatusArray"
ROS1_LOG = "rosgraph_msgs/msg/Log"
"""ROS 1 type names as normalised (``pkg/msg/Name``); a ROS 1 bag spells them ``pkg/Name``."""

ROS1_STATUS_SUFFIX = "/status"

GOAL_STATUS_TO_ROS2: dict[int, int] = {
    0: 1,  # PENDING -> ACCEPTED: accepted, not yet executing
    1: 2,  # ACTIVE -> EXECUTING
    2: 5,  # PREEMPTED -> CANCELED: canceled after it started executing (terminal)
    3: 4,  # SUCCEEDED -> SUCCEEDED
    4: 6,  # ABORTED -> ABORTED
    5: 0,  # REJECTED -> UNKNOWN: a ROS 2 server rejects in the goal response; never listed
    6: 3,  # PREEMPTING -> CANCELING
    7: 3,  # RECALLING -> CANCELING: cancel requested before it started executing
    8: 5,  # RECALLED -> CANCELED: canceled before it started executing (terminal)
    9: 0,  # LOST -> UNKNOWN: set by a client only; a ROS 2 server never sends it
}
"""actionlib_msgs/GoalStatus codes to action_msgs/msg/GoalStatus codes; any other code is 0."""

GOAL_ID_NAMESPACE = uuid.UUID("6f1d3c2e-5a4b-5c8d-9e0f-a1b2c3d4e5f6")
"""Namespace of the name-based UUIDs (RFC 4122 version 5) made from actionlib goal id strings."""


def goal_status(ros1_code: int) -> int:
    """The ROS 2 GoalStatus code of an actionlib one (unknown codes: UNKNOWN, 0)."""
    return GOAL_STATUS_TO_ROS2.get(ros1_code, 0)


def log_level(ros1_level: int) -> int:
    """The rcl_interfaces/msg/Log level of a rosgraph_msgs/Log one: 10 times its highest flag.

    DEBUG 1, INFO 2, WARN 4, ERROR 8, FATAL 16 become 10, 20, 30, 40, 50; 0 stays 0 (UNSET);
    a value of several flags takes its highest (6 is WARN); 32 and above become 60 to 80,
    levels the log bridge treats as it treats any level it does not know. The field is a
    ROS 1 ``byte`` (rosbags decodes it signed): its bits are read unsigned.
    """
    return 10 * (int(ros1_level) & 0xFF).bit_length()


@lru_cache(maxsize=4096)
def goal_uuid(goal_id: str) -> bytes:
    """The 16 bytes of a ROS 2 goal id made from an actionlib goal id string (name-based)."""
    return uuid.uuid5(GOAL_ID_NAMESPACE, goal_id).bytes


def status_topic(ros1_topic: str) -> str:
    """The ROS 2 status topic of an actionlib one: ``<a>/status`` becomes ``<a>/_action/status``.

    Any other name is returned as it is (the selection then does not take it as a status).
    """
    if ros1_topic.endswith(ROS1_STATUS_SUFFIX):
        return ros1_topic[: -len(ROS1_STATUS_SUFFIX)] + ACTION_STATUS_SUFFIX
    return ros1_topic


class _Stamp(Protocol):
    sec: int
    nanosec: int


class _Header(Protocol):
    stamp: _Stamp
    frame_id: str


class _KeyValue(Protocol):
    key: str
    value: str


class _DiagnosticStatus(Protocol):
    level: int
    name: str
    message: str
    hardware_id: str
    values: Sequence[_KeyValue]


class _DiagnosticArray(Protocol):
    header: _Header
    status: Sequence[_DiagnosticStatus]


class _GoalId(Protocol):
    stamp: _Stamp
    id: str


class _GoalStatus(Protocol):
    goal_id: _GoalId
    status: int


class _GoalStatusArray(Protocol):
    status_list: Sequence[_GoalStatus]


class _Log(Protocol):
    header: _Header
    level: int
    name: str
    msg: str
    file: str
    function: str
    line: int


class Translation(NamedTuple):
    """How a ROS 1 type is replayed: its ROS 2 type, topic name, message conversion."""

    ros2_type: str
    topic: Callable[[str], str]
    convert: Callable[[object], object]


@cache
def ros1_typestore() -> Typestore:
    """rosbags' ROS 1 Noetic types: what ROS 1 payloads are decoded with."""
    return get_typestore(Stores.ROS1_NOETIC)


@cache
def standard_md5(ros1_type: str) -> str:
    """The md5sum ROS 1 gives the standard definition of a type (Noetic)."""
    return ros1_typestore().generate_msgdef(ros1_type, ros_version=1)[1]


def _same(topic: str) -> str:
    return topic


class _Ros2:
    """The bundled ROS 2 classes the converted messages are built from."""

    def __init__(self) -> None:
        types = base_typestore().types
        self.time = types["builtin_interfaces/msg/Time"]
        self.header = types["std_msgs/msg/Header"]
        self.array = types["diagnostic_msgs/msg/DiagnosticArray"]
        self.status = types["diagnostic_msgs/msg/DiagnosticStatus"]
        self.pair = types["diagnostic_msgs/msg/KeyValue"]
        self.goal_array = types["action_msgs/msg/GoalStatusArray"]
        self.goal_status = types["action_msgs/msg/GoalStatus"]
        self.goal_info = types["action_msgs/msg/GoalInfo"]
        self.uuid = types["unique_identifier_msgs/msg/UUID"]
        self.log = types["rcl_interfaces/msg/Log"]


@cache
def _ros2() -> _Ros2:
    return _Ros2()


def _stamp(ros2: _Ros2, stamp: _Stamp) -> Msg:
    return ros2.time(sec=stamp.sec, nanosec=stamp.nanosec)


def diagnostic_array(msg: object) -> object:
    """diagnostic_msgs/DiagnosticArray → diagnostic_msgs/msg/DiagnosticArray (the header's
    ``seq`` is dropped; the statuses have the same fields)."""
    r = _ros2()
    array = cast("_DiagnosticArray", msg)
    header = array.header
    status, pair = r.status, r.pair
    return r.array(
        header=r.header(stamp=_stamp(r, header.stamp), frame_id=header.frame_id),
        status=[
            status(
                level=s.level,
                name=s.name,
                message=s.message,
                hardware_id=s.hardware_id,
                values=[pair(key=kv.key, value=kv.value) for kv in s.values],
            )
            for s in array.status
        ],
    )


def _uuid_array(goal_id: str) -> NDArray[np.uint8]:
    return np.frombuffer(goal_uuid(goal_id), dtype=np.uint8)


def goal_status_array(msg: object) -> object:
    """actionlib_msgs/GoalStatusArray → action_msgs/msg/GoalStatusArray: codes mapped
    (:data:`GOAL_STATUS_TO_ROS2`), each GoalID's string made a UUID, its stamp kept; the
    array's header and each goal's ``text`` have no ROS 2 field and are dropped."""
    r = _ros2()
    return r.goal_array(
        status_list=[
            r.goal_status(
                goal_info=r.goal_info(
                    goal_id=r.uuid(uuid=_uuid_array(goal.goal_id.id)),
                    stamp=_stamp(r, goal.goal_id.stamp),
                ),
                status=goal_status(goal.status),
            )
            for goal in cast("_GoalStatusArray", msg).status_list
        ]
    )


def log(msg: object) -> object:
    """rosgraph_msgs/Log → rcl_interfaces/msg/Log: see :func:`ros2_log`."""
    line = cast("_Log", msg)
    stamp = line.header.stamp
    fields = (line.level, line.name, line.msg, line.file, line.function, line.line)
    return ros2_log(stamp.sec, stamp.nanosec, *fields)


def ros2_log(
    sec: int,
    nanosec: int,
    ros1_level: int,
    name: str,
    msg: str,
    file: str,
    function: str,
    line: int,
) -> object:
    """The rcl_interfaces/msg/Log of a rosgraph_msgs/Log's fields: level mapped
    (:func:`log_level`), the header's stamp kept, ``name`` (the node's full name, ``/ns/node``)
    unchanged; the header's ``seq`` and ``frame_id`` and the ``topics`` have no ROS 2 field."""
    r = _ros2()
    return r.log(
        stamp=r.time(sec=sec, nanosec=nanosec),
        level=log_level(ros1_level),
        name=name,
        msg=msg,
        file=file,
        function=function,
        line=line,
    )


TRANSLATIONS: dict[str, Translation] = {
    ROS1_DIAGNOSTIC_ARRAY: Translation(
        "diagnostic_msgs/msg/DiagnosticArray", _same, diagnostic_array
    ),
    ROS1_GOAL_STATUS_ARRAY: Translation(
        "action_msgs/msg/GoalStatusArray", status_topic, goal_status_array
    ),
    ROS1_LOG: Translation("rcl_interfaces/msg/Log", _same, log),
}
"""The ROS 1 types the bridges read, by normalised ROS 1 type name."""
