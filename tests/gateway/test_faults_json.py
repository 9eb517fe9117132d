"""The fault routes' bodies against what ros2_medkit's gateway at 505bc2d5 answers.

Handler references are to fault_handlers.cpp at that commit, and to the fault manager and
transport code it calls.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import pytest

from medkit_replay.captures import EvidenceRecording, SnapshotCapture, SnapshotTopic
from medkit_replay.gateway.detail_json import fault_detail_body, recordings_held_at, status_object
from medkit_replay.gateway.errors import GatewayError
from medkit_replay.gateway.faults_json import (
    StatusFilter,
    entity_fault_list_body,
    fault_json,
    fault_list_body,
    in_scope,
    iso8601,
    parse_status_filter,
    query_bool,
    scoped_fault,
)
from medkit_replay.history import CorrelationState
from medkit_replay.model import Cluster, FaultSnapshot, MutedFault
from tests.gateway.values import T0, fault, recording


def codes(body: dict[str, Any]) -> list[str]:
    """The fault codes a list body holds, in order."""
    return [item["fault_code"] for item in body["items"]]


def snaps(body: dict[str, Any]) -> list[Any]:
    """A detail body's snapshots."""
    return list(body["environment_data"]["snapshots"])


NO_CORRELATION = CorrelationState()
MUTED = CorrelationState(
    muted=(MutedFault(fault_code="SYMPTOM", root_cause_code="ROOT", rule_id="r1", delay_ms=40),),
    clusters=(
        Cluster(
            cluster_id="r2_1",
            rule_id="r2",
            rule_name="bursts",
            label="bursts",
            representative_code="ROOT",
            representative_severity="ERROR",
            fault_codes=("ROOT", "OTHER"),
            count=2,
            first_at_ns=T0 + 1_500_000_000,
            last_at_ns=T0 + 2 * 10**9,
        ),
    ),
)


# -- status filter: http_utils.hpp parse_fault_status_param, read_fault_status_filter -------


@pytest.mark.parametrize(
    ("value", "statuses"),
    [
        (None, ("PREFAILED", "CONFIRMED")),
        ("pending", ("PREFAILED",)),
        ("confirmed", ("CONFIRMED",)),
        ("cleared", ("CLEARED", "HEALED", "PREPASSED")),
        ("healed", ("HEALED", "PREPASSED")),
        ("all", ("PREFAILED", "CONFIRMED", "CLEARED", "HEALED", "PREPASSED")),
    ],
)
def test_status_filter_table_as_the_transport_requests_statuses(
    value: str | None, statuses: tuple[str, ...]
) -> None:
    assert parse_status_filter(value).statuses == statuses


@pytest.mark.parametrize("value", ["bogus", "", "Confirmed", "active"])
def test_an_unknown_status_answers_400_with_the_allowed_values(value: str) -> None:
    with pytest.raises(GatewayError) as caught:
        parse_status_filter(value, {"app_id": "motor"})
    err = caught.value
    assert (err.status, err.error_code, err.message) == (
        400,
        "invalid-parameter",
        "Invalid status parameter value",
    )
    assert err.parameters == {
        "allowed_values": "pending, confirmed, cleared, healed, all",
        "parameter": "status",
        "value": value,
        "app_id": "motor",
    }


@pytest.mark.parametrize(
    ("raw", "expected"),
    [(None, False), ("true", True), ("TRUE", True), ("1", True), ("0", False), ("", False)],
)
def test_query_bool_as_parse_query_bool(raw: str | None, expected: bool) -> None:
    assert query_bool(raw) is expected


# -- fault JSON: fault_msg_conversions.cpp fault_to_json -------------------------------------------


def test_fault_json_fields_and_times_as_fault_to_json() -> None:
    item = fault_json(fault("MOTOR_OVERHEAT"))
    assert item == {
        "fault_code": "MOTOR_OVERHEAT",
        "severity": 2,
        "description": "too hot",
        "first_occurred": 1_700_000_000 + 250_000_000 / 1e9,
        "last_occurred": 1_700_000_005 + 123_456_789 / 1e9,
        "occurrence_count": 3,
        "status": "CONFIRMED",
        "reporting_sources": ["/robot/motor"],
        "severity_label": "ERROR",
    }


def test_last_passed_appears_once_the_fault_passed() -> None:
    item = fault_json(fault("A", "HEALED", last_passed_ns=T0 + 7 * 10**9))
    assert item["last_passed"] == 1_700_000_007.0
    assert list(item).index("last_passed") == list(item).index("last_occurred") + 1


# -- GET /faults: list_all_faults + ListFaults muting (correlation.md §1.4) ------------------------


def test_global_list_default_holds_pending_and_confirmed_in_code_order() -> None:
    faults = [fault("B", "CONFIRMED"), fault("A", "PREFAILED"), fault("C", "HEALED")]
    body = fault_list_body(faults, NO_CORRELATION, StatusFilter())
    assert codes(body) == ["A", "B"]
    assert body["x-medkit"] == {"count": 2, "muted_count": 0, "cluster_count": 0}


def test_global_list_cleared_filter_takes_healed_and_prepassed() -> None:
    faults = [fault("A", "CLEARED"), fault("B", "HEALED"), fault("C", "PREPASSED")]
    body = fault_list_body([*faults, fault("D")], NO_CORRELATION, parse_status_filter("cleared"))
    assert codes(body) == ["A", "B", "C"]


def test_muted_symptoms_are_left_out_unless_asked_for() -> None:
    faults = [fault("ROOT"), fault("SYMPTOM"), fault("OTHER")]
    body = fault_list_body(faults, MUTED, StatusFilter())
    assert codes(body) == ["OTHER", "ROOT"]
    assert body["x-medkit"] == {"count": 2, "muted_count": 1, "cluster_count": 1}


def test_include_muted_and_clusters_add_the_details() -> None:
    faults = [fault("ROOT"), fault("SYMPTOM")]
    body = fault_list_body(faults, MUTED, StatusFilter(), include_muted=True, include_clusters=True)
    assert codes(body) == ["ROOT", "SYMPTOM"]
    assert body["x-medkit"] == {
        "count": 2,
        "muted_count": 1,
        "cluster_count": 1,
        "muted_faults": [
            {"fault_code": "SYMPTOM", "root_cause_code": "ROOT", "rule_id": "r1", "delay_ms": 40}
        ],
        "clusters": [
            {
                "cluster_id": "r2_1",
                "rule_id": "r2",
                "rule_name": "bursts",
                "label": "bursts",
                "representative_code": "ROOT",
                "representative_severity": "ERROR",
                "fault_codes": ["ROOT", "OTHER"],
                "count": 2,
                "first_at": 1_700_000_001.5,
                "last_at": 1_700_000_002.0,
            }
        ],
    }


def test_empty_details_stay_out_even_when_asked_for() -> None:
    body = fault_list_body(
        [fault("A")], NO_CORRELATION, StatusFilter(), include_muted=True, include_clusters=True
    )
    assert body["x-medkit"] == {"count": 1, "muted_count": 0, "cluster_count": 0}


# -- per-entity scope: fault_scope.cpp fault_in_source_scope ---------------------------------------


@pytest.mark.parametrize(
    ("sources", "scope", "expected"),
    [
        (("/robot/motor",), {"/robot/motor"}, True),  # exact
        (("/robot/motor/driver",), {"/robot/motor"}, True),  # a path below
        (("/robot/motorbike",), {"/robot/motor"}, False),  # a prefix, not a path below
        (("/robot",), {"/robot/motor"}, False),  # above
        (("/robot/motor", "/robot/lidar"), {"/robot/motor"}, False),  # mixed sources
        (("/robot/motor", "/robot/lidar"), {"/robot/motor", "/robot/lidar"}, True),
        ((), {"/robot/motor"}, False),  # no sources
        (("/robot/motor",), set(), False),  # an entity owning nothing
        (("motor",), {"/robot/motor"}, False),  # the bare node name is not the FQN
    ],
)
def test_scope_matches_every_source_exactly_or_below(
    sources: tuple[str, ...], scope: set[str], expected: bool
) -> None:
    assert in_scope(sources, frozenset(scope)) is expected


def test_app_list_scopes_and_writes_the_app_block() -> None:
    faults = [
        fault("MINE"),
        fault("CHILD", sources=("/robot/motor/sub",)),
        fault("SHARED", sources=("/robot/motor", "/robot/lidar")),
        fault("THEIRS", sources=("/robot/lidar",)),
        fault("SYMPTOM"),
    ]
    body = entity_fault_list_body(
        faults,
        MUTED,
        StatusFilter(),
        kind="apps",
        entity_id="motor",
        sources=frozenset({"/robot/motor"}),
        source_id="/robot/motor",
    )
    assert codes(body) == ["CHILD", "MINE"]
    assert body["x-medkit"] == {
        "entity_id": "motor",
        "source_id": "/robot/motor",
        "count": 2,
        "muted_count": 1,
        "cluster_count": 1,
    }


@pytest.mark.parametrize(
    ("kind", "counts"),
    [
        ("components", {"aggregation_level": "component", "app_count": 2}),
        ("functions", {"aggregation_level": "function", "host_count": 2}),
        ("areas", {"aggregation_level": "area", "component_count": 1, "app_count": 2}),
    ],
)
def test_aggregated_lists_write_their_kind_block(kind: str, counts: dict[str, object]) -> None:
    faults = [fault("A"), fault("B", sources=("/robot/lidar",)), fault("C", sources=("/x",))]
    body = entity_fault_list_body(
        faults,
        NO_CORRELATION,
        StatusFilter(),
        kind=kind,
        entity_id="base",
        sources=frozenset({"/robot/motor", "/robot/lidar"}),
        component_count=1,
    )
    assert codes(body) == ["A", "B"]
    assert body["x-medkit"] == {
        "entity_id": "base",
        "aggregated": True,
        **counts,
        "aggregation_sources": ["/robot/lidar", "/robot/motor"],
        "count": 2,
    }


def test_an_entity_owning_no_source_lists_nothing_and_names_no_sources() -> None:
    body = entity_fault_list_body(
        [fault("A")],
        NO_CORRELATION,
        StatusFilter(),
        kind="functions",
        entity_id="f",
        sources=frozenset(),
    )
    assert body == {
        "items": [],
        "x-medkit": {
            "entity_id": "f",
            "aggregated": True,
            "aggregation_level": "function",
            "host_count": 0,
            "count": 0,
        },
    }


# -- GET /{kind}/{id}/faults/{code}: get_fault, build_sovd_fault_response --------------------------


@pytest.mark.parametrize(
    ("status", "expected"),
    [
        ("CONFIRMED", ("active", "1", "1", "0")),
        ("PREFAILED", ("passive", "1", "0", "1")),
        ("PREPASSED", ("passive", "0", "0", "1")),
        ("HEALED", ("cleared", "0", "0", "0")),
        ("CLEARED", ("cleared", "0", "0", "0")),
    ],
)
def test_status_object_as_build_status_object(status: str, expected: tuple[str, ...]) -> None:
    obj = status_object(status)
    got = (obj["aggregatedStatus"], obj["testFailed"], obj["confirmedDTC"], obj["pendingDTC"])
    assert got == expected


def capture(
    cid: int, t_s: int, *topics: SnapshotTopic, retained: bool = True, frame: bool = False
) -> SnapshotCapture:
    return SnapshotCapture(
        fault_code="MOTOR_OVERHEAT",
        capture_id=cid,
        t_ns=T0 + t_s * 10**9,
        retained=retained,
        freeze_frame=frame,
        topics=topics,
    )


TEMP = SnapshotTopic(
    topic="/motor/temperature",
    message_type="sensor_msgs/msg/Temperature",
    message_t_ns=T0 + 1_123_000_000,
    data={"temperature": 105.5, "variance": 0.1},
)
ODOM_TYPE = "example_msgs/msg/Custom"
CUSTOM = SnapshotTopic(
    topic="/robot/state", message_type=ODOM_TYPE, message_t_ns=T0 + 1_200_000_000, data={"a": 1}
)


def detail(
    captures: list[SnapshotCapture],
    recordings: list[EvidenceRecording],
    *,
    retain_on_clear: bool = False,
    bag_sizes: dict[str, int] | None = None,
) -> dict[str, Any]:
    return fault_detail_body(
        fault("MOTOR_OVERHEAT"),
        captures,
        recordings,
        kind="apps",
        entity_id="motor",
        rosbag_format="mcap",
        retain_on_clear=retain_on_clear,
        bag_sizes=bag_sizes,
    )


def test_detail_item_records_and_extension() -> None:
    body = detail([], [])
    assert body["item"] == {
        "code": "MOTOR_OVERHEAT",
        "fault_name": "too hot",
        "severity": 2,
        "status": {
            "aggregatedStatus": "active",
            "testFailed": "1",
            "confirmedDTC": "1",
            "pendingDTC": "0",
        },
    }
    assert body["environment_data"] == {
        "extended_data_records": {
            "first_occurrence": "2023-11-14T22:13:20.250Z",
            "last_occurrence": "2023-11-14T22:13:25.123Z",
        },
        "snapshots": [],
    }
    # build_sovd_fault_response's x-medkit: no last_passed there (only the list items have it)
    assert body["x-medkit"] == {
        "occurrence_count": 3,
        "reporting_sources": ["/robot/motor"],
        "severity_label": "ERROR",
        "status_raw": "CONFIRMED",
    }


def test_detail_leaves_out_an_empty_fault_name() -> None:
    body = fault_detail_body(
        fault("A", description=""),
        [],
        [],
        kind="apps",
        entity_id="m",
        rosbag_format="mcap",
    )
    assert body["item"] == {
        "code": "A",
        "severity": 2,
        "status": status_object("CONFIRMED"),
    }


def test_freeze_frames_per_topic_newest_capture_first_with_the_primary_value() -> None:
    older = capture(1, 1, TEMP)
    newer = capture(2, 9, CUSTOM)
    snapshots = snaps(detail([older, newer], []))
    assert snapshots == [
        {
            "type": "freeze_frame",
            "name": "state",
            "data": {"a": 1},  # not a known type: the whole message
            "x-medkit": {
                "topic": "/robot/state",
                "message_type": ODOM_TYPE,
                "full_data": {"a": 1},
                "captured_at": "2023-11-14T22:13:21.200Z",
            },
        },
        {
            "type": "freeze_frame",
            "name": "temperature",
            "data": 105.5,  # sensor_msgs/msg/Temperature's primary field
            "x-medkit": {
                "topic": "/motor/temperature",
                "message_type": "sensor_msgs/msg/Temperature",
                "full_data": {"temperature": 105.5, "variance": 0.1},
                "captured_at": "2023-11-14T22:13:21.123Z",
            },
        },
    ]


def test_the_retained_frame_shows_when_no_capture_rows_are_held() -> None:
    # GetFault: the compact frame only when no per-topic rows remain (or retain_on_clear)
    cleared = capture(1, 1, TEMP, CUSTOM, retained=False, frame=True)
    snapshots = snaps(detail([cleared], []))
    assert snapshots == [
        {
            "type": "freeze_frame",
            "name": "freeze_frame",
            "data": {"/motor/temperature": TEMP.data, "/robot/state": {"a": 1}},
            "x-medkit": {
                "topic": "",
                "message_type": "",
                "full_data": {"/motor/temperature": TEMP.data, "/robot/state": {"a": 1}},
                "captured_at": "2023-11-14T22:13:21.200Z",
            },
        }
    ]
    held = capture(1, 1, TEMP, retained=True, frame=True)
    assert len(snaps(detail([held], []))) == 1
    both = snaps(detail([held], [], retain_on_clear=True))
    assert [s["name"] for s in both] == ["temperature", "freeze_frame"]


def test_rosbag_snapshots_newest_first_with_a_download_uri() -> None:
    first = recording("fault_MOTOR_OVERHEAT_1700000010000", ("MOTOR_OVERHEAT",), 11)
    second = recording("fault_MOTOR_OVERHEAT_1700000100000", ("MOTOR_OVERHEAT",), 101)
    snapshots = snaps(detail([], [first, second], bag_sizes={second.recording_id: 9000}))
    assert snapshots == [
        {
            "type": "rosbag",
            "name": "rosbag_fault_MOTOR_OVERHEAT_1700000100000",
            "bulk_data_uri": "/apps/motor/bulk-data/rosbags/fault_MOTOR_OVERHEAT_1700000100000",
            "size_bytes": 9000,
            "duration_sec": 6.0,
            "format": "mcap",
            "x-medkit": {"captured_at": "2023-11-14T22:15:01.000Z"},
        },
        {
            "type": "rosbag",
            "name": "rosbag_fault_MOTOR_OVERHEAT_1700000010000",
            "bulk_data_uri": "/apps/motor/bulk-data/rosbags/fault_MOTOR_OVERHEAT_1700000010000",
            "size_bytes": 4096,
            "duration_sec": 6.0,
            "format": "mcap",
            "x-medkit": {"captured_at": "2023-11-14T22:13:31.000Z"},
        },
    ]


def test_detail_shows_only_this_faults_captures_and_recordings() -> None:
    other_capture = SnapshotCapture(
        fault_code="OTHER", capture_id=5, t_ns=T0, retained=True, freeze_frame=True, topics=(TEMP,)
    )
    mine = recording("fault_MOTOR_OVERHEAT_1", ("OTHER", "MOTOR_OVERHEAT"), 11)
    theirs = recording("fault_OTHER_2", ("OTHER",), 21)
    shown = snaps(detail([other_capture], [mine, theirs]))
    assert [s["name"] for s in shown] == ["rosbag_fault_MOTOR_OVERHEAT_1"]


def test_recordings_are_held_from_their_post_roll_end_until_deleted() -> None:
    kept = recording("a", ("A",), 10)
    gone = replace(recording("b", ("A",), 20), deleted_ns=T0 + 30 * 10**9)
    ids = [
        [r.recording_id for r in recordings_held_at([kept, gone], T0 + at * 10**9)]
        for at in (9, 10, 25, 30)
    ]
    assert ids == [[], ["a"], ["a", "b"], ["a"]]


def scoped(code: str, found: FaultSnapshot | None) -> FaultSnapshot:
    return scoped_fault(
        code,
        found,
        kind="components",
        entity_id="base",
        sources=frozenset({"/robot/motor"}),
        max_code_length=128,
    )


def test_scoped_fault_answers_the_fault_in_scope() -> None:
    assert scoped("A", fault("A")).fault_code == "A"


@pytest.mark.parametrize(
    ("code", "found", "status", "error_code", "message", "params"),
    [
        (
            "X" * 257,
            None,
            400,
            "invalid-parameter",
            "Invalid fault code",
            {"details": "Fault code must be between 1 and 256 characters"},
        ),
        (
            "a..b",
            None,
            503,
            "service-unavailable",
            "Failed to get fault",
            {
                "details": "fault_code cannot contain '..'",
                "component_id": "base",
                "fault_code": "a..b",
            },
        ),
        (
            "NOPE",
            None,
            404,
            "resource-not-found",
            "Fault not found",
            {"details": "Fault not found: NOPE", "component_id": "base", "fault_code": "NOPE"},
        ),
    ],
)
def test_scoped_fault_errors_in_the_handler_order(
    code: str,
    found: FaultSnapshot | None,
    status: int,
    error_code: str,
    message: str,
    params: dict[str, object],
) -> None:
    with pytest.raises(GatewayError) as caught:
        scoped(code, found)
    err = caught.value
    assert (err.status, err.error_code, err.message, err.parameters) == (
        status,
        error_code,
        message,
        params,
    )


def test_a_fault_of_another_entity_is_not_found_here() -> None:
    with pytest.raises(GatewayError) as caught:
        scoped("A", fault("A", sources=("/robot/motor", "/robot/lidar")))
    assert caught.value.status == 404
    assert caught.value.parameters is not None
    assert str(caught.value.parameters["details"]).startswith("Fault is not in scope")


@pytest.mark.parametrize(
    ("t_ns", "text"),
    [
        (0, "1970-01-01T00:00:00.000Z"),
        (T0 + 999_999_999, "2023-11-14T22:13:20.999Z"),
        (T0 + 1_000_000, "2023-11-14T22:13:20.001Z"),
    ],
)
def test_iso8601_truncates_to_the_millisecond(t_ns: int, text: str) -> None:
    assert iso8601(t_ns) == text
