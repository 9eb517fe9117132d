"""The rosbag bulk-data bodies and download checks against bulkdata_handlers.cpp at 505bc2d5."""

from __future__ import annotations

import pytest

from medkit_replay.gateway.bulk_json import (
    RosbagDownload,
    bulk_categories_body,
    bulk_source_filters,
    rosbag_descriptors_body,
    rosbag_download,
)
from medkit_replay.gateway.errors import GatewayError
from tests.gateway.values import fault, recording

# -- bulk data: bulkdata_handlers.cpp -------------------------------------------------------------


def test_categories_are_only_rosbags() -> None:
    assert bulk_categories_body() == {"items": ["rosbags"]}


def test_source_filters_fall_back_to_the_fqn_except_for_functions() -> None:
    assert bulk_source_filters("apps", frozenset({"/b", "/a"}), "/x") == ["/a", "/b"]
    assert bulk_source_filters("components", frozenset(), "/robot") == ["/robot"]
    assert bulk_source_filters("functions", frozenset(), "/robot") == []


def test_descriptors_fold_rows_by_recording_newest_first() -> None:
    faults = {
        "A": fault("A"),
        "B": fault("B"),
        "C": fault("C", sources=("/robot/lidar",)),
        "D": fault("D", sources=("/robot/motor/sub",)),  # below the app: not an exact source
    }
    old = recording("fault_A_1", ("A",), 11)
    burst = recording("fault_B_2", ("B", "A", "C"), 51)
    child = recording("fault_D_3", ("D",), 71)
    body = rosbag_descriptors_body(
        [old, burst, child], faults, ["/robot/motor"], rosbag_format="sqlite3"
    )
    assert body == {
        "items": [
            {
                "id": "fault_B_2",
                "name": "fault_B_2 recording 2023-11-14T22:14:11.000Z",
                "mimetype": "application/x-sqlite3",
                "size": 4096,
                "creation_date": "2023-11-14T22:14:11.000Z",
                "x-medkit": {
                    "fault_codes": ["A", "B"],  # C is reported by another source
                    "duration_sec": 6.0,
                    "format": "sqlite3",
                    "recording_id": "fault_B_2",
                },
            },
            {
                "id": "fault_A_1",
                "name": "fault_A_1 recording 2023-11-14T22:13:31.000Z",
                "mimetype": "application/x-sqlite3",
                "size": 4096,
                "creation_date": "2023-11-14T22:13:31.000Z",
                "x-medkit": {
                    "fault_codes": ["A"],
                    "duration_sec": 6.0,
                    "format": "sqlite3",
                    "recording_id": "fault_A_1",
                },
            },
        ]
    }


DOWNLOAD_FAULTS = {"A": fault("A"), "C": fault("C", sources=("/robot/lidar",))}
BAGS = [
    recording("fault_A_1", ("A",), 11),
    recording("fault_A_2", ("A",), 21),
    recording("fault_C_3", ("C",), 31),
    recording("fault_A_4", ("A",), 41, path=None),
]


def download(bulk_id: str) -> RosbagDownload:
    return rosbag_download(
        BAGS,
        DOWNLOAD_FAULTS,
        bulk_id,
        entity_id="motor",
        scope=frozenset({"/robot/motor"}),
        rosbag_format="mcap",
        max_code_length=128,
    )


def test_download_by_recording_id() -> None:
    got = download("fault_A_1")
    assert (got.recording.recording_id, got.mimetype, got.filename) == (
        "fault_A_1",
        "application/x-mcap",
        "fault_A_1.mcap",
    )


def test_download_by_fault_code_serves_its_newest_recording() -> None:
    # GetRosbag's fallback: a fault code means the fault's newest recording
    got = rosbag_download(
        BAGS[:3],
        DOWNLOAD_FAULTS,
        "A",
        entity_id="motor",
        scope=frozenset({"/robot/motor"}),
        rosbag_format="mcap",
        max_code_length=128,
    )
    assert got.recording.recording_id == "fault_A_2"


@pytest.mark.parametrize(
    ("bulk_id", "message", "params"),
    [
        ("fault_C_3", "Bulk-data not found for this entity", {"entity_id": "motor"}),
        ("C", "Bulk-data not found for this entity", {"entity_id": "motor"}),
        ("fault_A_4", "Bulk-data not found", {"bulk_data_id": "fault_A_4"}),
        ("nothing", "Bulk-data not found", {"bulk_data_id": "nothing"}),
        ("A", "Bulk-data not found", {"bulk_data_id": "A"}),  # its newest was never written
        ("..", "Bulk-data not found", {"bulk_data_id": ".."}),
        ("..%2Fsecret", "Bulk-data not found", {"bulk_data_id": "..%2Fsecret"}),
    ],
)
def test_download_refusals_are_404(bulk_id: str, message: str, params: dict[str, str]) -> None:
    with pytest.raises(GatewayError) as caught:
        download(bulk_id)
    err = caught.value
    assert (err.status, err.error_code, err.message, err.parameters) == (
        404,
        "resource-not-found",
        message,
        params,
    )
