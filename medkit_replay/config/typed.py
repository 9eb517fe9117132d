"""Typed reads of ROS 2 parameters, refusing a wrong type as a node declaring it would.

Every failure is a ConfigError pointing at the parameter's file and line.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from medkit_replay.config.params import NodeParams, Param, ParamValue

_TYPE_NAMES = {bool: "bool", int: "integer", float: "double", str: "string", list: "array"}


def _type_name(value: ParamValue) -> str:
    if value is None:
        return "null"
    return _TYPE_NAMES.get(type(value), type(value).__name__)


def _wrong(param: Param, name: str, expected: str) -> Exception:
    hint = ""
    if expected == "double" and isinstance(param.value, int) and not isinstance(param.value, bool):
        hint = f" (write {param.value}.0: ROS 2 refuses an integer for a double parameter)"
    article = "an" if expected[0] in "aeiou" else "a"
    got = f"{_type_name(param.value)} {param.value!r}"
    return param.error(name, f"expected {article} {expected}, got {got}{hint}")


def get_bool(params: NodeParams, name: str, default: bool) -> bool:
    """A bool parameter."""
    param = params.get(name)
    if param is None:
        return default
    if not isinstance(param.value, bool):
        raise _wrong(param, name, "bool")
    return param.value


def get_int(params: NodeParams, name: str, default: int) -> int:
    """An integer parameter (a bool or a double is refused)."""
    param = params.get(name)
    if param is None:
        return default
    if isinstance(param.value, bool) or not isinstance(param.value, int):
        raise _wrong(param, name, "integer")
    return param.value


def get_double(params: NodeParams, name: str, default: float) -> float:
    """A double parameter (an integer is refused, as rclcpp does)."""
    param = params.get(name)
    if param is None:
        return default
    if not isinstance(param.value, float):
        raise _wrong(param, name, "double")
    return param.value


def get_str(params: NodeParams, name: str, default: str) -> str:
    """A string parameter."""
    param = params.get(name)
    if param is None:
        return default
    if not isinstance(param.value, str):
        raise _wrong(param, name, "string")
    return param.value


def get_str_list(params: NodeParams, name: str, default: list[str]) -> list[str]:
    """A string-array parameter; an empty YAML list is accepted."""
    param = params.get(name)
    if param is None:
        return list(default)
    value = param.value
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise _wrong(param, name, "string array")
    return [str(v) for v in value]
