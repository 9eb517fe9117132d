"""The part of a recorded message a bridge request came from, kept for ``explain``.

Reads decoded messages the way the bridges do (their own mapping), and changes no bridge state.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.bridges.action_status import uuid_to_hex
from medkit_replay.model import LOG_LEVELS
from medkit_replay.trace import MAX_ITEMS, RecordedMessage

if TYPE_CHECKING:
    from collections.abc import Sequence

    from medkit_replay.bridges.diagnostic import DiagnosticBridge

DIAGNOSTIC_LEVELS = {0: "OK", 1: "WARN", 2: "ERROR", 3: "STALE"}
GOAL_STATUSES = {
    0: "UNKNOWN",
    1: "ACCEPTED",
    2: "EXECUTING",
    3: "CANCELING",
    4: "SUCCEEDED",
    5: "CANCELED",
    6: "ABORTED",
}
SERVICE_EVENT_TYPES = {
    0: "REQUEST_SENT",
    1: "REQUEST_RECEIVED",
    2: "RESPONSE_SENT",
    3: "RESPONSE_RECEIVED",
}


def _named(number: int, names: dict[int, str]) -> tuple[int, str] | int:
    name = names.get(number)
    return (number, name) if name is not None else number


def _kept(pairs: Sequence[tuple[str, str]]) -> tuple[tuple[tuple[str, str], ...], int]:
    return tuple(pairs[:MAX_ITEMS]), max(len(pairs) - MAX_ITEMS, 0)


def diagnostic_status(
    bridge: DiagnosticBridge,
    msg: object,
    where: tuple[int, str],
    fault_code: str,
    source_id: str,
    nth: int,
) -> RecordedMessage | None:
    """The ``nth`` (from 0) DiagnosticStatus of an array the bridge maps to this code and source.

    ``where`` is (input index, topic). None when no status of the array does (it cannot
    happen for a request the bridge made from this array).
    """
    found = 0
    for status in getattr(msg, "status", ()):
        if (
            bridge.map_to_fault_code(status) != fault_code
            or bridge.source_id_for(status) != source_id
        ):
            continue
        if found == nth:
            items, left_out = _kept([(str(p.key), str(p.value)) for p in status.values])
            return RecordedMessage(
                input_index=where[0],
                topic=where[1],
                type="diagnostic_msgs/msg/DiagnosticStatus",
                fields=(
                    ("level", _named(int(status.level), DIAGNOSTIC_LEVELS)),
                    ("name", str(status.name)),
                    ("message", str(status.message)),
                    ("hardware_id", str(status.hardware_id)),
                ),
                items=items,
                items_left_out=left_out,
            )
        found += 1
    return None


def goal_statuses(msg: object, where: tuple[int, str]) -> RecordedMessage:
    """The goals of an action_msgs/msg/GoalStatusArray: (goal id, status) each."""
    goals: list[tuple[str, str]] = []
    for goal in getattr(msg, "status_list", ()):
        info = getattr(goal, "goal_info", None)
        goal_id = getattr(getattr(info, "goal_id", None), "uuid", ())
        status = int(goal.status)
        goals.append((uuid_to_hex(goal_id), GOAL_STATUSES.get(status, str(status))))
    items, left_out = _kept(goals)
    return RecordedMessage(
        input_index=where[0],
        topic=where[1],
        type="action_msgs/msg/GoalStatusArray",
        fields=(("goals", len(goals)),),
        items=items,
        items_left_out=left_out,
    )


def log_line(msg: object, where: tuple[int, str]) -> RecordedMessage:
    """An rcl_interfaces/msg/Log line: level, logger, text and where it was logged."""
    return RecordedMessage(
        input_index=where[0],
        topic=where[1],
        type="rcl_interfaces/msg/Log",
        fields=(
            ("level", _named(int(getattr(msg, "level", 0)), LOG_LEVELS)),
            ("name", str(getattr(msg, "name", ""))),
            ("msg", str(getattr(msg, "msg", ""))),
            ("file", str(getattr(msg, "file", ""))),
            ("function", str(getattr(msg, "function", ""))),
            ("line", int(getattr(msg, "line", 0))),
        ),
    )


def service_call(msg: object, msgtype: str, where: tuple[int, str]) -> RecordedMessage:
    """A recorded ReportFault/ClearFault service event: which client, which call."""
    info = getattr(msg, "info", None)
    gid = bytes(int(b) & 0xFF for b in getattr(info, "client_gid", ())).hex()
    return RecordedMessage(
        input_index=where[0],
        topic=where[1],
        type=msgtype,
        fields=(
            ("event_type", _named(int(getattr(info, "event_type", 0)), SERVICE_EVENT_TYPES)),
            ("client_gid", gid),
            ("sequence_number", int(getattr(info, "sequence_number", 0))),
        ),
    )
