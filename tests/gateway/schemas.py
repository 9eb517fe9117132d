"""The gateway's published API document, as the serve tests check bodies against it.

Reads tests/gateway/openapi/openapi_subset.yaml (an excerpt of selfpatch/ros2_medkit_clients
spec/openapi.yaml at 2406bf5d; the 505bc2d5 gateway's routes answer with these shapes), validates
JSON bodies against its component schemas (JSON Schema 2020-12, the dialect of OpenAPI 3.1.0) and
says which schema a route answers with.
"""

from __future__ import annotations

import copy
import functools
import re
from datetime import datetime
from pathlib import Path
from typing import Any

import yaml
from jsonschema import Draft202012Validator, FormatChecker

SUBSET = Path(__file__).with_name("openapi") / "openapi_subset.yaml"
_SCHEMA_REF = "#/components/schemas/"
_RESPONSE_REF = "#/components/responses/"
_METHODS = ("get", "put", "post", "delete", "options", "head", "patch", "trace")
_MAX_REPORTED = 10  # validation failures listed in one AssertionError

# RFC 3339 date-time (what JSON Schema's "date-time" means); checked here rather than through
# jsonschema's optional rfc3339-validator so the result does not depend on what is installed.
_DATE_TIME = re.compile(
    r"\d{4}-\d{2}-\d{2}[Tt]\d{2}:\d{2}:\d{2}(\.\d+)?([Zz]|[+-]\d{2}:\d{2})\Z", re.ASCII
)
_FORMATS = FormatChecker(formats=())


def _is_date_time(value: object) -> bool:
    if not isinstance(value, str):
        return True  # formats constrain strings only
    if not _DATE_TIME.match(value):
        return False
    try:
        datetime.fromisoformat(value.upper().replace("Z", "+00:00"))
    except ValueError:  # e.g. month 13 or second 61
        return False
    return True


_FORMATS.checks("date-time")(_is_date_time)


@functools.cache
def _document() -> dict[str, Any]:
    loaded = yaml.safe_load(SUBSET.read_text(encoding="utf-8"))
    if not isinstance(loaded, dict):
        raise AssertionError(f"{SUBSET}: not a YAML mapping")
    return loaded


def load_document() -> dict[str, Any]:
    """The excerpt as a plain dict (a fresh copy each call: callers may change it)."""
    return copy.deepcopy(_document())


def schema_names() -> list[str]:
    """The names under components.schemas, in the document's order."""
    return list(_document()["components"]["schemas"])


@functools.cache
def _validator(schema_name: str) -> Any:
    components = _document()["components"]
    if schema_name not in components["schemas"]:
        raise KeyError(f"no schema {schema_name!r} in {SUBSET.name}; known: {schema_names()}")
    # The $refs are document-local ('#/components/...'): a root holding components resolves them.
    root = {"$ref": _SCHEMA_REF + schema_name, "components": components}
    return Draft202012Validator(root, format_checker=_FORMATS)


def validate(body: object, schema_name: str) -> None:
    """Raise AssertionError naming each place (as $.a.b[0]) where body breaks the schema."""
    errors = sorted(_validator(schema_name).iter_errors(body), key=lambda e: list(e.absolute_path))
    if not errors:
        return
    lines = [f"{e.json_path}: {e.message}" for e in errors[:_MAX_REPORTED]]
    if len(errors) > _MAX_REPORTED:
        lines.append(f"... and {len(errors) - _MAX_REPORTED} more")
    raise AssertionError(f"body does not match {schema_name}:\n  " + "\n  ".join(lines))


def routes() -> list[tuple[str, str]]:
    """Every (METHOD, path template) the excerpt holds, in the document's order."""
    return [
        (method.upper(), path)
        for path, item in _document()["paths"].items()
        for method in item
        if method in _METHODS
    ]


def response_schema(path: str, method: str, status: str) -> str | None:
    """The component schema a route answers with for status, or None when the document names none.

    None means the response has no JSON body or an inline schema (the binary download, the SSE
    stream, 204s). A route, method or status the excerpt does not hold raises KeyError: a test
    asking about one is itself wrong.
    """
    operation = _document()["paths"].get(path, {}).get(method.lower())
    if operation is None:
        raise KeyError(f"{method.upper()} {path} is not in {SUBSET.name}")
    response = operation["responses"].get(str(status))
    if response is None:
        raise KeyError(f"{method.upper()} {path} lists no {status} response")
    ref = response.get("$ref")
    if isinstance(ref, str) and ref.startswith(_RESPONSE_REF):
        response = _document()["components"]["responses"][ref.removeprefix(_RESPONSE_REF)]
    schema = response.get("content", {}).get("application/json", {}).get("schema", {})
    ref = schema.get("$ref")
    if isinstance(ref, str) and ref.startswith(_SCHEMA_REF):
        return ref.removeprefix(_SCHEMA_REF)
    return None


def route_template(path: str) -> str | None:
    """The path template a concrete request path (below /api/v1) falls under, or None.

    Where several templates fit, the one with the most literal segments wins, as a router would
    prefer '/faults/stream' to a '/faults/{x}'.
    """
    segments = path.strip("/").split("/") if path.strip("/") else []
    best: tuple[int, str] | None = None
    for template in _document()["paths"]:
        parts = template.strip("/").split("/") if template.strip("/") else []
        if len(parts) != len(segments):
            continue
        literal = 0
        for part, segment in zip(parts, segments, strict=True):
            if part.startswith("{") and part.endswith("}"):
                if not segment:
                    break
            elif part == segment:
                literal += 1
            else:
                break
        else:
            if best is None or literal > best[0]:
                best = (literal, template)
    return None if best is None else best[1]
