"""Upstream's test_correlation_config_parser.cpp (23 tests), the §2/§3 schema rules, and loading.

YAML texts go through parse_correlation_config and validate_config (correlation.md §2, §3, §13.3).
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import pytest

from medkit_replay.config.correlation_file import (
    CorrelationLoad,
    InvalidArgumentError,
    load_correlation,
    parse_correlation_config,
)
from medkit_replay.config.yamlcpp import YamlCppError
from medkit_replay.engine.correlation import (
    CorrelationConfig,
    CorrelationRule,
    Representative,
    string_to_mode,
    string_to_representative,
    validate_config,
)

if TYPE_CHECKING:
    from pathlib import Path


def parse(text: str) -> CorrelationConfig:
    """Parse YAML text as upstream's parse_config_string does."""
    return parse_correlation_config(text)


def only_rule(text: str) -> CorrelationRule:
    """The single rule of a config."""
    (rule,) = parse(text).rules
    return rule


# -- 13.3 tests 1-5: mode and representative names -------------------------------------------


def test_p01_string_to_mode_hierarchical() -> None:
    """13.3-1 StringToModeHierarchical [A]."""
    for text in ("hierarchical", "HIERARCHICAL", "Hierarchical"):
        assert string_to_mode(text) == "hierarchical"


def test_p02_string_to_mode_auto_cluster() -> None:
    """13.3-2 StringToModeAutoCluster [A]; AUTO_CLUSTER and AutoCluster [I]."""
    for text in ("auto_cluster", "autocluster", "cluster", "AUTO_CLUSTER", "AutoCluster"):
        assert string_to_mode(text) == "auto_cluster"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("invalid", "Invalid correlation mode: invalid. Valid values: hierarchical, auto_cluster"),
        ("", "Invalid correlation mode: . Valid values: hierarchical, auto_cluster"),
    ],
)
def test_p03_string_to_mode_invalid(text: str, message: str) -> None:
    """13.3-3 StringToModeInvalid: raises [A], with upstream's exact text [I]."""
    with pytest.raises(ValueError, match="Invalid correlation mode") as caught:
        string_to_mode(text)
    assert str(caught.value) == message


def test_p04_string_to_representative() -> None:
    """13.3-4 StringToRepresentative [A]; Recent and SEVERITY [I]."""
    assert string_to_representative("first") is Representative.FIRST
    assert string_to_representative("most_recent") is Representative.MOST_RECENT
    assert string_to_representative("recent") is Representative.MOST_RECENT
    assert string_to_representative("highest_severity") is Representative.HIGHEST_SEVERITY
    assert string_to_representative("severity") is Representative.HIGHEST_SEVERITY
    assert string_to_representative("Recent") is Representative.MOST_RECENT
    assert string_to_representative("SEVERITY") is Representative.HIGHEST_SEVERITY


def test_p05_string_to_representative_invalid() -> None:
    """13.3-5 StringToRepresentativeInvalid: raises [A], exact text [I]."""
    with pytest.raises(ValueError, match="Invalid representative") as caught:
        string_to_representative("invalid")
    assert str(caught.value) == (
        "Invalid representative: invalid. Valid values: first, most_recent, highest_severity"
    )


# -- 13.3 tests 6-23: parsing and validation -------------------------------------------------


def test_p06_parse_empty_config() -> None:
    """13.3-6 ParseEmptyConfig: disabled [A]; defaults and clean validation [I]."""
    config = parse("# Empty config - no correlation section\n")
    assert config.enabled is False
    assert config == CorrelationConfig(enabled=False, default_window_ms=500, patterns={}, rules=())
    result = validate_config(config)
    assert (result.valid, result.errors, result.warnings) == (True, (), ())


def test_p07_parse_disabled_config() -> None:
    """13.3-7 ParseDisabledConfig [A]."""
    assert parse("correlation:\n  enabled: false\n").enabled is False


def test_p08_parse_minimal_config() -> None:
    """13.3-8 ParseMinimalConfig [A]; the no-rules warning [I]."""
    config = parse("correlation:\n  enabled: true\n  default_window_ms: 1000\n")
    assert config.enabled is True
    assert config.default_window_ms == 1000
    assert config.patterns == {}
    assert config.rules == ()
    result = validate_config(config)
    assert result.valid is True
    assert result.warnings == ("Correlation is enabled but no rules are defined",)


def test_p09_parse_patterns() -> None:
    """13.3-9 ParsePatterns [A]; the no-rules warning [I]."""
    config = parse(
        """
correlation:
  enabled: true
  patterns:
    motor_errors:
      codes: ["MOTOR_COMM_*", "MOTOR_TIMEOUT_*"]
    sensor_issues:
      codes: ["SENSOR_*"]
"""
    )
    assert len(config.patterns) == 2
    assert config.patterns["motor_errors"] == ("MOTOR_COMM_*", "MOTOR_TIMEOUT_*")
    assert len(config.patterns["sensor_issues"]) == 1
    assert validate_config(config).warnings == ("Correlation is enabled but no rules are defined",)


def test_p10_parse_hierarchical_rule() -> None:
    """13.3-10 ParseHierarchicalRule [A]."""
    rule = only_rule(
        """
correlation:
  enabled: true
  patterns:
    motor_errors:
      codes: ["MOTOR_COMM_*"]
  rules:
    - id: estop_cascade
      name: "E-Stop Cascade"
      mode: hierarchical
      root_cause:
        codes: ["ESTOP_001"]
      symptoms:
        - pattern: motor_errors
      window_ms: 1000
      mute_symptoms: true
      auto_clear_with_root: true
"""
    )
    assert (rule.id, rule.name, rule.mode) == ("estop_cascade", "E-Stop Cascade", "hierarchical")
    assert rule.root_cause_codes == ("ESTOP_001",)
    assert rule.symptom_pattern_ids == ("motor_errors",)
    assert (rule.window_ms, rule.mute_symptoms, rule.auto_clear_with_root) == (1000, True, True)


def test_p11_parse_hierarchical_rule_with_inline_codes() -> None:
    """13.3-11 ParseHierarchicalRuleWithInlineCodes: codes and valid [A]; no warnings [I]."""
    config = parse(
        """
correlation:
  enabled: true
  rules:
    - id: inline_test
      name: "Inline Codes Test"
      mode: hierarchical
      root_cause: {codes: ["ESTOP_001"]}
      symptoms:
        - codes: ["MOTOR_COMM_*", "MOTOR_TIMEOUT_*"]
        - codes: ["DRIVE_*"]
      window_ms: 1000
"""
    )
    (rule,) = config.rules
    assert rule.id == "inline_test"
    assert rule.mode == "hierarchical"
    assert rule.symptom_pattern_ids == ()
    assert rule.inline_symptom_codes == ("MOTOR_COMM_*", "MOTOR_TIMEOUT_*", "DRIVE_*")
    result = validate_config(config)
    assert result.valid is True
    assert result.warnings == ()


def test_p12_parse_hierarchical_rule_mixed_symptoms() -> None:
    """13.3-12 ParseHierarchicalRuleMixedSymptoms [A]; name and window defaults [I]."""
    config = parse(
        """
correlation:
  enabled: true
  patterns:
    sensor_errors:
      codes: ["SENSOR_*"]
  rules:
    - id: mixed_test
      mode: hierarchical
      root_cause: {codes: ["ESTOP_001"]}
      symptoms:
        - pattern: sensor_errors
        - codes: ["MOTOR_*", "DRIVE_*"]
"""
    )
    (rule,) = config.rules
    assert rule.symptom_pattern_ids == ("sensor_errors",)
    assert rule.inline_symptom_codes == ("MOTOR_*", "DRIVE_*")
    assert validate_config(config).valid is True
    assert (rule.name, rule.window_ms) == ("mixed_test", 500)


def test_p13_parse_auto_cluster_rule() -> None:
    """13.3-13 ParseAutoClusterRule [A]."""
    rule = only_rule(CFG_CLUSTER_YAML)
    assert (rule.id, rule.mode, rule.match_pattern_ids) == (
        "comm_storm",
        "auto_cluster",
        ("comm_errors",),
    )
    assert (rule.min_count, rule.window_ms, rule.show_as_single) == (3, 500, True)
    assert rule.representative is Representative.HIGHEST_SEVERITY


def test_p14_parse_multiple_rules() -> None:
    """13.3-14 ParseMultipleRules [A]; rule2 defaults and clean validation [I]."""
    config = parse(
        """
correlation:
  enabled: true
  default_window_ms: 500
  patterns:
    motor_errors: {codes: ["MOTOR_*"]}
    sensor_issues: {codes: ["SENSOR_*"]}
  rules:
    - id: rule1
      mode: hierarchical
      root_cause: {codes: ["ROOT1"]}
      symptoms: [{pattern: motor_errors}]
    - id: rule2
      mode: auto_cluster
      match: [{pattern: sensor_issues}]
      min_count: 2
"""
    )
    assert len(config.patterns) == 2
    assert [(r.id, r.mode) for r in config.rules] == [
        ("rule1", "hierarchical"),
        ("rule2", "auto_cluster"),
    ]
    rule2 = config.rules[1]
    assert (rule2.window_ms, rule2.representative, rule2.show_as_single) == (
        500,
        Representative.HIGHEST_SEVERITY,
        True,
    )
    result = validate_config(config)
    assert (result.errors, result.warnings) == ((), ())


def test_p15_parse_default_values() -> None:
    """13.3-15 ParseDefaultValues [A]; name and the no-symptoms warning [I]."""
    config = parse(
        """
correlation:
  enabled: true
  rules:
    - id: minimal_rule
      root_cause:
        codes: ["TEST"]
"""
    )
    (rule,) = config.rules
    assert rule.mode == "hierarchical"
    assert (rule.window_ms, rule.mute_symptoms, rule.auto_clear_with_root) == (500, True, True)
    assert rule.name == "minimal_rule"
    result = validate_config(config)
    assert result.valid is True
    assert result.warnings == ("Hierarchical rule 'minimal_rule' has no symptoms defined",)


def _one_rule(symptom_pattern: str, extra: str = "") -> str:
    return f"""
correlation:
  enabled: true
  patterns:
    motor_errors:
      codes: ["MOTOR_*"]
  rules:
    - id: test_rule
      root_cause:
        codes: ["ESTOP"]
      symptoms:
        - pattern: {symptom_pattern}
{extra}"""


def test_p16_validate_valid_config() -> None:
    """13.3-16 ValidateValidConfig [A]; no warnings [I]."""
    result = validate_config(parse(_one_rule("motor_errors")))
    assert result.valid is True
    assert result.errors == ()
    assert result.warnings == ()


def test_p17_validate_unknown_pattern_reference() -> None:
    """13.3-17 ValidateUnknownPatternReference [A]; exact text [I]."""
    result = validate_config(parse(_one_rule("nonexistent_pattern")))
    assert result.valid is False
    assert len(result.errors) == 1
    assert "nonexistent_pattern" in result.errors[0]
    assert result.errors == ("Rule 'test_rule' references unknown pattern: nonexistent_pattern",)


def test_p18_validate_duplicate_rule_id() -> None:
    """13.3-18 ValidateDuplicateRuleId [A]; exact errors and warnings [I]."""
    result = validate_config(
        parse(
            """
correlation:
  enabled: true
  rules:
    - id: same_id
      root_cause: {codes: ["A"]}
    - id: same_id
      root_cause: {codes: ["B"]}
"""
        )
    )
    assert result.valid is False
    assert result.errors
    assert result.errors == ("Duplicate rule ID: same_id",)
    assert result.warnings == ("Hierarchical rule 'same_id' has no symptoms defined",) * 2


def test_p19_validate_hierarchical_no_root_cause() -> None:
    """13.3-19 ValidateHierarchicalNoRootCause [A]; exact messages [I]."""
    result = validate_config(
        parse(ON + "  rules:\n    - id: broken_rule\n      mode: hierarchical\n")
    )
    assert result.valid is False
    assert result.errors == ("Hierarchical rule 'broken_rule' has no root_cause codes",)
    assert result.warnings == ("Hierarchical rule 'broken_rule' has no symptoms defined",)


def _windowed(window: str) -> str:
    return (
        "correlation:\n  enabled: true\n  rules:\n    - id: test_rule\n"
        f"      root_cause: {{codes: [A]}}\n      window_ms: {window}\n"
    )


def test_p20_validate_zero_window_ms() -> None:
    """13.3-20 ValidateZeroWindowMs [A]; exact messages [I]."""
    result = validate_config(parse(_windowed("0")))
    assert result.valid is False
    assert result.errors == ("Rule 'test_rule' has window_ms=0",)
    assert result.warnings == ("Hierarchical rule 'test_rule' has no symptoms defined",)


def test_p21_validate_warning_long_window() -> None:
    """13.3-21 ValidateWarningLongWindow: valid with warnings [A]; exact list [I]."""
    result = validate_config(parse(_windowed("120000")))
    assert result.valid is True
    assert result.warnings
    assert result.warnings == (
        "Hierarchical rule 'test_rule' has no symptoms defined",
        "Rule 'test_rule' has window_ms > 60s, which may be too long",
    )


def test_p22_validate_disabled_config_skips_validation() -> None:
    """13.3-22 ValidateDisabledConfigSkipsValidation [A]."""
    result = validate_config(parse("correlation:\n  enabled: false\n  rules: [{id: ''}]\n"))
    assert (result.valid, result.errors, result.warnings) == (True, (), ())


FULL_EXAMPLE = """
correlation:
  enabled: true
  default_window_ms: 500
  patterns:
    motor_errors: {codes: ["MOTOR_COMM_*", "MOTOR_TIMEOUT_*"]}
    sensor_issues: {codes: ["SENSOR_*_TIMEOUT", "SENSOR_*_DISCONNECT"]}
    drive_faults: {codes: ["DRIVE_*"]}
  rules:
    - {id: estop_cascade, name: "E-Stop Cascade", mode: hierarchical,
       root_cause: {codes: ["ESTOP_001"]},
       symptoms: [{pattern: motor_errors}, {pattern: drive_faults}], window_ms: 1000,
       mute_symptoms: true, auto_clear_with_root: true}
    - {id: ota_expected, name: "OTA Expected Timeouts", mode: hierarchical,
       root_cause: {codes: ["OTA_UPDATE_ACTIVE"]},
       symptoms: [{pattern: motor_errors}, {pattern: sensor_issues}], window_ms: 5000,
       mute_symptoms: true}
    - {id: comm_storm, name: "Communication Storm", mode: auto_cluster,
       match: [{pattern: motor_errors}, {pattern: sensor_issues}],
       min_count: 3, window_ms: 500, show_as_single: true, representative: highest_severity}
"""


def test_p23_parse_full_example_config() -> None:
    """13.3-23 ParseFullExampleConfig [A]; default auto_clear and pattern order [I]."""
    config = parse(FULL_EXAMPLE)
    assert config.enabled is True
    assert config.default_window_ms == 500
    assert len(config.patterns) == 3
    assert len(config.rules) == 3
    assert validate_config(config).valid is True
    assert config.rules[1].id == "ota_expected"
    assert config.rules[1].auto_clear_with_root is True
    assert list(config.patterns) == ["drive_faults", "motor_errors", "sensor_issues"]


# -- §13.1 shared configs --------------------------------------------------------------------

CFG_HIER_YAML = """
correlation:
  enabled: true
  default_window_ms: 500
  patterns:
    motor_errors: {codes: ["MOTOR_COMM_*", "MOTOR_TIMEOUT_*"]}
    drive_faults: {codes: ["DRIVE_*"]}
  rules:
    - id: estop_cascade
      name: "E-Stop Cascade"
      mode: hierarchical
      root_cause: {codes: ["ESTOP_001"]}
      symptoms: [{pattern: motor_errors}, {pattern: drive_faults}]
      window_ms: 1000
      mute_symptoms: true
      auto_clear_with_root: true
"""
CFG_CLUSTER_YAML = """
correlation:
  enabled: true
  patterns:
    comm_errors: {codes: ["*_COMM_*", "*_TIMEOUT"]}
  rules:
    - id: comm_storm
      name: "Communication Storm"
      mode: auto_cluster
      match: [{pattern: comm_errors}]
      min_count: 3
      window_ms: 500
      show_as_single: true
      representative: highest_severity
"""
CFG_MIXED_YAML = """
correlation:
  enabled: true
  patterns:
    motor_errors: {codes: ["MOTOR_*"]}
    sensor_errors: {codes: ["SENSOR_*"]}
  rules:
    - id: estop_rule
      mode: hierarchical
      root_cause: {codes: ["ESTOP_001"]}
      symptoms: [{pattern: motor_errors}]
      window_ms: 500
      mute_symptoms: true
      auto_clear_with_root: true
    - id: sensor_cluster
      mode: auto_cluster
      match: [{pattern: sensor_errors}]
      min_count: 2
      window_ms: 500
      representative: first
"""
CFG_ERR_FIRST3_YAML = """
correlation:
  enabled: true
  patterns:
    errors: {codes: ["*_ERROR"]}
  rules:
    - id: test_cluster
      mode: auto_cluster
      match: [{pattern: errors}]
      min_count: 3
      window_ms: 500
      show_as_single: true
      representative: first
"""
CFG_INTEGRATION_YAML = """
correlation:
  enabled: true
  default_window_ms: 500
  patterns:
    motor_errors: {codes: ["MOTOR_COMM_*", "MOTOR_TIMEOUT_*"]}
    drive_faults: {codes: ["DRIVE_*"]}
    sensor_errors: {codes: ["SENSOR_*"]}
  rules:
    - id: estop_cascade
      name: "E-Stop Cascade"
      mode: hierarchical
      root_cause: {codes: ["ESTOP_001"]}
      symptoms: [{pattern: motor_errors}, {pattern: drive_faults}]
      window_ms: 2000
      mute_symptoms: true
      auto_clear_with_root: true
    - id: sensor_storm
      name: "Sensor Storm"
      mode: auto_cluster
      match: [{pattern: sensor_errors}]
      min_count: 2
      window_ms: 2000
      show_as_single: true
      representative: highest_severity
"""


@pytest.mark.parametrize(
    "text",
    [
        CFG_HIER_YAML,
        CFG_CLUSTER_YAML,
        CFG_MIXED_YAML,
        CFG_ERR_FIRST3_YAML,
        CFG_ERR_FIRST3_YAML.replace("representative: first", "representative: most_recent"),
        CFG_INTEGRATION_YAML,
    ],
    ids=["hier", "cluster", "mixed", "err_first3", "err_recent3", "integration"],
)
def test_shared_configs_validate_cleanly(text: str) -> None:
    """§13.1 [I]: every shared config validates with no errors and no warnings."""
    result = validate_config(parse(text))
    assert (result.errors, result.warnings) == ((), ())


def test_cfg_mixed_parses_to_the_expected_values() -> None:
    """§13.1 CFG_MIXED: name defaults to the id; show_as_single defaults to true."""
    assert parse(CFG_MIXED_YAML) == CorrelationConfig(
        enabled=True,
        default_window_ms=500,
        patterns={"motor_errors": ("MOTOR_*",), "sensor_errors": ("SENSOR_*",)},
        rules=(
            CorrelationRule(
                id="estop_rule",
                name="estop_rule",
                mode="hierarchical",
                window_ms=500,
                root_cause_codes=("ESTOP_001",),
                symptom_pattern_ids=("motor_errors",),
            ),
            CorrelationRule(
                id="sensor_cluster",
                name="sensor_cluster",
                mode="auto_cluster",
                window_ms=500,
                match_pattern_ids=("sensor_errors",),
                min_count=2,
                show_as_single=True,
                representative=Representative.FIRST,
            ),
        ),
    )


# -- §2 schema: documents and sections ------------------------------------------------------

ON = "correlation:\n  enabled: true\n"
RULE = ON + "  rules:\n    - id: r\n"


@pytest.mark.parametrize(
    "text",
    [
        "",
        "# comments only\n",
        "other: 1\n",
        "correlation:\n",
        "correlation: ~\n",
        "- a\n- b\n",
        "correlation: [enabled, true]\n",
        "correlation:\n  enabled: [true]\n",
        "correlation:\n  enabled: ~\n",
        "correlation:\n  enabled: off\n  default_window_ms: garbage\n  rules: 5\n",
    ],
)
def test_disabled_documents(text: str) -> None:
    """§2: no section, null, sequences, non-scalar or false `enabled` → disabled, no error.

    Once `enabled` is false nothing else is read, even garbage.
    """
    assert parse(text) == CorrelationConfig(enabled=False)


@pytest.mark.parametrize(
    "text",
    [
        "hello\n",  # top-level scalar: BadSubscript
        "correlation: true\n",  # scalar section: BadSubscript
        "correlation:\n  enabled: 1\n",  # `1` is not a bool
        "correlation:\n  enabled: tRUE\n",
        "correlation: {enabled: true\n",  # syntax error
        ON + "  rules:\n    - just_a_string\n",  # a non-map rule item
    ],
)
def test_documents_that_throw(text: str) -> None:
    """§2: these make yaml-cpp throw; the whole config fails to load."""
    with pytest.raises(YamlCppError):
        parse(text)


def test_duplicate_keys_first_wins_for_lookups_last_wins_for_patterns() -> None:
    """§2: duplicate pattern ids: the last wins and no duplicate error can fire.

    A looked-up key (here `enabled`, `id`) finds the first of its duplicates, as yaml-cpp does.
    """
    config = parse(ON + "  patterns:\n    p: {codes: [X]}\n    p: {codes: [Y]}\n")
    assert config.patterns == {"p": ("Y",)}
    assert validate_config(config).errors == ()
    assert parse("correlation:\n  enabled: false\n  enabled: true\n").enabled is False
    rule = only_rule(RULE + "      id: other\n      root_cause: {codes: [A]}\n")
    assert rule.id == "r"


def test_default_window_ms() -> None:
    """§2: default_window_ms is a uint32 inherited by rules without window_ms."""
    config = parse(
        ON + "  default_window_ms: 010\n  rules:\n    - {id: a}\n    - {id: b, window_ms: 0x20}\n"
    )
    assert config.default_window_ms == 8
    assert [r.window_ms for r in config.rules] == [8, 32]
    assert parse(ON + "  default_window_ms: ~\n").default_window_ms == 500
    with pytest.raises(YamlCppError):
        parse(ON + "  default_window_ms: -5\n")


def test_default_window_ms_zero_is_inherited_as_an_error() -> None:
    """§3: default_window_ms itself is not validated; a rule inheriting 0 is an error."""
    result = validate_config(parse(ON + "  default_window_ms: 0\n  rules:\n    - {id: r}\n"))
    assert "Rule 'r' has window_ms=0" in result.errors


def test_patterns_codes_shapes() -> None:
    """§2: non-map entries or non-sequence codes give no codes; items are coerced or skipped."""
    config = parse(
        ON
        + "  patterns:\n"
        + "    a: [A]\n"
        + "    b: ~\n"
        + "    c: {codes: A}\n"
        + "    d: {codes: [123, 4.5, true, ~, '~', [x], {y: 1}, null, '']}\n"
        + "    e:\n"
    )
    assert config.patterns == {
        "a": (),
        "b": (),
        "c": (),
        "d": ("123", "4.5", "true", "~", ""),
        "e": (),
    }
    assert validate_config(config).warnings == (
        *(f"Pattern '{p}' has no codes defined" for p in ("a", "b", "c", "e")),
        "Correlation is enabled but no rules are defined",
    )


def test_patterns_ignored_unless_a_map_and_sorted_by_id() -> None:
    """§2: `patterns` as a sequence is ignored; ids iterate in ascending (byte) order."""
    assert parse(ON + "  patterns: [a, b]\n").patterns == {}
    config = parse(ON + "  patterns:\n    zeta: {codes: [Z]}\n    Alpha: {codes: [A]}\n")
    assert list(config.patterns) == ["Alpha", "zeta"]
    assert parse(ON + "  patterns:\n    ~: {codes: [X]}\n").patterns == {"null": ("X",)}


def test_pattern_entry_that_is_a_scalar_throws() -> None:
    """`p: A`: reading `codes` of a scalar is a BadSubscript in yaml-cpp."""
    with pytest.raises(YamlCppError):
        parse(ON + "  patterns:\n    p: A\n")


def test_rules_ignored_unless_a_sequence() -> None:
    """§2: `rules` given as a map is ignored."""
    assert parse(ON + "  rules: {id: r}\n").rules == ()


@pytest.mark.parametrize(
    ("item", "expected_id"), [("~", ""), ("[a, b]", ""), ("{id: 42}", "42"), ("{id: ~}", "")]
)
def test_rule_ids(item: str, expected_id: str) -> None:
    """§2: id is a scalar taken as a string; null, absent or non-scalar → ""."""
    rule = only_rule(ON + f"  rules:\n    - {item}\n")
    assert (rule.id, rule.name) == (expected_id, expected_id)


def test_empty_ids_are_errors_and_a_second_one_is_a_duplicate() -> None:
    """§3.2: `Rule missing 'id' field`, and `Duplicate rule ID: ` with a trailing space."""
    result = validate_config(
        parse(ON + "  rules:\n    - {root_cause: {codes: [A]}}\n    - {root_cause: {codes: [B]}}\n")
    )
    assert result.errors == (
        "Rule missing 'id' field",
        "Duplicate rule ID: ",
        "Rule missing 'id' field",
    )


def test_name_defaults_to_id() -> None:
    """§2: a null or absent name gives the id."""
    assert only_rule(RULE + "      name: ~\n").name == "r"
    assert only_rule(RULE + "      name: Nice Name\n").name == "Nice Name"


@pytest.mark.parametrize(
    ("mode", "expected"),
    [("~", "hierarchical"), ("AutoCluster", "auto_cluster"), ("CLUSTER", "auto_cluster")],
)
def test_mode_values(mode: str, expected: str) -> None:
    """§2: mode is case-insensitive; null gives the default."""
    assert only_rule(RULE + f"      mode: {mode}\n").mode == expected


@pytest.mark.parametrize(
    ("mode", "message"),
    [
        (
            "auto-cluster",
            "Invalid correlation mode: auto-cluster. Valid values: hierarchical, auto_cluster",
        ),
        ("''", "Invalid correlation mode: . Valid values: hierarchical, auto_cluster"),
    ],
)
def test_invalid_mode_throws_invalid_argument(mode: str, message: str) -> None:
    """§2: anything else throws invalid_argument with upstream's exact text."""
    with pytest.raises(ValueError, match="Invalid correlation mode") as caught:
        parse(RULE + f"      mode: {mode}\n")
    assert str(caught.value) == message
    assert isinstance(caught.value, InvalidArgumentError)
    assert caught.value.line == 5


def test_invalid_representative_only_matters_for_cluster_rules() -> None:
    """§2: `representative: bogus` is harmless in a hierarchical rule, fatal in a cluster rule."""
    rule = only_rule(RULE + "      representative: bogus\n      root_cause: {codes: [A]}\n")
    assert rule.representative is Representative.HIGHEST_SEVERITY
    with pytest.raises(ValueError, match="Invalid representative") as caught:
        parse(RULE + "      mode: cluster\n      representative: bogus\n")
    assert str(caught.value) == (
        "Invalid representative: bogus. Valid values: first, most_recent, highest_severity"
    )


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("Recent", Representative.MOST_RECENT),
        ("mostrecent", Representative.MOST_RECENT),
        ("First", Representative.FIRST),
        ("HighestSeverity", Representative.HIGHEST_SEVERITY),
        ("~", Representative.HIGHEST_SEVERITY),
    ],
)
def test_representative_values(text: str, expected: Representative) -> None:
    """§2: representative spellings, case-insensitive; null gives the default."""
    rule = only_rule(RULE + f"      mode: cluster\n      representative: {text}\n")
    assert rule.representative is expected


@pytest.mark.parametrize(
    ("root_cause", "codes"),
    [
        ("[A]", ()),
        ("{codes: A}", ()),
        ("~", ()),
        ("{codes: ~}", ()),
        ("{codes: ['']}", ("",)),
        ("{codes: [A, ~, 7]}", ("A", "7")),
    ],
)
def test_root_cause_shapes(root_cause: str, codes: tuple[str, ...]) -> None:
    """§2: only `root_cause: {codes: [..]}` gives codes; `""` is accepted as a code."""
    assert only_rule(RULE + f"      root_cause: {root_cause}\n").root_cause_codes == codes


@pytest.mark.parametrize("root_cause", ["A", "'A'"])
def test_scalar_root_cause_throws(root_cause: str) -> None:
    """§2: `root_cause: A` throws (yaml-cpp BadSubscript)."""
    with pytest.raises(YamlCppError):
        parse(RULE + f"      root_cause: {root_cause}\n")


def test_cluster_rules_ignore_hierarchical_keys_and_vice_versa() -> None:
    """§2: each mode reads only its own keys, so invalid values of the other mode are harmless."""
    cluster = only_rule(RULE + "      mode: cluster\n      root_cause: A\n      mute_symptoms: x\n")
    assert cluster.root_cause_codes == ()
    assert cluster.mute_symptoms is True
    hier = only_rule(
        RULE + "      min_count: x\n      show_as_single: x\n      match: 5\n"
        "      root_cause: {codes: [A]}\n"
    )
    assert (hier.min_count, hier.show_as_single, hier.match_pattern_ids) == (3, True, ())


def test_symptom_item_shapes() -> None:
    """§2: `pattern` wins over `codes`; non-maps and scalar `codes` are ignored."""
    rule = only_rule(
        RULE
        + "      root_cause: {codes: [A]}\n"
        + "      symptoms:\n"
        + "        - {pattern: p, codes: [X]}\n"
        + "        - {codes: [Y, ~, [z]]}\n"
        + "        - {codes: Q}\n"
        + "        - just_a_string\n"
        + "        - [x]\n"
        + "        - {other: 1}\n"
    )
    assert rule.symptom_pattern_ids == ("p",)
    assert rule.inline_symptom_codes == ("Y",)
    assert only_rule(RULE + "      symptoms: {pattern: p}\n").symptom_pattern_ids == ()


def test_match_takes_only_pattern_items() -> None:
    """§2: inline `codes:` items are ignored in `match`."""
    rule = only_rule(
        RULE
        + "      mode: auto_cluster\n"
        + "      match:\n"
        + "        - {pattern: p}\n"
        + "        - {codes: [X]}\n"
        + "        - str\n"
        + "        - {pattern: q, codes: [Y]}\n"
    )
    assert rule.match_pattern_ids == ("p", "q")
    assert rule.inline_symptom_codes == ()


@pytest.mark.parametrize(
    ("fields", "mute", "auto_clear"),
    [
        ("mute_symptoms: 'off'\n      auto_clear_with_root: N", False, False),
        ("mute_symptoms: ~\n      auto_clear_with_root: [no]", True, True),
        ("mute_symptoms: YES\n      auto_clear_with_root: Off", True, False),
    ],
)
def test_bool_fields(fields: str, mute: bool, auto_clear: bool) -> None:
    """§2: bools in yaml-cpp spellings; null or non-scalar gives the default."""
    rule = only_rule(RULE + f"      root_cause: {{codes: [A]}}\n      {fields}\n")
    assert (rule.mute_symptoms, rule.auto_clear_with_root) == (mute, auto_clear)


@pytest.mark.parametrize(
    ("fields", "window", "min_count"),
    [
        ("window_ms: '750'\n      min_count: 00012", 750, 10),
        ("window_ms: 0x10\n      min_count: +2", 16, 2),
        ("window_ms: ~\n      min_count: []", 500, 3),
        ("window_ms: 4294967295\n      min_count: 0", 4294967295, 0),
    ],
)
def test_uint32_fields(fields: str, window: int, min_count: int) -> None:
    """§2: uint32 fields read as yaml-cpp's stream parsing reads them."""
    rule = only_rule(RULE + f"      mode: cluster\n      {fields}\n")
    assert (rule.window_ms, rule.min_count) == (window, min_count)


@pytest.mark.parametrize("bad", ["-5", "-0", "1.5", "1e3", "12abc", "4294967296", "'  750'"])
def test_uint32_fields_that_throw(bad: str) -> None:
    """§2: negative, fractional, trailing junk, overflow or a leading space throw."""
    with pytest.raises(YamlCppError) as caught:
        parse(RULE + f"      window_ms: {bad}\n")
    assert caught.value.line == 5


@pytest.mark.parametrize("bad", ["1", "0", "t", "tRUE"])
def test_bool_fields_that_throw(bad: str) -> None:
    """§2: `1`, `0`, `t`, `tRUE` are not bools."""
    with pytest.raises(YamlCppError):
        parse(RULE + f"      root_cause: {{codes: [A]}}\n      mute_symptoms: {bad}\n")


# -- §3 validation details ------------------------------------------------------------------


def test_validation_order_and_texts() -> None:
    """§3: patterns by id first, then rules in file order with checks in upstream's order."""
    config = parse(
        ON
        + "  patterns:\n    z_empty: {codes: []}\n    a_empty: ~\n    ok: {codes: [X]}\n"
        + "  rules:\n"
        + "    - {id: h, root_cause: {codes: [A]}, symptoms: [{pattern: nope}], window_ms: 60000}\n"
        + "    - {id: c0, mode: cluster, match: [{pattern: gone}], min_count: 0,\n"
        + "       window_ms: 60001}\n"
        + "    - {id: c1, mode: cluster, min_count: 1, window_ms: 0}\n"
        + "    - {id: h0, root_cause: {codes: [A]}, symptoms: [{pattern: ok}], min_count: 0}\n"
    )
    result = validate_config(config)
    assert result.errors == (
        "Rule 'h' references unknown pattern: nope",
        "Rule 'c0' references unknown pattern: gone",
        "Rule 'c0' has min_count=0, must be at least 1",
        "Rule 'c1' has window_ms=0",
    )
    assert result.warnings == (
        "Pattern 'a_empty' has no codes defined",
        "Pattern 'z_empty' has no codes defined",
        "Rule 'c0' has window_ms > 60s, which may be too long",
        "Auto-cluster rule 'c1' has no match patterns defined",
        "Rule 'c1' has min_count < 2, which may cause false clusters",
    )


# -- load_correlation (§1.1) ----------------------------------------------------------------


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "correlation.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def test_load_missing_file(tmp_path: Path) -> None:
    """§1.1: a missing file → error, no engine."""
    path = tmp_path / "nope.yaml"
    loaded = load_correlation(path)
    assert loaded.config is None
    (message,) = loaded.warnings
    assert message.startswith(f"{path}: ")
    assert "not found" in message
    assert not path.exists()


def test_load_syntax_error(tmp_path: Path) -> None:
    """§1.1: a parse exception → `Failed to load correlation config: <what>`, no engine."""
    path = _write(tmp_path, "correlation:\n  enabled: true\n  rules: [\n")
    loaded = load_correlation(path)
    assert loaded.config is None
    (message,) = loaded.warnings
    assert message.startswith(f"{path}:")
    assert "Failed to load correlation config: " in message


def test_load_bad_conversion_names_its_line(tmp_path: Path) -> None:
    """§1.1: a bad scalar fails the load; the message carries path and line."""
    path = _write(tmp_path, RULE + "      window_ms: 1.5\n")
    loaded = load_correlation(path)
    assert loaded.config is None
    (message,) = loaded.warnings
    assert message.startswith(f"{path}:5: Failed to load correlation config: ")


def test_load_invalid_mode(tmp_path: Path) -> None:
    """§1.1: an invalid mode fails the load with upstream's exact invalid_argument text."""
    path = _write(tmp_path, RULE + "      mode: auto-cluster\n")
    loaded = load_correlation(path)
    assert loaded.config is None
    (message,) = loaded.warnings
    assert message.startswith(
        f"{path}:5: Failed to load correlation config: Invalid correlation mode: auto-cluster. "
        "Valid values: hierarchical, auto_cluster"
    )


@pytest.mark.parametrize("text", ["", "correlation:\n  enabled: false\n", "other: 1\n"])
def test_load_disabled(tmp_path: Path, text: str) -> None:
    """§1.1: enabled false (or no section) → an info note, no engine (and a top-level key
    upstream does not read is warned)."""
    path = _write(tmp_path, text)
    loaded = load_correlation(path)
    assert loaded.config is None
    *unknown, message = loaded.warnings
    assert message.startswith(f"{path}: ")
    assert "disabled" in message
    assert unknown == (
        [
            f"{path}:1: correlation file: unknown key 'other' (expected one of: correlation); "
            "upstream ignores it"
        ]
        if text.startswith("other")
        else []
    )


def test_load_valid_config(tmp_path: Path) -> None:
    """§1.1: a clean config gives the engine config and no messages."""
    path = _write(tmp_path, CFG_INTEGRATION_YAML)
    assert load_correlation(path) == CorrelationLoad(parse(CFG_INTEGRATION_YAML), ())


def test_load_keeps_the_engine_with_warnings(tmp_path: Path) -> None:
    """§1.1: each validation warning is listed; warnings alone keep the engine."""
    path = _write(tmp_path, _windowed("120000"))
    loaded = load_correlation(path)
    assert loaded.config == parse(_windowed("120000"))
    assert loaded.warnings == (
        f"{path}: Correlation config: Hierarchical rule 'test_rule' has no symptoms defined",
        f"{path}: Correlation config: Rule 'test_rule' has window_ms > 60s, which may be too long",
    )


def test_load_validation_errors_disable_correlation_loudly(tmp_path: Path) -> None:
    """§1.1: any error → each error listed, no engine, and a loud line saying so."""
    path = _write(tmp_path, _one_rule("nonexistent_pattern"))
    loaded = load_correlation(path)
    assert loaded.config is None
    assert loaded.warnings[0] == (
        f"{path}: Correlation config error: "
        "Rule 'test_rule' references unknown pattern: nonexistent_pattern"
    )
    assert len(loaded.warnings) == 2
    assert loaded.warnings[1].startswith(f"{path}: CORRELATION IS DISABLED FOR THIS RUN")


def test_load_lists_warnings_before_errors(tmp_path: Path) -> None:
    """§1.1: warnings are logged, then errors."""
    path = _write(tmp_path, _windowed("0"))
    loaded = load_correlation(path)
    assert loaded.config is None
    assert loaded.warnings[:2] == (
        f"{path}: Correlation config: Hierarchical rule 'test_rule' has no symptoms defined",
        f"{path}: Correlation config error: Rule 'test_rule' has window_ms=0",
    )
    assert "DISABLED" in loaded.warnings[2]


def test_load_opens_read_only_and_creates_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The loader only reads: every open is read-only; the folder and file are unchanged."""
    path = _write(tmp_path, CFG_HIER_YAML)
    before = (
        sorted(p.name for p in tmp_path.iterdir()),
        path.read_bytes(),
        path.stat().st_mtime_ns,
    )
    flags: list[int] = []
    real_open = os.open

    def spy(file: object, flag: int, *args: object, **kwargs: object) -> int:
        flags.append(flag)
        return real_open(file, flag, *args, **kwargs)  # type: ignore[arg-type]

    # The loader opens through medkit_replay.files (os.open, so that a FIFO cannot block it).
    monkeypatch.setattr(os, "open", spy)
    assert load_correlation(path).config is not None
    assert load_correlation(tmp_path / "missing.yaml").config is None
    monkeypatch.undo()
    assert flags
    assert all(f & os.O_ACCMODE == os.O_RDONLY and not f & os.O_CREAT for f in flags)
    after = (sorted(p.name for p in tmp_path.iterdir()), path.read_bytes(), path.stat().st_mtime_ns)
    assert after == before
