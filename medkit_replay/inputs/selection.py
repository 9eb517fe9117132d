"""Which recorded topics the replay reads, recognised by type and name (SEMANTICS.md §2).

Pure: decides from a topic's name and type alone; no I/O and no decoding.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

Role = Literal[
    "action_status",
    "diagnostics",
    "report_fault",
    "clear_fault",
    "fault_events",
    "rosout",
    "extra",
    "script",
]

ACTION_STATUS_TYPE = "action_msgs/msg/GoalStatusArray"
DIAGNOSTICS_TYPE = "diagnostic_msgs/msg/DiagnosticArray"
REPORT_FAULT_EVENT_TYPE = "ros2_medkit_msgs/srv/ReportFault_Event"
CLEAR_FAULT_EVENT_TYPE = "ros2_medkit_msgs/srv/ClearFault_Event"
FAULT_EVENT_TYPE = "ros2_medkit_msgs/msg/FaultEvent"
LOG_TYPE = "rcl_interfaces/msg/Log"
ACTION_STATUS_SUFFIX = "/_action/status"

# Topic suffixes of the roles read on every namespace: (suffix, role, expected type).
_SUFFIX_ROLES: tuple[tuple[str, Role, str], ...] = (
    (ACTION_STATUS_SUFFIX, "action_status", ACTION_STATUS_TYPE),
    ("/report_fault/_service_event", "report_fault", REPORT_FAULT_EVENT_TYPE),
    ("/clear_fault/_service_event", "clear_fault", CLEAR_FAULT_EVENT_TYPE),
    ("/fault_manager/events", "fault_events", FAULT_EVENT_TYPE),
)


@dataclass(frozen=True, slots=True, kw_only=True)
class Selection:
    """What to read from a recording.

    Attributes:
        rosout: read the log topic (rcl_interfaces/msg/Log) for the log bridge.
        rosout_topic: the log bridge's ``rosout_topic`` (default ``/rosout``).
        diagnostics_topics: topics read as diagnostics (default ``/diagnostics`` only).
        extra_topics: further topics delivered with role ``extra``, whatever their type.
        only_roles: when set, read only topics of these roles (e.g. a quick pre-pass).
    """

    rosout: bool = False
    rosout_topic: str = "/rosout"
    diagnostics_topics: tuple[str, ...] = ("/diagnostics",)
    extra_topics: tuple[str, ...] = ()
    only_roles: frozenset[Role] | None = None

    def classify(self, topic: str, msgtype: str) -> tuple[Role | None, str | None]:
        """The role of a topic, or why a topic named like a role's input is not read.

        Args:
            topic: the recorded topic name.
            msgtype: its type, normalised (:func:`medkit_replay.msgdefs.normalize_typename`).

        Returns:
            ``(role, None)`` for a topic to read; ``(None, reason)`` for a topic whose name
            says it is an input but whose type is not the expected one; ``(None, None)`` for
            every other topic.
        """
        role, reason = self._classify(topic, msgtype)
        if role is not None and self.only_roles is not None and role not in self.only_roles:
            return None, None
        return role, reason

    def _classify(self, topic: str, msgtype: str) -> tuple[Role | None, str | None]:
        if topic in self.extra_topics:
            return "extra", None
        if topic in self.diagnostics_topics:
            return _check(topic, msgtype, "diagnostics", DIAGNOSTICS_TYPE)
        if self.rosout and topic == self.rosout_topic:
            return _check(topic, msgtype, "rosout", LOG_TYPE)
        for suffix, role, expected in _SUFFIX_ROLES:
            # An action status topic needs an action name before the suffix.
            if topic.endswith(suffix) and (role != "action_status" or topic != suffix):
                return _check(topic, msgtype, role, expected)
        return None, None


def _check(topic: str, msgtype: str, role: Role, expected: str) -> tuple[Role | None, str | None]:
    if msgtype == expected:
        return role, None
    return None, f"topic {topic} has type {msgtype or 'unknown'!r}, not {expected}; not read"
