"""The budget file: every rule kind parsed, strict errors with file:line, the JSON Schema agrees."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING

import jsonschema
import pytest
import yaml

from medkit_replay.checks.budget import (
    KINDS,
    AllowConfirm,
    ExpectCluster,
    ExpectConfirmed,
    ExpectNotConfirmed,
    MaxConfirmed,
    MaxConfirmedDuration,
    MaxOccurrences,
    NeverConfirm,
    Pattern,
    ResolvedByEnd,
    Window,
)
from medkit_replay.checks.budget_file import SCHEMA_FILE, load_budget, parse_budget
from medkit_replay.errors import ConfigError
from tests.checks.support import BUDGETS, ROOT, budget_text

if TYPE_CHECKING:
    from pathlib import Path

EVERY_KIND = """
- name: per severity
  max_confirmed: {CRITICAL: 0, ERROR: 3}
- never_confirm: ["ESTOP*", "BATTERY_?OW"]
- allow_confirm: ["*"]
- max_occurrences: {"ESTOP": 1, "*": 5}
- max_confirmed_duration_sec: {"MOTOR_*": 2.5, "*": 30}
- resolved_by_end: [MOTOR_*]
- expect_confirmed: {code: MOTOR_LEFT_OVERHEAT, between: [0, 1.5], muted_by: "ROOT_*"}
- expect_not_confirmed: {code: LIDAR_*, between: [5, 10]}
- expect_not_confirmed: {code: ESTOP}
- expect_cluster: {rule: sensor_storm}
- name: storm by id
  expect_cluster: {cluster: "sensor_storm_?"}
"""


def schema() -> dict[str, object]:
    loaded: dict[str, object] = json.loads(SCHEMA_FILE.read_text(encoding="utf-8"))
    return loaded


def schema_errors(text: str) -> list[str]:
    validator = jsonschema.Draft202012Validator(schema())
    return [error.message for error in validator.iter_errors(yaml.safe_load(text))]


def test_every_rule_kind_parses() -> None:
    budget = parse_budget(budget_text(EVERY_KIND), "b.yaml")
    assert [r.kind for r in budget.rules] == [
        "max_confirmed",
        "never_confirm",
        "allow_confirm",
        "max_occurrences",
        "max_confirmed_duration_sec",
        "resolved_by_end",
        "expect_confirmed",
        "expect_not_confirmed",
        "expect_not_confirmed",
        "expect_cluster",
        "expect_cluster",
    ]
    assert {r.kind for r in budget.rules} == set(KINDS)
    specs = [r.spec for r in budget.rules]
    assert specs[0] == MaxConfirmed(((2, 3), (3, 0)))
    assert specs[1] == NeverConfirm((Pattern.of("ESTOP*"), Pattern.of("BATTERY_?OW")))
    assert specs[2] == AllowConfirm((Pattern.of("*"),))
    assert specs[3] == MaxOccurrences(((Pattern.of("ESTOP"), 1), (Pattern.of("*"), 5)))
    assert specs[4] == MaxConfirmedDuration(((Pattern.of("MOTOR_*"), 2.5), (Pattern.of("*"), 30.0)))
    assert specs[5] == ResolvedByEnd((Pattern.of("MOTOR_*"),))
    assert specs[6] == ExpectConfirmed(
        Pattern.of("MOTOR_LEFT_OVERHEAT"), Window(0.0, 1.5), Pattern.of("ROOT_*")
    )
    assert specs[7] == ExpectNotConfirmed(Pattern.of("LIDAR_*"), Window(5.0, 10.0))
    assert specs[8] == ExpectNotConfirmed(Pattern.of("ESTOP"))
    assert specs[9] == ExpectCluster(rule=Pattern.of("sensor_storm"))
    assert specs[10] == ExpectCluster(cluster=Pattern.of("sensor_storm_?"))
    assert [r.index for r in budget.rules] == list(range(1, 12))
    assert [r.line for r in budget.rules][:3] == [3, 5, 6]
    assert budget.title == "b.yaml"
    assert schema_errors(budget_text(EVERY_KIND)) == []


def test_names_given_and_derived() -> None:
    budget = parse_budget(budget_text(EVERY_KIND, header="version: 1\nname: Mine\nrules:\n"), "b")
    names = [r.name for r in budget.rules]
    assert budget.title == "Mine"
    assert names[0] == "per severity"
    assert names[1] == "never confirmed: ESTOP*, BATTERY_?OW"
    assert names[3] == "most occurrences: ESTOP 1, * 5"
    assert names[4] == "longest CONFIRMED: MOTOR_* 2.5 s, * 30 s"
    assert names[6] == "MOTOR_LEFT_OVERHEAT confirmed between 0 and 1.5 s, muted by ROOT_*"
    assert names[8] == "ESTOP not confirmed"
    assert names[9] == "cluster of rule sensor_storm formed"
    assert names[10] == "storm by id"
    assert len(set(names)) == len(names)


def test_a_repeated_derived_name_gets_its_rule_number() -> None:
    text = budget_text("- never_confirm: [A]\n- never_confirm: [A]\n- never_confirm: [B, C, D, E]")
    names = [r.name for r in parse_budget(text, "b").rules]
    assert names == [
        "never confirmed: A",
        "never confirmed: A (rule 2)",
        "never confirmed: B, C, D +1 more",
    ]


@pytest.mark.parametrize(
    ("pattern", "code", "matches"),
    [
        ("ESTOP*", "ESTOP", True),
        ("ESTOP*", "ESTOP_PRESSED", True),
        ("ESTOP*", "MY_ESTOP", False),
        ("*_OVERHEAT", "MOTOR_LEFT_OVERHEAT", True),
        ("MOTOR_?", "MOTOR_1", True),
        ("MOTOR_?", "MOTOR_12", False),
        ("MOTOR.1", "MOTOR.1", True),
        ("MOTOR.1", "MOTORX1", False),  # only * and ? are special
        ("[AB]", "A", False),
        ("[AB]", "[AB]", True),
        ("estop", "ESTOP", False),  # case-sensitive
        ("*", "", True),
    ],
)
def test_glob_patterns(pattern: str, code: str, matches: bool) -> None:
    assert Pattern.of(pattern).matches(code) is matches


# (the rules, or a whole file when not starting with "- "; line; words in the message; whether
# the JSON Schema refuses it too: it cannot see duplicate keys or names, nor order a window)
BAD: list[tuple[str, int | None, str, bool]] = [
    ("version: 2\nrules: [{never_confirm: [A]}]\n", 1, "budget format 2 is not supported", True),
    ("rules: [{never_confirm: [A]}]\n", 1, "'version: 1' is required", True),
    ("version: '1'\nrules: [{never_confirm: [A]}]\n", 1, "expected a whole number", True),
    (
        "version: 1\nrule: [{never_confirm: [A]}]\n",
        2,
        "unknown key 'rule' (did you mean 'rules'?)",
        True,
    ),
    ("version: 1\n", 1, "'rules' (the list of rules) is required", True),
    ("version: 1\nrules: []\n", 2, "the budget has no rule", True),
    ("version: 1\nrules: {a: 1}\n", 2, "rules: expected a list of rules, found a mapping", True),
    ("version: 1\nname: 3\nrules: [{never_confirm: [A]}]\n", 2, "name: expected a string", True),
    ("[never_confirm, A]\n", 1, "budget: expected a mapping, found a list", True),
    ("version: 1\nrules:\n  - never_confirm: [A\n", 4, "invalid YAML", False),
    (
        "version: 1\nversion: 1\nrules: [{never_confirm: [A]}]\n",
        2,
        "duplicate key 'version'",
        False,
    ),
    (
        "- max_confimed: {ERROR: 1}",
        3,
        "unknown key 'max_confimed' (did you mean 'max_confirmed'?)",
        True,
    ),
    ("- name: only a name", 3, "a rule needs one of: max_confirmed, never_confirm", True),
    (
        "- never_confirm: [A]\n  allow_confirm: [B]",
        3,
        "one kind per rule, found never_confirm and allow_confirm",
        True,
    ),
    ("- 42", 3, "rule 1: expected a mapping, found a whole number (42)", True),
    ("- never_confirm: [A]\n  name: ''", 4, "rule 1: name must not be empty", True),
    (
        "- {name: x, never_confirm: [A]}\n- {name: x, never_confirm: [B]}",
        4,
        "name 'x' is already used by rule 1",
        False,
    ),
    (
        "- max_confirmed: {ERROR: '3'}",
        3,
        "max_confirmed.ERROR: expected a whole number, found a string ('3')",
        True,
    ),
    ("- max_confirmed: {error: 3}", 3, "unknown key 'error' (did you mean 'ERROR'?)", True),
    ("- max_confirmed: {ERROR: -1}", 3, "max_confirmed.ERROR: must be 0 or more, found -1", True),
    ("- max_confirmed: {ERROR: 1.5}", 3, "expected a whole number, found a number (1.5)", True),
    ("- max_confirmed: {}", 3, "name at least one severity", True),
    ("- max_confirmed: [ERROR]", 3, "max_confirmed: expected a mapping, found a list", True),
    ("- never_confirm: ESTOP*", 3, "never_confirm: expected a list of fault-code patterns", True),
    ("- never_confirm: []", 3, "never_confirm: the list of patterns is empty", True),
    (
        "- never_confirm:\n    - A\n    - ''",
        5,
        "never_confirm[1]: a fault-code pattern must not be empty",
        True,
    ),
    ("- allow_confirm: [1]", 3, "allow_confirm[0]: expected a string, found a whole number", True),
    ("- resolved_by_end: null", 3, "found nothing (null)", True),
    ("- max_occurrences: {A: x}", 3, "max_occurrences.A: expected a whole number", True),
    ("- max_occurrences: {}", 3, "map at least one fault-code pattern", True),
    ("- max_occurrences: {'': 1}", 3, "a fault-code pattern must not be empty", True),
    (
        "- max_confirmed_duration_sec: {A: true}",
        3,
        "expected a number of seconds, found a boolean",
        True,
    ),
    ("- max_confirmed_duration_sec: {A: -2}", 3, "must be a finite number, 0 or more", True),
    ("- max_confirmed_duration_sec: {A: .inf}", 3, "must be a finite number", False),
    (
        "- expect_confirmed: {between: [1, 2]}",
        3,
        "'code' (the fault-code pattern expected) is required",
        True,
    ),
    ("- expect_confirmed: {code: A, within: [1, 2]}", 3, "unknown key 'within'", True),
    (
        "- expect_confirmed:\n    code: A\n    between: [5, 1]",
        5,
        "the window ends (1 s) before it starts (5 s)",
        False,
    ),
    ("- expect_confirmed: {code: A, between: [1]}", 3, "between: expected [FROM, TO]", True),
    (
        "- expect_confirmed: {code: A, between: [1, x]}",
        3,
        "between[1]: expected a number of seconds",
        True,
    ),
    (
        "- expect_confirmed: {code: A, muted_by: ''}",
        3,
        "muted_by: a fault-code pattern must not be empty",
        True,
    ),
    (
        "- expect_not_confirmed: A",
        3,
        "expect_not_confirmed: expected a mapping, found a string",
        True,
    ),
    ("- expect_not_confirmed: {}", 3, "'code' (the fault-code pattern) is required", True),
    ("- expect_cluster: {rule: a, cluster: b}", 3, "give exactly one of 'rule'", True),
    ("- expect_cluster: {}", 3, "give exactly one of 'rule'", True),
    ("- expect_cluster: {rules: a}", 3, "unknown key 'rules' (did you mean 'rule'?)", True),
    ("- expect_cluster: {x: a}", 3, "unknown key 'x' (expected one of: rule, cluster)", True),
]


@pytest.mark.parametrize(("case", "line", "words", "schema_rejects"), BAD)
def test_bad_budgets_name_file_and_line(
    case: str, line: int | None, words: str, schema_rejects: bool
) -> None:
    text = budget_text(case) if case.startswith("- ") else case  # rules, or a whole file
    with pytest.raises(ConfigError) as caught:
        parse_budget(text, "budgets/ci.yaml")
    err = caught.value
    assert err.path == "budgets/ci.yaml"
    assert err.line == line
    assert words in err.problem
    assert err.render().startswith(f"budgets/ci.yaml:{line}: ")
    if schema_rejects:
        assert schema_errors(text), "the JSON Schema accepts what the parser refuses"


def test_empty_budget() -> None:
    with pytest.raises(ConfigError, match="empty budget") as caught:
        parse_budget("# nothing\n", "b.yaml")
    assert caught.value.line is None


def test_load_budget_missing_and_unreadable(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="budget file not found"):
        load_budget(tmp_path / "absent.yaml")
    binary = tmp_path / "binary.yaml"
    binary.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(ConfigError, match="cannot read budget file"):
        load_budget(binary)


def test_schema_is_valid_draft_2020_12() -> None:
    jsonschema.Draft202012Validator.check_schema(schema())


@pytest.mark.parametrize("path", sorted(BUDGETS.glob("*.yaml")), ids=lambda p: p.name)
def test_example_budgets_validate_against_the_schema(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    assert schema_errors(text) == []
    assert "yaml-language-server: $schema=../../medkit_replay/checks/budget.schema.json" in text
    assert (path.parent / "../../medkit_replay/checks/budget.schema.json").resolve() == SCHEMA_FILE
    budget = load_budget(path)
    assert budget.name and budget.rules


def test_readme_budget_parses_and_validates() -> None:
    page = (ROOT / "docs" / "commands" / "check.md").read_text(encoding="utf-8")
    block = page.split("```yaml\n", 1)[1].split("```", 1)[0]
    assert schema_errors(block) == []
    assert len(parse_budget(block, "docs/commands/check.md").rules) == 10


def test_docs_reference_the_schema() -> None:
    docs = (ROOT / "docs" / "budgets.md").read_text(encoding="utf-8")
    assert "medkit_replay/checks/budget.schema.json" in docs
    assert all(f"`{kind}`" in docs for kind in KINDS)


def test_schema_lists_every_rule_kind() -> None:
    rule = schema()["$defs"]
    assert isinstance(rule, dict)
    kinds = [variant["title"] for variant in rule["rule"]["oneOf"]]
    assert kinds == list(KINDS)
