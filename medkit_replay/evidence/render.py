"""A decoded message as ros2_medkit_serialization renders it to JSON (the freeze frame's ``data``).

Upstream goes message -> YAML (dynmsg, values only) -> JSON, guessing each scalar's type from its
text: keys end up sorted, 8-bit integers and strings that read as numbers or yes/no become
numbers or booleans, whole floats become integers, NaN and infinities the strings ``.nan``,
``.inf``, ``-.inf`` (so the JSON stays strict), and an empty list ``null``.
"""

from __future__ import annotations

import math
import re
from typing import TYPE_CHECKING, cast

from rosbags.interfaces import Nodetype

if TYPE_CHECKING:
    from collections.abc import Iterable

    from rosbags.interfaces.typing import FieldDesc
    from rosbags.typesys.store import Typestore

_BOOLEAN_WORDS = {
    "true": True,
    "True": True,
    "yes": True,
    "Yes": True,
    "false": False,
    "False": False,
    "no": False,
    "No": False,
}
_INTEGER = re.compile(r"-?[0-9]+")
_DECIMAL = re.compile(r"-?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?")
_INT64 = (-(2**63), 2**63 - 1)


def scalar(text: str) -> object:
    """How upstream's YAML-to-JSON step types one scalar: bool, then int64, then double, else
    the text itself (in that order, with its checks on the first character)."""
    if text in _BOOLEAN_WORDS:
        return _BOOLEAN_WORDS[text]
    if _INTEGER.fullmatch(text):
        value = int(text)
        if _INT64[0] <= value <= _INT64[1]:
            return value
    if _DECIMAL.fullmatch(text):
        number = float(text)
        if math.isfinite(number):
            return number
    return text


def float_text(value: float, *, single: bool) -> str:
    """yaml-cpp's text of a float: max_digits10 significant digits, or .nan/.inf/-.inf."""
    if math.isnan(value):
        return ".nan"
    if math.isinf(value):
        return "-.inf" if value < 0 else ".inf"
    return f"{value:.9g}" if single else f"{value:.17g}"


def render(store: Typestore, msgtype: str, message: object) -> dict[str, object] | None:
    """The message's JSON value as upstream would store it (None: a message with no fields)."""
    _, fields = store.fielddefs[msgtype]
    out: dict[str, object] = {}
    for name, desc in fields:
        out[name] = _value(store, desc, getattr(message, name))
    return dict(sorted(out.items())) if out else None


def _value(store: Typestore, desc: FieldDesc, value: object) -> object:
    kind, rest = desc
    if kind == Nodetype.NAME:
        assert isinstance(rest, str)
        return render(store, rest, value)
    if kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
        item_desc = cast("FieldDesc", rest[0])
        items = [_value(store, item_desc, item) for item in cast("Iterable[object]", value)]
        return items or None
    typename = rest[0] if isinstance(rest, tuple) else rest
    return _base(str(typename), value)


def _base(typename: str, value: object) -> object:
    if typename == "bool":
        return bool(value)
    if typename in ("float32", "float64"):
        return scalar(float_text(float(value), single=typename == "float32"))  # type: ignore[arg-type]
    if typename in ("string", "wstring"):
        return scalar(str(value))
    integer = int(value)  # type: ignore[call-overload]
    if _INT64[0] <= integer <= _INT64[1]:
        return integer
    return scalar(float_text(float(integer), single=False))
