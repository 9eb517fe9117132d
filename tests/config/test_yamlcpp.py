"""yaml-cpp 0.7 emulation: node kinds, subscripts and `as<T>()` conversions (correlation.md §2).

Expected values are yaml-cpp 0.7.0's own (libstdc++ stream parsing for the integers).
"""

from __future__ import annotations

import pytest

from medkit_replay.config.yamlcpp import (
    Node,
    YamlCppError,
    as_bool,
    as_int32,
    as_string,
    as_uint32,
    compose,
    is_map,
    is_null,
    is_scalar,
    is_sequence,
    kind_name,
    line_of,
    map_items,
    sequence_items,
    subscript,
)


def value(text: str) -> Node:
    """The node of `v: <text>`."""
    node = subscript(compose(f"v: {text}\n"), "v")
    assert node is not None
    return node


# -- bool -----------------------------------------------------------------------------------

BOOLS_OK = [
    *[(s, True) for s in ("true", "True", "TRUE", "yes", "Yes", "YES", "y", "Y")],
    *[(s, True) for s in ("on", "On", "ON", '"true"', "'yes'", "!!str on")],
    *[(s, False) for s in ("false", "False", "FALSE", "no", "No", "NO", "n", "N")],
    *[(s, False) for s in ("off", "Off", "OFF", '"off"')],
]
BOOLS_BAD = ["1", "0", "t", "f", "tRUE", "yEs", "oFF", "TRue", '""', "nope", '"true "', "[true]"]


@pytest.mark.parametrize(("text", "expected"), BOOLS_OK)
def test_as_bool_spellings(text: str, expected: bool) -> None:
    """§2 bool: y/n, yes/no, true/false, on/off; lower, UPPER or Capitalised; quoting ignored."""
    assert as_bool(value(text)) is expected


@pytest.mark.parametrize("text", BOOLS_BAD)
def test_as_bool_anything_else_throws(text: str) -> None:
    """§2 bool: `1`, `0`, `t`, mixed case and non-scalars throw (bad conversion)."""
    with pytest.raises(YamlCppError, match="bad conversion"):
        as_bool(value(text))


def test_as_bool_null_throws() -> None:
    """A Null node is not a scalar: as<bool> throws."""
    with pytest.raises(YamlCppError):
        as_bool(value("~"))


# -- integers -------------------------------------------------------------------------------

UINT32_OK = [
    ("0", 0),
    ("500", 500),
    ("0x10", 16),
    ("0X1f", 31),
    ("010", 8),
    ("00012", 10),
    ("+20", 20),
    ("+0", 0),
    ("+0x10", 16),
    ('"750"', 750),
    ("'750'", 750),
    ('"750  "', 750),
    ('"750\\t"', 750),
    ('"750\\n"', 750),
    ("4294967295", 4294967295),
    ("0xffffffff", 4294967295),
    ("037777777777", 4294967295),
    ("2147483648", 2147483648),
]
UINT32_BAD = [
    "-5",
    "-0",
    "1.5",
    "1e3",
    "12abc",
    "4294967296",
    "0x100000000",
    "040000000000",
    '" 750"',
    "08",
    "09",
    "0x",
    "0xg",
    "+",
    "+-5",
    "0o10",
    "0b11",
    "1_000",
    '""',
    ".inf",
    "nan",
    "[1]",
    "{a: 1}",
    "~",
]


@pytest.mark.parametrize(("text", "expected"), UINT32_OK)
def test_as_uint32_stream_parsing(text: str, expected: int) -> None:
    """§2 uint32: base auto-detection (0x hex, leading-0 octal), `+`, trailing spaces."""
    assert as_uint32(value(text)) == expected


@pytest.mark.parametrize("text", UINT32_BAD)
def test_as_uint32_throws(text: str) -> None:
    """§2 uint32: `-5`, `-0`, `1.5`, `1e3`, `12abc`, overflow, leading space, and non-digits."""
    with pytest.raises(YamlCppError):
        as_uint32(value(text))


INT32_OK = [
    ("0", 0),
    ("-0", 0),
    ("-5", -5),
    ("+3", 3),
    ("'-3'", -3),
    ("010", 8),
    ("-010", -8),
    ("0x10", 16),
    ("-0x10", -16),
    ("2147483647", 2147483647),
    ("-2147483648", -2147483648),
    ("-0x80000000", -2147483648),
    ("017777777777", 2147483647),
]
INT32_BAD = ["2147483648", "-2147483649", "0x80000000", "2.5", "1e3", "--5", "08", "abc", "~"]


@pytest.mark.parametrize(("text", "expected"), INT32_OK)
def test_as_int32_with_sign(text: str, expected: int) -> None:
    """fault-manager.md §1.12: decimal, octal or hex with an optional sign, within int32."""
    assert as_int32(value(text)) == expected


@pytest.mark.parametrize("text", INT32_BAD)
def test_as_int32_throws(text: str) -> None:
    """fault-manager.md §1.12: anything else (2.5, 1e3, overflow, null) is a conversion error."""
    with pytest.raises(YamlCppError):
        as_int32(value(text))


# -- strings and nulls ---------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "expected"),
    [("123", "123"), ("4.5", "4.5"), ("true", "true"), ('""', ""), ("'~'", "~"), ("~", "null")],
)
def test_as_string(text: str, expected: str) -> None:
    """§2: scalars are taken as text; as<std::string> of a Null node is "null"."""
    assert as_string(value(text)) == expected


def test_as_string_of_a_collection_throws() -> None:
    """as<std::string> of a sequence or map throws."""
    with pytest.raises(YamlCppError):
        as_string(value("[a]"))
    with pytest.raises(YamlCppError):
        as_string(value("{a: 1}"))


@pytest.mark.parametrize("text", ["~", "null", "Null", "NULL", ""])
def test_plain_null_spellings_are_null(text: str) -> None:
    """Only plain, untagged `~`/`null`/`Null`/`NULL`/empty are Null nodes."""
    node = value(text)
    assert is_null(node) is True
    assert is_scalar(node) is False
    assert kind_name(node) == "null"


@pytest.mark.parametrize("text", ['"null"', "'~'", "nULL", "!!str null", "! null", "!!null ~"])
def test_quoted_or_tagged_null_is_a_scalar(text: str) -> None:
    """Quoting or any tag makes a scalar (yaml-cpp resolves no tags)."""
    node = value(text)
    assert is_null(node) is False
    assert is_scalar(node) is True


def test_kinds() -> None:
    """IsScalar / IsSequence / IsMap."""
    assert is_sequence(value("[1, 2]")) and not is_map(value("[1, 2]"))
    assert is_map(value("{a: 1}")) and not is_sequence(value("{a: 1}"))
    assert [kind_name(value(t)) for t in ("x", "[x]", "{x: 1}", "~")] == [
        "scalar",
        "sequence",
        "map",
        "null",
    ]


# -- documents and subscripts -------------------------------------------------------------


@pytest.mark.parametrize("text", ["", "# only a comment\n", "\n\n"])
def test_empty_document_is_a_null_root(text: str) -> None:
    """YAML::Load of nothing gives a Null root; subscripting it finds nothing."""
    assert compose(text) is None
    assert subscript(compose(text), "correlation") is None


def test_only_the_first_document_is_read() -> None:
    """YAML::Load reads the first document; a broken later one is never seen."""
    root = compose("a: 1\n---\n{{{{\n")
    node = subscript(root, "a")
    assert node is not None
    assert as_uint32(node) == 1


def test_syntax_error_throws_with_its_line() -> None:
    """ParserException on a syntax error, with the 1-based line."""
    with pytest.raises(YamlCppError) as caught:
        compose("a: 1\nb: [1, 2\nc: 3\n")
    assert caught.value.line is not None
    assert caught.value.line >= 2
    with pytest.raises(YamlCppError):
        compose("{{{{not valid yaml")


def test_subscript_of_a_scalar_is_bad_subscript() -> None:
    """§2: const operator[] on a scalar throws BadSubscript, at the scalar's line."""
    root = compose("a: 1\nroot_cause: A\n")
    scalar = subscript(root, "root_cause")
    assert scalar is not None
    with pytest.raises(YamlCppError, match=r"operator\[\] call on a scalar") as caught:
        subscript(scalar, "codes")
    assert caught.value.line == 2
    with pytest.raises(YamlCppError):
        subscript(compose("hello\n"), "correlation")


def test_subscript_of_null_or_sequence_finds_nothing() -> None:
    """Null and sequence nodes have no keys; a missing key is falsy too."""
    assert subscript(value("~"), "codes") is None
    assert subscript(value("[codes]"), "codes") is None
    assert subscript(value("{x: 1}"), "codes") is None
    assert subscript(None, "codes") is None


def test_subscript_finds_the_first_of_duplicate_keys() -> None:
    """yaml-cpp keeps duplicate keys and a lookup finds the first one."""
    root = compose("enabled: false\nenabled: true\n")
    node = subscript(root, "enabled")
    assert node is not None
    assert as_bool(node) is False
    assert root is not None
    assert [as_string(k) for k, _ in map_items(root)] == ["enabled", "enabled"]


def test_subscript_matches_quoted_keys_not_null_keys() -> None:
    """Keys compare by scalar text, quoted or not; a Null key never matches."""
    root = compose('"a": 1\n~: 2\n')
    assert subscript(root, "a") is not None
    assert subscript(root, "null") is None
    assert subscript(root, "~") is None


def test_line_numbers_and_items() -> None:
    """line_of is 1-based; items keep file order."""
    root = compose("x: 1\nseq:\n  - a\n  - ~\n  - [b]\n")
    seq = subscript(root, "seq")
    assert seq is not None
    assert line_of(seq) == 3
    items = sequence_items(seq)
    assert [kind_name(i) for i in items] == ["scalar", "null", "sequence"]
    assert [line_of(i) for i in items] == [3, 4, 5]
    assert sequence_items(value("x")) == []
    assert map_items(value("[x]")) == []


def test_aliases_and_merge_keys() -> None:
    """An alias is the anchored node; `<<` is an ordinary key (yaml-cpp 0.7 does not merge)."""
    root = compose("a: &n {k: 5}\nb: *n\nc:\n  <<: *n\n")
    b = subscript(subscript(root, "b"), "k")
    assert b is not None
    assert as_uint32(b) == 5
    assert subscript(subscript(root, "c"), "k") is None
