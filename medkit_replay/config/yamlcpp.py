"""YAML as upstream's C++ sees it through yaml-cpp 0.7: node kinds, subscripts, `as<T>()`.

PyYAML only composes nodes; scalars stay raw text and every conversion is yaml-cpp's own.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, cast

import yaml
from yaml.composer import Composer
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode
from yaml.parser import Parser
from yaml.reader import Reader
from yaml.resolver import BaseResolver
from yaml.scanner import Scanner

from medkit_replay.yaml_bounds import (
    YamlBoundsError,
    compose_bounded_at,
    describe_yaml_error,
    shown_text,
)

if TYPE_CHECKING:
    from yaml.error import Mark
    from yaml.events import ScalarEvent

__all__ = [
    "MAX_FILE_BYTES",
    "Node",
    "YamlCppError",
    "as_bool",
    "as_int32",
    "as_string",
    "as_uint32",
    "compose",
    "is_map",
    "is_null",
    "is_scalar",
    "is_sequence",
    "kind_name",
    "line_of",
    "map_items",
    "sequence_items",
    "subscript",
]

# yaml-cpp turns an untagged plain scalar with one of these texts into a Null node.
_NULL_TEXTS = frozenset({"", "~", "null", "Null", "NULL"})
_NULL_TAG = "tag:medkit-replay,2026:yaml-cpp-null"
_SCALAR_TAG = "tag:yaml.org,2002:str"
# std::ws / isspace in the "C" locale.
_STREAM_SPACE = " \t\n\v\f\r"
_BOOL_NAMES = {"y": True, "n": False, "yes": True, "no": False}
_BOOL_NAMES |= {"true": True, "false": False, "on": True, "off": False}
_INT32_MIN = -(2**31)
_INT32_MAX = 2**31 - 1
_UINT32_MAX = 2**32 - 1
# A correlation file with 10,000 rules is under 2 MB.
MAX_FILE_BYTES = 16 * 1024 * 1024
_MAX_INT32_DIGITS = 11  # 2**32 in octal; fewer in decimal and hex


class YamlCppError(Exception):
    """What yaml-cpp would throw (ParserException, BadSubscript, TypedBadConversion).

    ``line`` is 1-based, or None when unknown.
    """

    def __init__(self, message: str, line: int | None) -> None:
        super().__init__(message)
        self.message = message
        self.line = line


class _Loader(Reader, Scanner, Parser, Composer, BaseResolver):
    """Reader to composer only: no constructor, and no type resolution but yaml-cpp's null."""

    def __init__(self, stream: str | bytes) -> None:
        Reader.__init__(self, stream)
        Scanner.__init__(self)
        Parser.__init__(self)
        Composer.__init__(self)
        BaseResolver.__init__(self)

    def compose_scalar_node(self, anchor: dict[object, Node]) -> ScalarNode:
        event: ScalarEvent = self.get_event()  # type: ignore[no-untyped-call]
        # yaml-cpp: only an untagged *plain* scalar can be null ("!" is a tag too).
        plain_null = event.tag is None and event.style is None and event.value in _NULL_TEXTS
        node = ScalarNode(
            _NULL_TAG if plain_null else _SCALAR_TAG,
            event.value,
            cast("Mark | None", event.start_mark),
            cast("Mark | None", event.end_mark),
            style=event.style,
        )
        if anchor is not None:
            self.anchors[anchor] = node
        return node


def compose(text: str | bytes) -> Node | None:
    """The first document's root node, as `YAML::Load` builds it; None for an empty stream.

    None stands for yaml-cpp's default (Null) root: subscripting it finds nothing.
    Later documents are not read, as `YAML::Load` reads only the first one.
    """
    try:
        loader = _Loader(text)  # reading starts here: bad bytes can fail already
    except yaml.YAMLError as exc:
        problem, line = describe_yaml_error(exc, text)
        raise YamlCppError(problem, line) from exc
    try:
        return compose_bounded_at(
            loader, lambda: loader.get_node() if loader.check_node() else None
        )
    except YamlBoundsError as exc:
        raise YamlCppError(exc.message, exc.line) from exc
    except yaml.YAMLError as exc:
        problem, line = describe_yaml_error(exc, text)
        raise YamlCppError(problem, line) from exc
    finally:
        loader.dispose()


def line_of(node: Node) -> int | None:
    """1-based line where the node starts."""
    mark = node.start_mark
    return None if mark is None else mark.line + 1


def is_null(node: Node | None) -> bool:
    """A Null node (a plain, untagged `~`, `null`, `Null`, `NULL` or nothing)."""
    return isinstance(node, ScalarNode) and node.tag == _NULL_TAG


def is_scalar(node: Node | None) -> bool:
    """yaml-cpp's IsScalar: a scalar that is not Null (quoted `"null"` is a scalar)."""
    return isinstance(node, ScalarNode) and node.tag != _NULL_TAG


def is_sequence(node: Node | None) -> bool:
    """yaml-cpp's IsSequence."""
    return isinstance(node, SequenceNode)


def is_map(node: Node | None) -> bool:
    """yaml-cpp's IsMap."""
    return isinstance(node, MappingNode)


def kind_name(node: Node | None) -> str:
    """Node type in words, for messages."""
    if node is None or is_null(node):
        return "null"
    if is_scalar(node):
        return "scalar"
    return "sequence" if is_sequence(node) else "map"


def map_items(node: Node) -> list[tuple[Node, Node]]:
    """Every key/value pair of a map in file order, duplicate keys included (yaml-cpp keeps all)."""
    if not isinstance(node, MappingNode):
        return []
    return list(cast("list[tuple[Node, Node]]", node.value))


def sequence_items(node: Node) -> list[Node]:
    """The items of a sequence in order."""
    if not isinstance(node, SequenceNode):
        return []
    return list(cast("list[Node]", node.value))


def subscript(node: Node | None, key: str) -> Node | None:
    """yaml-cpp's read-only `node[key]`; None when there is no such key (a falsy node).

    A Null or sequence node has no keys; a scalar throws BadSubscript. With duplicate keys the
    *first* one is found, as yaml-cpp searches its pair list from the front.
    """
    if node is None or is_null(node) or isinstance(node, SequenceNode):
        return None
    if isinstance(node, ScalarNode):
        raise YamlCppError(f'operator[] call on a scalar (key: "{key}")', line_of(node))
    for item_key, value in map_items(node):
        if is_scalar(item_key) and cast("str", item_key.value) == key:
            return value
    return None


def as_string(node: Node) -> str:
    """`as<std::string>()`: a scalar's text; a Null node gives "null"; else bad conversion."""
    if is_null(node):
        return "null"
    if not isinstance(node, ScalarNode):
        raise YamlCppError(f"bad conversion: a {kind_name(node)} is not a string", line_of(node))
    return cast("str", node.value)


def _flexible_case(text: str) -> bool:
    # yaml-cpp's IsFlexibleCase: all lower, or a capital followed by all lower or all upper.
    def lower(s: str) -> bool:
        return all("a" <= ch <= "z" for ch in s)

    def upper(s: str) -> bool:
        return all("A" <= ch <= "Z" for ch in s)

    if not text or lower(text):
        return True
    return upper(text[0]) and (lower(text[1:]) or upper(text[1:]))


def as_bool(node: Node) -> bool:
    """`as<bool>()`: y/n, yes/no, true/false, on/off in lower, UPPER or Capitalised case."""
    if is_scalar(node):
        text = cast("str", node.value)
        if _flexible_case(text):
            value = _BOOL_NAMES.get(text.lower())
            if value is not None:
                return value
        raise YamlCppError(f"bad conversion: '{shown_text(text)}' is not a bool", line_of(node))
    raise YamlCppError(f"bad conversion: a {kind_name(node)} is not a bool", line_of(node))


def _stream_integer(text: str, *, signed: bool) -> int | None:
    """`std::stringstream >> noskipws >> n` with the base left to the input, then `>> ws` to EOF.

    Mirrors libstdc++'s num_get: optional sign, `0x`/`0X` → hex, a leading `0` → octal,
    no leading spaces, trailing spaces allowed; None where the conversion fails.
    """
    if not signed and text.startswith("-"):
        return None  # yaml-cpp refuses a leading '-' for unsigned types before parsing
    i, n = 0, len(text)
    negative = False
    if i < n and text[i] in "+-":
        negative = text[i] == "-"
        i += 1
    base, found_zero = 10, False
    if i < n and text[i] == "0":
        base, found_zero = 8, True
        i += 1
        if i < n and text[i] in "xX":
            base, found_zero = 16, False
            i += 1
    digits = "0123456789abcdefABCDEF" if base == 16 else "0123456789"[:base]
    start = i
    while i < n and text[i] in digits:
        i += 1
    if i == start and not found_zero:
        return None
    if text[i:].strip(_STREAM_SPACE):
        return None
    if len(text[start:i].lstrip("0")) > _MAX_INT32_DIGITS:
        return None  # overflows any 32-bit type (and int() refuses thousands of digits)
    magnitude = int(text[start:i], base) if i > start else 0
    value = -magnitude if negative else magnitude
    if signed:
        return value if _INT32_MIN <= value <= _INT32_MAX else None
    return value if value <= _UINT32_MAX else None


def as_uint32(node: Node) -> int:
    """`as<uint32_t>()`: decimal, `0x` hex or `0` octal, optional `+`; no `-`, no overflow."""
    return _as_integer(node, signed=False, name="a uint32")


def as_int32(node: Node) -> int:
    """`as<int>()`: decimal, `0x` hex or `0` octal with an optional sign, within int32."""
    return _as_integer(node, signed=True, name="an int")


def _as_integer(node: Node, *, signed: bool, name: str) -> int:
    if is_scalar(node):
        text = cast("str", node.value)
        value = _stream_integer(text, signed=signed)
        if value is not None:
            return value
        raise YamlCppError(f"bad conversion: '{shown_text(text)}' is not {name}", line_of(node))
    raise YamlCppError(f"bad conversion: a {kind_name(node)} is not {name}", line_of(node))
