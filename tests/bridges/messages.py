"""Builders for the ROS messages the bridges read, made with rosbags' Humble type store.

The bridges see exactly the objects a bag decode would hand them (numpy goal ids included).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np
from rosbags.typesys import Stores, get_typestore

if TYPE_CHECKING:
    from collections.abc import Iterable

    from rosbags.typesys.store import Msg, MsgType

TS = get_typestore(Stores.ROS2_HUMBLE)

_Time = TS.types["builtin_interfaces/msg/Time"]
_Header = TS.types["std_msgs/msg/Header"]
_UUID = TS.types["unique_identifier_msgs/msg/UUID"]
_GoalInfo = TS.types["action_msgs/msg/GoalInfo"]
_GoalStatus = TS.types["action_msgs/msg/GoalStatus"]
_GoalStatusArray = TS.types["action_msgs/msg/GoalStatusArray"]
_KeyValue = TS.types["diagnostic_msgs/msg/KeyValue"]
_DiagnosticStatus = TS.types["diagnostic_msgs/msg/DiagnosticStatus"]
_DiagnosticArray = TS.types["diagnostic_msgs/msg/DiagnosticArray"]
_Log = TS.types["rcl_interfaces/msg/Log"]

# action_msgs/msg/GoalStatus
EXECUTING = 2
SUCCEEDED = 4
CANCELED = 5
ABORTED = 6
# diagnostic_msgs/msg/DiagnosticStatus
OK, WARN, ERROR, STALE = 0, 1, 2, 3

GOAL_STATUS_ARRAY = "action_msgs/msg/GoalStatusArray"
DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"
LOG = "rcl_interfaces/msg/Log"


def _stamp() -> MsgType:
    return _Time(sec=0, nanosec=0)


def goal(uuid: Iterable[int], status: int) -> Msg:
    """One GoalStatus with the given 16 goal-id bytes."""
    goal_id = _UUID(uuid=np.array(list(uuid), dtype=np.uint8))
    return _GoalStatus(goal_info=_GoalInfo(goal_id=goal_id, stamp=_stamp()), status=status)


def goal_array(*goals: Msg) -> MsgType:
    """A GoalStatusArray of the given goals, in order."""
    status_list: list[Msg] = list(goals)
    return _GoalStatusArray(status_list=status_list)


def arr(*goals: tuple[int, int]) -> MsgType:
    """``arr((g1, S1), (g2, S2))`` of bridges.md §8: goals whose uuid[0] is g, in order."""
    return goal_array(*(goal([g, *([0] * 15)], status) for g, status in goals))


def one(g: int, status: int) -> MsgType:
    """``one(g, S)`` of bridges.md §8: one goal with uuid[0] = g and status S."""
    return arr((g, status))


def status_topic(action: str) -> str:
    """The status topic of an action."""
    return action + "/_action/status"


def _kv(key: str, value: str) -> Msg:
    return _KeyValue(key=key, value=value)


def diag(
    name: str,
    level: int,
    message: str = "",
    *,
    hardware_id: str = "",
    values: Mapping[str, str] | Iterable[tuple[str, str]] = (),
) -> Msg:
    """One DiagnosticStatus; ``values`` keep their order."""
    pairs = values.items() if isinstance(values, Mapping) else values
    return _DiagnosticStatus(
        level=level,
        name=name,
        message=message,
        hardware_id=hardware_id,
        values=[_kv(key, value) for key, value in pairs],
    )


def diag_array(*statuses: Msg) -> MsgType:
    """A DiagnosticArray holding the statuses in order."""
    status: list[Msg] = list(statuses)
    return _DiagnosticArray(header=_Header(stamp=_stamp(), frame_id=""), status=status)


def log(name: str, level: int, msg: str) -> MsgType:
    """An rcl_interfaces/msg/Log line."""
    return _Log(
        stamp=_stamp(), level=level, name=name, msg=msg, file="f.cpp", function="fn", line=1
    )
