"""Typed reads of one node's ROS parameters (flat dotted names), as strict as rclcpp.

A value of another type stops the live node at start-up, so it raises ConfigError naming it.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, TypeVar

from medkit_replay.engine.local_filter import LocalFilterConfig
from medkit_replay.errors import ConfigError, ConfigWarning
from medkit_replay.model import NS_PER_SEC

if TYPE_CHECKING:
    from collections.abc import Mapping

INT64_MIN = -(1 << 63)
INT64_MAX = (1 << 63) - 1
INT32_MAX = (1 << 31) - 1

_FILTER = "fault_reporter.local_filtering."
_SHOWN = 80

_T = TypeVar("_T")


def _kind(value: object) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int):
        return "integer"
    if isinstance(value, float):
        return "double"
    if isinstance(value, str):
        return "string"
    if isinstance(value, list | tuple):
        return "array"
    return type(value).__name__


def _shown(value: object) -> str:
    """A value for a message: its repr, cut short when long (a 5,000-digit number, say)."""
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 128:
        return f"of about {int(value.bit_length() * 0.30103) + 1:,} digits"
    text = repr(value)
    return text if len(text) <= _SHOWN else f"{text[: _SHOWN - 3]}..."


def to_int32(value: int) -> int:
    """``static_cast<int>`` of an int64 on a two's-complement target."""
    wrapped = value & 0xFFFFFFFF
    return wrapped - (1 << 32) if wrapped > INT32_MAX else wrapped


class ParameterReader:
    """Reads one node's parameters with upstream's defaults and collects its warnings."""

    def __init__(self, node: str, params: Mapping[str, object]) -> None:
        self.node = node
        self.params = params
        self.warnings: list[str] = []

    def warn(self, text: str, *, parameter: str | None = None, shown_at: bool = False) -> None:
        """Record a warning the live node would log at start-up; ``parameter``: the parameter
        it is about, located by :func:`medkit_replay.config.nodes.located_warnings` (its file
        and line also shown in the text with ``shown_at``)."""
        self.warnings.append(
            ConfigWarning(f"{self.node}: {text}", shown_at=shown_at, parameter=parameter)
        )

    def replaced(self, parameter: str, text: str, value: _T) -> _T:
        """``value``, used in place of ``parameter``'s own that the live node would not use; the
        warning it logs (``text``) recorded as :meth:`warn` does."""
        self.warn(text, parameter=parameter)
        return value

    def _wrong(self, name: str, expected: str, value: object, hint: str = "") -> ConfigError:
        problem = (
            f"{self.node} parameter '{name}' must be {expected}, "
            f"got {_kind(value)} {_shown(value)}{hint}"
        )
        return ConfigError(problem, parameter=name)

    def boolean(self, name: str, default: bool) -> bool:
        """A bool parameter."""
        value = self.params.get(name, default)
        if not isinstance(value, bool):
            raise self._wrong(name, "a bool", value)
        return value

    def integer(self, name: str, default: int) -> int:
        """An int64 parameter."""
        value = self.params.get(name, default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self._wrong(name, "an integer", value)
        if not INT64_MIN <= value <= INT64_MAX:
            raise self._wrong(name, "an integer", value, " (outside int64)")
        return value

    def double(self, name: str, default: float) -> float:
        """A double parameter; an integer is refused, as rclcpp's static typing does."""
        value = self.params.get(name, default)
        if isinstance(value, int) and not isinstance(value, bool):
            raise self._wrong(name, "a double", value, f" (write {value}.0)")
        if not isinstance(value, float):
            raise self._wrong(name, "a double", value)
        return value

    def string(self, name: str, default: str) -> str:
        """A string parameter."""
        value = self.params.get(name, default)
        if not isinstance(value, str):
            raise self._wrong(name, "a string", value)
        return value

    def strings(self, name: str) -> tuple[str, ...]:
        """A string-array parameter (default empty)."""
        value = self.params.get(name, [])
        if not isinstance(value, list | tuple) or not all(isinstance(v, str) for v in value):
            raise self._wrong(name, "a list of strings", value)
        return tuple(str(v) for v in value)

    def local_filter(self, *, enabled_default: bool = True) -> LocalFilterConfig:
        """``fault_reporter.local_filtering.*`` read and narrowed as the FaultReporter does."""
        defaults = LocalFilterConfig()
        window = self.double(_FILTER + "default_window_sec", defaults.default_window_sec)
        if not math.isfinite(window * NS_PER_SEC):
            # NaN, inf and seconds whose nanoseconds overflow a double slip past upstream's
            # ``<= 0`` check into an undefined duration cast.
            raise self._wrong(_FILTER + "default_window_sec", "a finite double of seconds", window)
        return LocalFilterConfig(
            enabled=self.boolean(_FILTER + "enabled", enabled_default),
            default_threshold=to_int32(
                self.integer(_FILTER + "default_threshold", defaults.default_threshold)
            ),
            default_window_sec=window,
            bypass_severity=self.integer(_FILTER + "bypass_severity", defaults.bypass_severity)
            & 0xFF,
        )
