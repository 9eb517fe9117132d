"""Topic selection by type and name (SEMANTICS.md §2) and type-name normalisation.

Pure: no files.
"""

from __future__ import annotations

import pytest

from medkit_replay.inputs.selection import (
    ACTION_STATUS_TYPE,
    CLEAR_FAULT_EVENT_TYPE,
    DIAGNOSTICS_TYPE,
    FAULT_EVENT_TYPE,
    LOG_TYPE,
    REPORT_FAULT_EVENT_TYPE,
    Selection,
)
from medkit_replay.msgdefs import normalize_typename

DEFAULT = Selection()


@pytest.mark.parametrize(
    ("topic", "msgtype", "role"),
    [
        ("/navigate_to_pose/_action/status", ACTION_STATUS_TYPE, "action_status"),
        ("/robot1/dock/_action/status", ACTION_STATUS_TYPE, "action_status"),
        ("/diagnostics", DIAGNOSTICS_TYPE, "diagnostics"),
        ("/fault_manager/report_fault/_service_event", REPORT_FAULT_EVENT_TYPE, "report_fault"),
        ("/r1/fault_manager/clear_fault/_service_event", CLEAR_FAULT_EVENT_TYPE, "clear_fault"),
        ("/fault_manager/events", FAULT_EVENT_TYPE, "fault_events"),
        ("/robot1/fault_manager/events", FAULT_EVENT_TYPE, "fault_events"),
    ],
)
def test_roles_by_type_and_name(topic: str, msgtype: str, role: str) -> None:
    assert DEFAULT.classify(topic, msgtype) == (role, None)


@pytest.mark.parametrize(
    ("topic", "msgtype"),
    [
        ("/diagnostics_agg", DIAGNOSTICS_TYPE),  # not configured
        ("/rosout", LOG_TYPE),  # off by default
        ("/_action/status", ACTION_STATUS_TYPE),  # no action name
        ("/chatter", "std_msgs/msg/String"),
    ],
)
def test_other_topics_are_skipped_silently(topic: str, msgtype: str) -> None:
    assert DEFAULT.classify(topic, msgtype) == (None, None)


def test_a_known_name_with_another_type_is_skipped_with_a_reason() -> None:
    role, reason = DEFAULT.classify("/diagnostics", "std_msgs/msg/String")
    assert role is None
    assert reason == (
        "topic /diagnostics has type 'std_msgs/msg/String', not diagnostic_msgs/msg/"
        "DiagnosticArray; not read"
    )
    assert DEFAULT.classify("/x/_action/status", "")[1] is not None


def test_configurable_diagnostics_rosout_and_extra_topics() -> None:
    selection = Selection(rosout=True, diagnostics_topics=("/diag",), extra_topics=("/chatter",))
    assert selection.classify("/diag", DIAGNOSTICS_TYPE) == ("diagnostics", None)
    assert selection.classify("/diagnostics", DIAGNOSTICS_TYPE) == (None, None)
    assert selection.classify("/rosout", LOG_TYPE) == ("rosout", None)
    assert selection.classify("/chatter", "std_msgs/msg/String") == ("extra", None)


@pytest.mark.parametrize(
    ("name", "normal"),
    [
        ("test_msgs/BasicTypes", "test_msgs/msg/BasicTypes"),
        ("diagnostic_msgs/DiagnosticArray", DIAGNOSTICS_TYPE),
        ("ros2_medkit_msgs/srv/msg/ReportFault_Event", REPORT_FAULT_EVENT_TYPE),
        ("ros2_medkit_msgs/srv/msg/Fault", "ros2_medkit_msgs/msg/Fault"),
        (" std_msgs/msg/String ", "std_msgs/msg/String"),
        (REPORT_FAULT_EVENT_TYPE, REPORT_FAULT_EVENT_TYPE),
    ],
)
def test_normalize_typename(name: str, normal: str) -> None:
    assert normalize_typename(name) == normal
