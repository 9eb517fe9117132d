"""Per-node configuration: each recognised node's parameters turned into its typed config.

Adds the file and line of the value at fault to any ConfigError raised, or warning given, while
reading them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, TypeVar

from medkit_replay.errors import ConfigError, ConfigWarning

if TYPE_CHECKING:
    from collections.abc import Callable

    from medkit_replay.config.params import NodeParams

T = TypeVar("T")


def values(params: NodeParams) -> dict[str, object]:
    """The bare values of a node's parameters."""
    return {name: param.value for name, param in params.items()}


def located(params: NodeParams, build: Callable[[], T]) -> T:
    """Run ``build``; a ConfigError naming a parameter gets that parameter's file and line."""
    try:
        return build()
    except ConfigError as err:
        param = params.get(err.parameter or "")
        if param is None or err.path is not None:
            raise
        raise ConfigError(
            err.problem, path=str(param.path), line=param.line, parameter=err.parameter
        ) from None


def located_warnings(params: NodeParams, warnings: list[str]) -> list[str]:
    """The warnings, those about a parameter with the file and line where it was written (their
    text as it is)."""
    return [_place(params, warning) for warning in warnings]


def _place(params: NodeParams, warning: str) -> str:
    if not isinstance(warning, ConfigWarning) or warning.path is not None:
        return warning
    param = params.get(warning.parameter or "")
    if param is None:
        return warning
    return ConfigWarning(
        warning.message,
        path=str(param.path),
        line=param.line,
        shown_at=warning.shown_at,
        parameter=warning.parameter,
    )
