"""GenericError answers against primitives.cpp and handler_context.cpp at 505bc2d5."""

from __future__ import annotations

import pytest

from medkit_replay.gateway.errors import (
    GatewayError,
    body_bytes,
    check_entity_id,
    entity_not_found,
    error_body,
    error_status,
    method_not_allowed,
    wrong_entity_type,
)

# -- errors: primitives.cpp write_generic_error, handler_context.cpp -------------------------------


def test_error_body_is_the_generic_error() -> None:
    assert error_body(entity_not_found("ghost")) == {
        "error_code": "entity-not-found",
        "message": "Entity not found",
        "parameters": {"entity_id": "ghost"},
    }
    assert error_body(GatewayError(404, "resource-not-found", "Unknown category: x", {})) == {
        "error_code": "resource-not-found",
        "message": "Unknown category: x",
    }


def test_vendor_codes_go_under_vendor_error() -> None:
    body = error_body(GatewayError(400, "x-medkit-collection-not-supported", "no"))
    assert body == {
        "error_code": "vendor-error",
        "vendor_code": "x-medkit-collection-not-supported",
        "message": "no",
    }
    assert error_status(GatewayError(200, "internal-error", "x")) == 400


def test_writes_answer_405() -> None:
    err = method_not_allowed("DELETE", "/api/v1/faults")
    assert (err.status, error_body(err)["error_code"]) == (405, "invalid-request")


def test_wrong_entity_type_names_both_types() -> None:
    err = wrong_entity_type("motor", "components", "apps")
    assert (err.status, err.message) == (
        400,
        "Invalid entity type for route: expected Component, got App",
    )


@pytest.mark.parametrize(
    ("entity_id", "details"),
    [
        ("", "Entity ID cannot be empty"),
        ("a" * 257, "Entity ID too long (max 256 characters)"),
        (
            "a/b",
            "Entity ID contains invalid character: '/'. "
            "Only alphanumeric, underscore and hyphen are allowed",
        ),
        (
            "a\nb",
            "Entity ID contains invalid character: '0x0a'. "
            "Only alphanumeric, underscore and hyphen are allowed",
        ),
    ],
)
def test_malformed_entity_ids_answer_400(entity_id: str, details: str) -> None:
    with pytest.raises(GatewayError) as caught:
        check_entity_id(entity_id)
    assert caught.value.parameters == {"details": details, "entity_id": entity_id}
    check_entity_id("front-left_door2")


def test_bodies_are_written_indented_with_sorted_keys() -> None:
    assert body_bytes({"b": [], "a": "é"}) == b'{\n  "a": "\xc3\xa9",\n  "b": []\n}'
