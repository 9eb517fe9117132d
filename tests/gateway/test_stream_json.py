"""The fault stream's frames against sse_fault_handler.cpp at 505bc2d5."""

from __future__ import annotations

import json

import pytest

from medkit_replay.gateway.stream_json import (
    KEEPALIVE,
    event_app_id,
    parse_last_event_id,
    sse_event,
)
from medkit_replay.model import FaultEvent
from tests.gateway.values import T0, fault

# -- GET /faults/stream: sse_fault_handler.cpp format_sse_event ------------------------------------


def test_sse_frame_text() -> None:
    event = FaultEvent(
        t_ns=T0 + 500_000_000,
        event_type="fault_cleared",
        fault=fault("ROOT", "CLEARED"),
        auto_cleared_codes=("SYMPTOM",),
    )
    frame = sse_event(event, 7, app_id="motor")
    lines = frame.split("\n")
    assert lines[:2] == ["id: 7", "event: fault_cleared"]
    assert lines[3:] == ["", ""]
    data = lines[2].removeprefix("data: ")
    assert data == (
        '{"auto_cleared_codes":["SYMPTOM"],"event_type":"fault_cleared","fault":'
        '{"description":"too hot","fault_code":"ROOT","first_occurred":1700000000.25,'
        '"last_occurred":1700000005.1234567,"occurrence_count":3,'
        '"reporting_sources":["/robot/motor"],"severity":2,"severity_label":"ERROR",'
        '"status":"CLEARED"},"timestamp":1700000000.5,'
        '"x-medkit":{"entity_id":"motor","entity_type":"apps"}}'
    )
    assert json.loads(data)["fault"]["last_occurred"] == 1_700_000_005 + 123_456_789 / 1e9


def test_sse_frame_without_cascade_or_app_has_neither_key() -> None:
    event = FaultEvent(t_ns=T0, event_type="fault_confirmed", fault=fault("A"))
    data = json.loads(sse_event(event, 1).split("\n")[2].removeprefix("data: "))
    assert sorted(data) == ["event_type", "fault", "timestamp"]
    assert KEEPALIVE == ":keepalive\n\n"


@pytest.mark.parametrize(
    ("sources", "apps", "expected"),
    [
        (("/robot/motor",), {"motor"}, "motor"),
        (("/robot/arm/motor",), {"robot_arm_motor"}, "robot_arm_motor"),
        (("/robot/motor",), {"lidar"}, None),
        ((), {"motor"}, None),
    ],
)
def test_event_app_id_as_resolve_entity_context(
    sources: tuple[str, ...], apps: set[str], expected: str | None
) -> None:
    assert event_app_id(fault("A", sources=sources), apps) == expected


def test_event_app_id_prefers_the_node_links() -> None:
    assert event_app_id(fault("A"), {"motor"}, {"robot/motor": "drive"}) == "drive"


@pytest.mark.parametrize(
    ("raw", "expected"),
    [
        (None, 0),
        ("", 0),
        ("5", 5),
        ("12", 10),  # above the newest id: clamped
        ("-1", 0),
        ("3a", 0),
        ("18446744073709551616", 0),  # 2**64: out of stoull's range
        ("9" * 5000, 0),
    ],
)
def test_last_event_id_parse_and_clamp(raw: str | None, expected: int) -> None:
    assert parse_last_event_id(raw, newest_id=10) == expected
