"""The gateway's error answers: upstream's error codes, the published GenericError body, and
the errors the read-only routes raise (unknown entity, fault, bulk data; writes refused).

Follows ros2_medkit_gateway at 505bc2d5: core/http/error_codes.hpp (the codes),
dto/errors.hpp and http/detail/primitives.cpp (the GenericError body),
handler_context.cpp and core/entity_validation.cpp (entity checks).
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING

from medkit_replay.gateway.entities import SINGULAR, validate_entity_id

if TYPE_CHECKING:
    from collections.abc import Mapping

ERR_INVALID_REQUEST = "invalid-request"
ERR_ENTITY_NOT_FOUND = "entity-not-found"
ERR_RESOURCE_NOT_FOUND = "resource-not-found"
ERR_INVALID_PARAMETER = "invalid-parameter"
ERR_SERVICE_UNAVAILABLE = "service-unavailable"
ERR_INTERNAL_ERROR = "internal-error"
ERR_VENDOR_ERROR = "vendor-error"

_VENDOR_PREFIX = "x-medkit-"

ID_FIELDS: Mapping[str, str] = {kind: f"{one}_id" for kind, one in SINGULAR.items()}
"""The parameter naming an entity in the fault routes' errors, by route collection."""

TYPE_NAMES: Mapping[str, str] = {kind: one.capitalize() for kind, one in SINGULAR.items()}
"""How upstream names an entity type in error messages, by route collection."""


class GatewayError(Exception):
    """An error answer: HTTP status, upstream's error code, message and parameters."""

    def __init__(
        self,
        status: int,
        error_code: str,
        message: str,
        parameters: Mapping[str, object] | None = None,
    ) -> None:
        super().__init__(message)
        self.status = status
        self.error_code = error_code
        self.message = message
        self.parameters: dict[str, object] | None = (
            dict(parameters) if parameters is not None else None
        )


def error_body(err: GatewayError) -> dict[str, object]:
    """The GenericError body: an ``x-medkit-*`` code goes under ``vendor_code`` with
    ``error_code`` ``vendor-error``; ``parameters`` only when there are some."""
    body: dict[str, object] = {}
    if err.error_code.startswith(_VENDOR_PREFIX):
        body["error_code"] = ERR_VENDOR_ERROR
        body["vendor_code"] = err.error_code
    else:
        body["error_code"] = err.error_code
    body["message"] = err.message
    if err.parameters:
        body["parameters"] = err.parameters
    return body


def error_status(err: GatewayError) -> int:
    """The HTTP status sent: upstream clamps an error's status to 400-599."""
    return min(max(err.status, 400), 599)


def body_bytes(body: object) -> bytes:
    """A JSON body as the gateway writes it: two-space indent, keys in byte order (nlohmann's
    objects are sorted maps), non-ASCII text as UTF-8."""
    text = json.dumps(body, indent=2, sort_keys=True, ensure_ascii=False, allow_nan=False)
    return text.encode("utf-8", "replace")


def invalid_parameter(message: str, parameters: Mapping[str, object] | None = None) -> GatewayError:
    """400 ``invalid-parameter``."""
    return GatewayError(400, ERR_INVALID_PARAMETER, message, parameters)


def method_not_allowed(method: str, path: str) -> GatewayError:
    """405 for a write: a served recording has no fault manager to change. The code is the one
    upstream's own 405 routes (bulk-data upload/delete on areas and functions) answer with."""
    return GatewayError(
        405,
        ERR_INVALID_REQUEST,
        f"{method} is not supported: medkit-replay serves a recorded run, read-only",
        {"method": method, "path": path},
    )


def check_entity_id(entity_id: str) -> None:
    """Raise the 400 upstream answers for a malformed entity id (validate_entity_for_route)."""
    reason = validate_entity_id(entity_id)
    if reason is not None:
        raise invalid_parameter("Invalid entity ID", {"details": reason, "entity_id": entity_id})


def entity_not_found(entity_id: str) -> GatewayError:
    """404 ``entity-not-found``: no entity of any kind has this id."""
    return GatewayError(404, ERR_ENTITY_NOT_FOUND, "Entity not found", {"entity_id": entity_id})


def wrong_entity_type(entity_id: str, expected_kind: str, actual_kind: str) -> GatewayError:
    """400: the id names an entity of another kind than the route's (kinds as route
    collections, ``apps`` etc.)."""
    expected, actual = TYPE_NAMES[expected_kind], TYPE_NAMES[actual_kind]
    return invalid_parameter(
        f"Invalid entity type for route: expected {expected}, got {actual}",
        {"entity_id": entity_id, "expected_type": expected, "actual_type": actual},
    )


def unknown_category(category: str) -> GatewayError:
    """404 for a bulk-data category other than ``rosbags`` (a replay has no upload store)."""
    return GatewayError(404, ERR_RESOURCE_NOT_FOUND, f"Unknown category: {category}")


def bulk_data_not_found(bulk_data_id: str) -> GatewayError:
    """404: no recording (nor fault with one) answers to this bulk-data id."""
    return GatewayError(
        404, ERR_RESOURCE_NOT_FOUND, "Bulk-data not found", {"bulk_data_id": bulk_data_id}
    )


def bulk_data_not_in_scope(entity_id: str) -> GatewayError:
    """404: the recording exists but none of its faults belongs to this entity."""
    return GatewayError(
        404,
        ERR_RESOURCE_NOT_FOUND,
        "Bulk-data not found for this entity",
        {"entity_id": entity_id},
    )
