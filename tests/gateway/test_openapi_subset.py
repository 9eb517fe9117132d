"""The excerpt of the published OpenAPI document and its readers in tests/gateway/schemas.py.

Each schema accepts a body shaped as the 505bc2d5 gateway answers and refuses a broken one.
"""

from __future__ import annotations

import re
from typing import Any

import pytest
import yaml
from jsonschema import Draft202012Validator

from tests.gateway import schemas

SOURCE_COMMIT = "2406bf5d4675e2d5468403a7e8306c6b3f8d72e8"

# name -> (a body the schema accepts, a body it must refuse)
SAMPLES: dict[str, tuple[object, object]] = {
    "BulkDataCategoryList": ({"items": ["rosbags"]}, {"items": [{"id": "rosbags"}]}),
    "BulkDataDescriptor": (
        {
            "id": "clip-1",
            "name": "MOTOR_OVERHEAT.mcap",
            "mimetype": "application/x-mcap",
            "size": 2048,
            "creation_date": "2026-11-26T10:00:00.5Z",
            "x-medkit": {"fault_code": "MOTOR_OVERHEAT"},
        },
        {"id": "clip-1", "name": "clip", "creation_date": "yesterday"},
    ),
    "BulkDataDescriptorList": (
        {"items": [{"id": "clip-1", "name": "clip"}]},
        {"items": [{"id": "clip-1"}]},
    ),
    "EntityDetail": (
        {"id": "engine", "name": "engine", "type": "Component", "uri": "/api/v1/components/engine"},
        {"id": "engine"},
    ),
    "EntityList": ({"items": [{"id": "powertrain", "name": "powertrain"}]}, {"entities": []}),
    "FaultDetail": (
        {
            "item": {
                "code": "MOTOR_OVERHEAT",
                "fault_name": "Motor overheat",
                "severity": 2,
                "status": {"aggregatedStatus": "active", "confirmedDTC": "1", "testFailed": "1"},
            },
            "environment_data": {
                "extended_data_records": {
                    "first_occurrence": "2026-11-26T10:00:00.000Z",
                    "last_occurrence": "2026-11-26T10:00:05.250Z",
                },
                "snapshots": [
                    {"type": "freeze_frame", "name": "temp", "data": {"value": 91.5}},
                    {
                        "type": "rosbag",
                        "name": "MOTOR_OVERHEAT",
                        "bulk_data_uri": "/apps/motor/bulk-data/rosbags/MOTOR_OVERHEAT",
                        "size_bytes": 2048,
                        "duration_sec": 4.0,
                        "format": "mcap",
                    },
                ],
            },
            "x-medkit": {"occurrence_count": 3, "reporting_sources": ["/motor"]},
        },
        {
            "item": {"code": "MOTOR_OVERHEAT", "severity": 2, "status": {"aggregatedStatus": "on"}},
            "environment_data": {},
        },
    ),
    "FaultList": (
        {"items": [{"fault_code": "MOTOR_OVERHEAT", "severity": 2, "status": "CONFIRMED"}]},
        {"items": [{"fault_code": "MOTOR_OVERHEAT", "severity": "ERROR", "status": "CONFIRMED"}]},
    ),
    "FaultListItem": (
        {
            "fault_code": "MOTOR_OVERHEAT",
            "severity": 2,
            "severity_label": "ERROR",
            "status": "CONFIRMED",
            "description": "Motor temperature above limit",
            "first_occurred": 1764151200.123456789,
            "last_occurred": 1764151205.0,
            "occurrence_count": 3,
            "reporting_sources": ["/powertrain/motor"],
            "last_passed": None,  # a field the handlers add: the schema leaves room for it
        },
        {
            "fault_code": "MOTOR_OVERHEAT",
            "severity": 2,
            "status": "CONFIRMED",
            "severity_label": "FATAL",
        },
    ),
    "GenericError": (
        {
            "error_code": "resource-not-found",
            "message": "Fault not found",
            "parameters": {"code": "X"},
        },
        {"message": "Fault not found"},
    ),
    "HealthStatus": (
        {"status": "healthy", "timestamp": 1764151200, "discovery": {"mode": "runtime_only"}},
        {"status": "healthy", "timestamp": "now"},
    ),
    "RootOverview": (
        {
            "name": "ROS 2 Medkit Gateway",
            "version": "0.4.0",
            "api_base": "/api/v1",
            "endpoints": ["GET /api/v1/faults"],
            "capabilities": {"faults": True, "operations": False},
        },
        {
            "name": "ROS 2 Medkit Gateway",
            "version": "0.4.0",
            "api_base": "/api/v1",
            "endpoints": [],
        },
    ),
    "VersionInfo": (
        {
            "items": [
                {
                    "version": "1.0.0",
                    "base_uri": "/api/v1",
                    "vendor_info": {"name": "ros2_medkit", "version": "0.4.0"},
                }
            ]
        },
        {"items": [{"version": "1.0.0", "base_uri": "/api/v1", "vendor_info": {"name": "x"}}]},
    ),
}


def _refs(node: object) -> list[str]:
    if isinstance(node, dict):
        found = [node["$ref"]] if isinstance(node.get("$ref"), str) else []
        return found + [ref for value in node.values() for ref in _refs(value)]
    if isinstance(node, list):
        return [ref for value in node for ref in _refs(value)]
    return []


def _resolve(document: dict[str, Any], ref: str) -> object:
    assert ref.startswith("#/"), f"{ref} points outside the file"
    node: object = document
    for token in ref[2:].split("/"):
        token = token.replace("~1", "/").replace("~0", "~")
        assert isinstance(node, dict) and token in node, f"{ref} does not resolve"
        node = node[token]
    return node


def test_the_subset_names_its_source_and_parses() -> None:
    header = schemas.SUBSET.read_text(encoding="utf-8").split("\ncomponents:", 1)[0]
    assert "selfpatch/ros2_medkit_clients" in header
    assert "spec/openapi.yaml" in header
    assert SOURCE_COMMIT in header
    assert "2026-11-26" in header
    document = schemas.load_document()
    assert document["openapi"] == "3.1.0"
    assert document["info"]["version"] == "0.4.0"
    assert list(document) == ["components", "info", "openapi", "paths", "servers", "tags"]


def test_the_subset_keeps_the_documents_layout() -> None:
    # The published document is a sorted-key YAML dump; the excerpt is written the same way, so a
    # hand edit that reorders keys or changes a value's form shows up here.
    text = schemas.SUBSET.read_text(encoding="utf-8")
    body = "".join(line for line in text.splitlines(keepends=True) if not line.startswith("#"))
    dumped = yaml.safe_dump(yaml.safe_load(body), sort_keys=True, default_flow_style=False)
    assert body == dumped


def test_load_document_hands_out_copies() -> None:
    first = schemas.load_document()
    first["paths"].clear()
    assert schemas.load_document()["paths"]


def test_every_ref_resolves_inside_the_file() -> None:
    document = schemas.load_document()
    refs = _refs(document)
    assert refs
    for ref in refs:
        _resolve(document, ref)


def test_the_schemas_are_exactly_those_the_routes_reach() -> None:
    document = schemas.load_document()
    reached: set[str] = set()
    pending = _refs(document["paths"])
    while pending:
        ref = pending.pop()
        if ref in reached:
            continue
        reached.add(ref)
        pending.extend(_refs(_resolve(document, ref)))
    held = {f"#/components/schemas/{name}" for name in schemas.schema_names()}
    assert held == {ref for ref in reached if ref.startswith("#/components/schemas/")}


@pytest.mark.parametrize("name", schemas.schema_names())
def test_each_schema_is_valid_json_schema_2020_12(name: str) -> None:
    Draft202012Validator.check_schema(schemas.load_document()["components"]["schemas"][name])


def test_every_schema_has_samples() -> None:
    assert set(SAMPLES) == set(schemas.schema_names())


@pytest.mark.parametrize("name", sorted(SAMPLES))
def test_each_schema_accepts_a_valid_body(name: str) -> None:
    schemas.validate(SAMPLES[name][0], name)


@pytest.mark.parametrize("name", sorted(SAMPLES))
def test_each_schema_refuses_a_broken_body(name: str) -> None:
    with pytest.raises(AssertionError, match=f"does not match {name}"):
        schemas.validate(SAMPLES[name][1], name)


def test_generic_error_without_error_code_is_refused_with_its_path() -> None:
    with pytest.raises(AssertionError, match=re.escape("$: 'error_code' is a required property")):
        schemas.validate({"message": "no such fault"}, "GenericError")


def test_a_failure_names_the_place_inside_the_body() -> None:
    body = {
        "items": [{"fault_code": "A", "severity": 1, "status": "CONFIRMED"}, {"fault_code": "B"}]
    }
    with pytest.raises(AssertionError) as caught:
        schemas.validate(body, "FaultList")
    message = str(caught.value)
    assert "$.items[1]: 'severity' is a required property" in message
    assert "$.items[1]: 'status' is a required property" in message
    assert "items[0]" not in message


@pytest.mark.parametrize(
    "stamp",
    ["2026-11-26 10:00:00Z", "2026-11-26T10:00:00", "2026-13-26T10:00:00Z", "1764151200"],
)
def test_date_times_are_checked(stamp: str) -> None:
    record = {"item": {"code": "A", "severity": 1, "status": {"aggregatedStatus": "active"}}}
    body = {**record, "environment_data": {"extended_data_records": {"first_occurrence": stamp}}}
    with pytest.raises(AssertionError, match=r"first_occurrence: .* is not a 'date-time'"):
        schemas.validate(body, "FaultDetail")


def test_an_unknown_schema_name_is_a_key_error() -> None:
    with pytest.raises(KeyError, match="FaultSummary"):
        schemas.validate({}, "FaultSummary")


def test_response_schema_reads_the_paths() -> None:
    assert schemas.response_schema("/faults", "GET", "200") == "FaultList"
    assert schemas.response_schema("/apps/{app_id}/faults", "get", "200") == "FaultList"
    detail = "/components/{component_id}/faults/{fault_code}"
    assert schemas.response_schema(detail, "GET", "200") == "FaultDetail"
    assert schemas.response_schema(detail, "GET", "404") == "GenericError"
    assert schemas.response_schema("/", "GET", "200") == "RootOverview"
    assert schemas.response_schema("/version-info", "GET", "200") == "VersionInfo"
    assert schemas.response_schema("/health", "GET", "200") == "HealthStatus"
    assert schemas.response_schema("/areas/{area_id}/subareas", "GET", "200") == "EntityList"
    assert schemas.response_schema("/apps/{app_id}/is-located-on", "GET", "200") == "EntityDetail"
    bulk = "/apps/{app_id}/bulk-data/{category_id}"
    assert (
        schemas.response_schema("/apps/{app_id}/bulk-data", "GET", "200") == "BulkDataCategoryList"
    )
    assert schemas.response_schema(bulk, "GET", "200") == "BulkDataDescriptorList"
    assert schemas.response_schema(bulk, "POST", "201") == "BulkDataDescriptor"
    # no named schema: the binary download (inline), the SSE stream and a 204
    assert schemas.response_schema(bulk + "/{file_id}", "GET", "200") is None
    assert schemas.response_schema("/faults/stream", "GET", "200") is None
    assert schemas.response_schema("/faults", "DELETE", "204") is None


@pytest.mark.parametrize(
    ("path", "method", "status"),
    [
        ("/apps/{app_id}/data", "GET", "200"),  # not a route a recording answers
        ("/faults/stream", "POST", "200"),
        ("/faults", "GET", "405"),  # the document lists no 405
    ],
)
def test_response_schema_refuses_what_the_subset_does_not_hold(
    path: str, method: str, status: str
) -> None:
    with pytest.raises(KeyError):
        schemas.response_schema(path, method, status)


def test_routes_lists_every_operation_once() -> None:
    listed = schemas.routes()
    assert len(listed) == len(set(listed)) == 61
    assert ("GET", "/faults") in listed
    assert ("DELETE", "/faults") in listed
    assert ("GET", "/faults/stream") in listed
    assert ("DELETE", "/functions/{function_id}/faults/{fault_code}") in listed
    assert ("POST", "/components/{component_id}/bulk-data/{category_id}") in listed
    for kind, key in [
        ("areas", "area_id"),
        ("components", "component_id"),
        ("apps", "app_id"),
        ("functions", "function_id"),
    ]:
        base = f"/{kind}/{{{key}}}"
        for path in [
            base,
            f"{base}/faults",
            f"{base}/faults/{{fault_code}}",
            f"{base}/bulk-data",
            f"{base}/bulk-data/{{category_id}}",
            f"{base}/bulk-data/{{category_id}}/{{file_id}}",
        ]:
            assert ("GET", path) in listed, path
    for method, path in listed:
        for status in schemas.load_document()["paths"][path][method.lower()]["responses"]:
            schemas.response_schema(path, method, status)  # every listed response is readable


@pytest.mark.parametrize(
    ("path", "template"),
    [
        ("/", "/"),
        ("/faults", "/faults"),
        ("/faults/stream", "/faults/stream"),
        ("/apps/motor/faults/MOTOR_OVERHEAT", "/apps/{app_id}/faults/{fault_code}"),
        ("/areas/powertrain/subareas", "/areas/{area_id}/subareas"),
        (
            "/components/engine/bulk-data/rosbags/clip-1",
            "/components/{component_id}/bulk-data/{category_id}/{file_id}",
        ),
        ("/apps/motor/data", None),
        ("/apps//faults", None),
        ("/nothing", None),
    ],
)
def test_route_template_matches_request_paths(path: str, template: str | None) -> None:
    assert schemas.route_template(path) == template
