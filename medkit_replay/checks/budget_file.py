"""Reading a fault budget file: a strict parser of the budget YAML with file:line errors.

The YAML is composed within bounds, then every value is checked into the model of ``budget``.
``budget.schema.json`` beside this module is the same format as a JSON Schema (editor
completion). Unknown keys, wrong types and out-of-range values are ConfigErrors naming the file
and line (exit 2).
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

import yaml
from yaml.constructor import ConstructorError, SafeConstructor

from medkit_replay.checks.budget import (
    BUDGET_VERSION,
    KINDS,
    SEVERITIES,
    AllowConfirm,
    Budget,
    ExpectCluster,
    ExpectConfirmed,
    ExpectNotConfirmed,
    MaxConfirmed,
    MaxConfirmedDuration,
    MaxOccurrences,
    NeverConfirm,
    Pattern,
    ResolvedByEnd,
    Rule,
    Window,
    default_name,
)
from medkit_replay.errors import ConfigError
from medkit_replay.files import read_limited
from medkit_replay.text import closest, name_hint
from medkit_replay.yaml_bounds import (
    compose_config,
    shown_text,
)

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from medkit_replay.checks.budget import RuleSpec

SCHEMA_FILE = Path(__file__).with_name("budget.schema.json")
"""The budget format as a JSON Schema (draft 2020-12)."""

MAX_BUDGET_BYTES = 16 * 1024 * 1024
"""A budget larger than this is refused unread (real ones are a few KB)."""

_TOP_KEYS = ("version", "name", "rules")
_INT = "tag:yaml.org,2002:int"
_FLOAT = "tag:yaml.org,2002:float"
_STR = "tag:yaml.org,2002:str"
_BOOL = "tag:yaml.org,2002:bool"
_NULL = "tag:yaml.org,2002:null"
_T = TypeVar("_T")
_SHOWN = 40
_COUNT_MAX = (1 << 63) - 1


# -- the parser ------------------------------------------------------------------------------


class _Reader:
    """Turns composed YAML nodes into checked values; every error names file and line."""

    def __init__(self, path: str) -> None:
        self.path = path
        self._constructor = SafeConstructor()

    def fail(self, node: yaml.Node | None, problem: str) -> ConfigError:
        line = node.start_mark.line + 1 if node is not None else None
        return ConfigError(problem, path=self.path, line=line)

    def scalar(self, node: yaml.Node, where: str) -> object:
        if not isinstance(node, yaml.ScalarNode):
            raise self.fail(node, f"{where}: expected a value, found {_kind(node)}")
        try:
            return self._constructor.construct_object(node)
        except ConstructorError as err:
            raise self.fail(node, f"{where}: {err.problem}") from None
        except ValueError:  # int() refuses thousands of digits
            raise self.fail(node, f"{where}: {_text(node)} is too long a number") from None

    def string(self, node: yaml.Node, where: str) -> str:
        if not (isinstance(node, yaml.ScalarNode) and node.tag == _STR):
            raise self.fail(node, f"{where}: expected a string, found {_kind(node)}")
        return str(node.value)

    def pattern(self, node: yaml.Node, where: str) -> Pattern:
        text = self.string(node, where)
        if not text:
            raise self.fail(node, f"{where}: a fault-code pattern must not be empty")
        return Pattern.of(text)

    def patterns(self, node: yaml.Node, where: str) -> tuple[Pattern, ...]:
        if not isinstance(node, yaml.SequenceNode):
            raise self.fail(
                node, f"{where}: expected a list of fault-code patterns, found {_kind(node)}"
            )
        if not node.value:
            raise self.fail(node, f"{where}: the list of patterns is empty")
        return tuple(self.pattern(item, f"{where}[{n}]") for n, item in enumerate(node.value))

    def count(self, node: yaml.Node, where: str) -> int:
        if not (isinstance(node, yaml.ScalarNode) and node.tag == _INT):
            raise self.fail(node, f"{where}: expected a whole number, found {_kind(node)}")
        value = self.scalar(node, where)
        assert isinstance(value, int)
        if value < 0:
            raise self.fail(node, f"{where}: must be 0 or more, found {_text(node)}")
        if value > _COUNT_MAX:  # no count reaches it, and a longer number cannot be shown
            raise self.fail(node, f"{where}: {_text(node)} is larger than {_COUNT_MAX}")
        return value

    def seconds(self, node: yaml.Node, where: str) -> float:
        if not (isinstance(node, yaml.ScalarNode) and node.tag in (_INT, _FLOAT)):
            raise self.fail(node, f"{where}: expected a number of seconds, found {_kind(node)}")
        value = self.scalar(node, where)
        assert isinstance(value, int | float)
        try:
            seconds = float(value)
        except OverflowError:
            seconds = math.inf
        # Times are compared in nanoseconds: past the double range there, no time is meant.
        if not math.isfinite(seconds * 1e9) or seconds < 0:
            raise self.fail(
                node, f"{where}: must be a finite number, 0 or more, found {_text(node)}"
            )
        return seconds

    def mapping(
        self, node: yaml.Node, where: str, *, allowed: Sequence[str] | None = None
    ) -> list[tuple[str, yaml.Node, yaml.Node]]:
        """(key, key node, value node) in file order; keys are strings, unique, and allowed."""
        if not isinstance(node, yaml.MappingNode):
            raise self.fail(node, f"{where}: expected a mapping, found {_kind(node)}")
        items: list[tuple[str, yaml.Node, yaml.Node]] = []
        seen: set[str] = set()
        for key_node, value_node in node.value:
            key = self.string(key_node, f"{where}: key")
            if key in seen:
                raise self.fail(key_node, f"{where}: duplicate key '{shown_text(key)}'")
            if allowed is not None and key not in allowed:
                hint = name_hint(closest(key, allowed), allowed)
                raise self.fail(key_node, f"{where}: unknown key '{shown_text(key)}' ({hint})")
            seen.add(key)
            items.append((key, key_node, value_node))
        return items

    def window(self, node: yaml.Node, where: str) -> Window:
        if not (isinstance(node, yaml.SequenceNode) and len(node.value) == 2):
            raise self.fail(
                node, f"{where}: expected [FROM, TO], two numbers of seconds from the start"
            )
        start = self.seconds(node.value[0], f"{where}[0]")
        end = self.seconds(node.value[1], f"{where}[1]")
        if end < start:
            raise self.fail(
                node, f"{where}: the window ends ({end:g} s) before it starts ({start:g} s)"
            )
        return Window(start, end)


def _text(node: yaml.Node) -> str:
    """A scalar's text for a message, cut short when long."""
    return shown_text(str(node.value), limit=_SHOWN)


def _kind(node: yaml.Node) -> str:
    if isinstance(node, yaml.MappingNode):
        return "a mapping"
    if isinstance(node, yaml.SequenceNode):
        return "a list"
    names = {_INT: "a whole number", _FLOAT: "a number", _STR: "a string", _BOOL: "a boolean"}
    if node.tag == _NULL:
        return "nothing (null)"
    text = shown_text(str(node.value), limit=_SHOWN)
    shown = f"'{text}'" if node.tag == _STR else text  # as written
    return f"{names.get(node.tag, 'a value')} ({shown})"


def _max_confirmed(reader: _Reader, node: yaml.Node, where: str) -> MaxConfirmed:
    items = reader.mapping(node, where, allowed=SEVERITIES)
    if not items:
        raise reader.fail(node, f"{where}: name at least one severity ({', '.join(SEVERITIES)})")
    limits = {SEVERITIES.index(k): reader.count(v, f"{where}.{k}") for k, _, v in items}
    return MaxConfirmed(tuple(sorted(limits.items())))


def _limits(
    reader: _Reader,
    node: yaml.Node,
    where: str,
    value: Callable[[yaml.Node, str], _T],
) -> tuple[tuple[Pattern, _T], ...]:
    items = reader.mapping(node, where)
    if not items:
        raise reader.fail(node, f"{where}: map at least one fault-code pattern to its limit")
    limits: list[tuple[Pattern, _T]] = []
    for key, key_node, value_node in items:
        if not key:
            raise reader.fail(key_node, f"{where}: a fault-code pattern must not be empty")
        limits.append((Pattern.of(key), value(value_node, f"{where}.{shown_text(key)}")))
    return tuple(limits)


def _code_and_window(
    reader: _Reader, node: yaml.Node, where: str, allowed: tuple[str, ...], code_is: str
) -> tuple[dict[str, yaml.Node], Pattern, Window | None]:
    """An expectation's keys, its required ``code`` pattern and its optional ``between``."""
    values = {k: v for k, _, v in reader.mapping(node, where, allowed=allowed)}
    if "code" not in values:
        raise reader.fail(node, f"{where}: 'code' ({code_is}) is required")
    code = reader.pattern(values["code"], f"{where}.code")
    between = values.get("between")
    return values, code, reader.window(between, f"{where}.between") if between is not None else None


def _expect_confirmed(reader: _Reader, node: yaml.Node, where: str) -> ExpectConfirmed:
    allowed = ("code", "between", "muted_by")
    values, code, between = _code_and_window(
        reader, node, where, allowed, "the fault-code pattern expected"
    )
    muted_by = values.get("muted_by")
    return ExpectConfirmed(
        code=code,
        between=between,
        muted_by=reader.pattern(muted_by, f"{where}.muted_by") if muted_by is not None else None,
    )


def _expect_not_confirmed(reader: _Reader, node: yaml.Node, where: str) -> ExpectNotConfirmed:
    _, code, between = _code_and_window(
        reader, node, where, ("code", "between"), "the fault-code pattern"
    )
    return ExpectNotConfirmed(code=code, between=between)


def _expect_cluster(reader: _Reader, node: yaml.Node, where: str) -> ExpectCluster:
    values = {k: v for k, _, v in reader.mapping(node, where, allowed=("rule", "cluster"))}
    if len(values) != 1:
        raise reader.fail(
            node,
            f"{where}: give exactly one of 'rule' (a correlation rule id pattern) or "
            "'cluster' (a cluster id pattern)",
        )
    if "rule" in values:
        return ExpectCluster(rule=reader.pattern(values["rule"], f"{where}.rule"))
    return ExpectCluster(cluster=reader.pattern(values["cluster"], f"{where}.cluster"))


def _spec(reader: _Reader, kind: str, node: yaml.Node, where: str) -> RuleSpec:
    where = f"{where}: {kind}"
    if kind == "max_confirmed":
        return _max_confirmed(reader, node, where)
    if kind == "never_confirm":
        return NeverConfirm(reader.patterns(node, where))
    if kind == "allow_confirm":
        return AllowConfirm(reader.patterns(node, where))
    if kind == "max_occurrences":
        return MaxOccurrences(_limits(reader, node, where, reader.count))
    if kind == "max_confirmed_duration_sec":
        return MaxConfirmedDuration(_limits(reader, node, where, reader.seconds))
    if kind == "resolved_by_end":
        return ResolvedByEnd(reader.patterns(node, where))
    if kind == "expect_confirmed":
        return _expect_confirmed(reader, node, where)
    if kind == "expect_not_confirmed":
        return _expect_not_confirmed(reader, node, where)
    assert kind == "expect_cluster"
    return _expect_cluster(reader, node, where)


def _rule(reader: _Reader, node: yaml.Node, index: int) -> tuple[Rule, bool]:
    """One rule and whether its name was given."""
    where = f"rule {index}"
    items = reader.mapping(node, where, allowed=("name", *KINDS))
    kinds = [(k, v) for k, _, v in items if k != "name"]
    if not kinds:
        raise reader.fail(node, f"{where}: a rule needs one of: {', '.join(KINDS)}")
    if len(kinds) > 1:
        raise reader.fail(
            node, f"{where}: one kind per rule, found {' and '.join(k for k, _ in kinds)}"
        )
    kind, value = kinds[0]
    spec = _spec(reader, kind, value, where)
    names = [v for k, _, v in items if k == "name"]
    name = reader.string(names[0], f"{where}: name").strip() if names else ""
    if names and not name:
        raise reader.fail(names[0], f"{where}: name must not be empty")
    line = node.start_mark.line + 1
    return Rule(name or default_name(spec), kind, spec, index, line), bool(names)


def parse_budget(text: str, path: str) -> Budget:
    """Parse a budget's YAML text; ``path`` names it in errors.

    Raises:
        ConfigError: invalid YAML, an unknown key, a wrong type or value (with file and line).
    """
    reader = _Reader(path)
    root = compose_config(text, path)
    if root is None:
        raise ConfigError("empty budget: expected 'version: 1' and a list of 'rules'", path=path)
    values = {k: (kn, v) for k, kn, v in reader.mapping(root, "budget", allowed=_TOP_KEYS)}
    if "version" not in values:
        raise reader.fail(root, "budget: 'version: 1' is required (the budget format version)")
    version_node = values["version"][1]
    version = reader.count(version_node, "version")
    if version != BUDGET_VERSION:
        raise reader.fail(
            version_node,
            f"version: budget format {_text(version_node)} is not supported by this medkit-replay "
            f"(it reads version {BUDGET_VERSION})",
        )
    name: str | None = None
    if "name" in values:
        name = reader.string(values["name"][1], "name").strip() or None
    if "rules" not in values:
        raise reader.fail(root, "budget: 'rules' (the list of rules) is required")
    rules_node = values["rules"][1]
    if not isinstance(rules_node, yaml.SequenceNode):
        raise reader.fail(rules_node, f"rules: expected a list of rules, found {_kind(rules_node)}")
    if not rules_node.value:
        raise reader.fail(rules_node, "rules: the budget has no rule")
    parsed = [_rule(reader, node, n) for n, node in enumerate(rules_node.value, start=1)]
    return Budget(path=path, rules=_unique_names(reader, parsed), name=name, version=version)


def _unique_names(reader: _Reader, parsed: list[tuple[Rule, bool]]) -> tuple[Rule, ...]:
    """Given names must differ; a derived name that repeats one gets its rule number."""
    given: dict[str, Rule] = {}
    for rule, named in parsed:
        if named:
            if rule.name in given:
                first = given[rule.name]
                raise ConfigError(
                    f"rule {rule.index}: name '{shown_text(rule.name)}' is already used by "
                    f"rule {first.index}",
                    path=reader.path,
                    line=rule.line,
                )
            given[rule.name] = rule
    taken = set(given)
    rules: list[Rule] = []
    for rule, named in parsed:
        if not named:
            name = rule.name
            if name in taken:
                name = f"{name} (rule {rule.index})"
            taken.add(name)
            rule = Rule(name, rule.kind, rule.spec, rule.index, rule.line)
        rules.append(rule)
    return tuple(rules)


def load_budget(path: str | Path, *, allow_empty: bool = False) -> Budget:
    """Read and parse a budget file; ``allow_empty`` (``--allow-empty``) lets a replay that
    took nothing hold it.

    Raises:
        ConfigError: the file is missing, unreadable or not a valid budget (file and line).
    """
    shown = str(path)
    try:
        data = read_limited(path, MAX_BUDGET_BYTES)
    except FileNotFoundError:
        raise ConfigError("budget file not found", path=shown) from None
    except OSError as err:  # a FIFO, device, directory or oversized file too
        raise ConfigError(f"cannot read budget file: {err}", path=shown) from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        line = data.count(b"\n", 0, err.start) + 1
        raise ConfigError(f"cannot read budget file: {err}", path=shown, line=line) from None
    budget = parse_budget(text, shown)
    return replace(budget, allow_empty=True) if allow_empty else budget
