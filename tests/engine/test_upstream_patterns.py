"""Upstream's test_pattern_matcher.cpp, ported (correlation.md §13.2, all 15 tests plus [I] extras).

Wildcard `*` is the only special character; matching is anchored and case-sensitive (§4).
"""

from __future__ import annotations

import pytest

from medkit_replay.engine.correlation import PatternMatcher, matches_any, matches_wildcard

# (upstream test, code, pattern, expected)
WILDCARD_CASES: list[tuple[str, str, str, bool]] = [
    # 1 ExactMatch [A]
    ("ExactMatch", "MOTOR_COMM_FL", "MOTOR_COMM_FL", True),
    ("ExactMatch", "MOTOR_COMM_FL", "MOTOR_COMM_FR", False),
    ("ExactMatch", "MOTOR_COMM_FL", "MOTOR_COMM", False),
    ("ExactMatch", "MOTOR_COMM", "MOTOR_COMM_FL", False),
    # 2 WildcardSuffix [A]
    ("WildcardSuffix", "MOTOR_COMM_FL", "MOTOR_COMM_*", True),
    ("WildcardSuffix", "MOTOR_COMM_FR", "MOTOR_COMM_*", True),
    ("WildcardSuffix", "MOTOR_COMM_REAR_LEFT", "MOTOR_COMM_*", True),
    ("WildcardSuffix", "SENSOR_COMM_FL", "MOTOR_COMM_*", False),
    ("WildcardSuffix", "MOTOR_TIMEOUT", "MOTOR_COMM_*", False),
    # 3 WildcardPrefix [A]
    ("WildcardPrefix", "MOTOR_COMM_FL", "*_COMM_FL", True),
    ("WildcardPrefix", "SENSOR_COMM_FL", "*_COMM_FL", True),
    ("WildcardPrefix", "FRONT_MOTOR_COMM_FL", "*_COMM_FL", True),
    ("WildcardPrefix", "MOTOR_COMM_FR", "*_COMM_FL", False),
    ("WildcardPrefix", "MOTOR_TIMEOUT_FL", "*_COMM_FL", False),
    # 4 WildcardMiddle [A]
    ("WildcardMiddle", "MOTOR_COMM_FL", "MOTOR_*_FL", True),
    ("WildcardMiddle", "MOTOR_TIMEOUT_FL", "MOTOR_*_FL", True),
    ("WildcardMiddle", "MOTOR_DRIVE_COMM_FL", "MOTOR_*_FL", True),
    ("WildcardMiddle", "MOTOR_COMM_FR", "MOTOR_*_FL", False),
    ("WildcardMiddle", "SENSOR_COMM_FL", "MOTOR_*_FL", False),
    # 5 MultipleWildcards [A]
    ("MultipleWildcards", "MOTOR_COMM_FL", "*_COMM_*", True),
    ("MultipleWildcards", "SENSOR_COMM_REAR", "*_COMM_*", True),
    ("MultipleWildcards", "A_COMM_B", "*_COMM_*", True),
    ("MultipleWildcards", "MOTOR_TIMEOUT_FL", "*_COMM_*", False),
    # 6 WildcardOnly [A]
    ("WildcardOnly", "ANYTHING", "*", True),
    ("WildcardOnly", "", "*", True),
    ("WildcardOnly", "MOTOR_COMM_FL", "*", True),
    # 7 WildcardEdgeCases [A]
    ("WildcardEdgeCases", "MOTOR", "", False),
    ("WildcardEdgeCases", "", "", True),
    ("WildcardEdgeCases", "MOTOR_COMM_FL", "MOTOR**FL", True),
    ("WildcardEdgeCases", "ABC", "***", True),
    # 8 SpecialRegexCharacters [A] (no `*`, so plain equality)
    ("SpecialRegexCharacters", "MOTOR.COMM", "MOTOR.COMM", True),
    ("SpecialRegexCharacters", "MOTORXCOMM", "MOTOR.COMM", False),
    ("SpecialRegexCharacters", "MOTOR[1]", "MOTOR[1]", True),
    ("SpecialRegexCharacters", "MOTOR+COMM", "MOTOR+COMM", True),
    ("SpecialRegexCharacters", "MOTOR?COMM", "MOTOR?COMM", True),
    # 8 SpecialRegexCharacters, extra cases with a wildcard [I]
    ("SpecialRegexCharacters[I]", "MOTOR.COMM_X", "MOTOR.COMM_*", True),
    ("SpecialRegexCharacters[I]", "MOTORXCOMM_X", "MOTOR.COMM_*", False),
    ("SpecialRegexCharacters[I]", "A?B", "A?*", True),
    ("SpecialRegexCharacters[I]", "AXB", "A?*", False),
    ("SpecialRegexCharacters[I]", "A[1]x", "A[1]*", True),
    ("SpecialRegexCharacters[I]", "A1x", "A[1]*", False),
    ("SpecialRegexCharacters[I]", "X(Y)|Z", "*(Y)|*", True),
    ("SpecialRegexCharacters[I]", "A^B$", "A^*$", True),
    ("SpecialRegexCharacters[I]", "A\\B", "A\\*", True),
    ("SpecialRegexCharacters[I]", "AB", "A\\*", False),
    ("SpecialRegexCharacters[I]", "a_comm_x", "A_*", False),
    ("SpecialRegexCharacters[I]", "A_", "A_*", True),
    ("SpecialRegexCharacters[I]", "A", "A_*", False),
    ("SpecialRegexCharacters[I]", "", "**", True),
    ("SpecialRegexCharacters[I]", "ab", "*a*b*", True),
    ("SpecialRegexCharacters[I]", "ba", "*a*b*", False),
]


@pytest.mark.parametrize(
    ("test", "code", "pattern", "expected"),
    WILDCARD_CASES,
    ids=[f"{t}-{c!r}~{p!r}" for t, c, p, _ in WILDCARD_CASES],
)
def test_matches_wildcard(test: str, code: str, pattern: str, expected: bool) -> None:
    """13.2 tests 1-8: the static matches_wildcard."""
    assert matches_wildcard(code, pattern) is expected, test


def test_star_does_not_cross_line_breaks() -> None:
    """§4 [I]: `*` is std::regex `.*`, which stops at \\n and \\r."""
    assert matches_wildcard("A\nB", "A*") is False
    assert matches_wildcard("A\rB", "A*B") is False
    assert matches_wildcard("A\tB", "A*B") is True


def test_matches_pattern_by_id() -> None:
    """13.2 test 9 MatchesPatternById [A]."""
    matcher = PatternMatcher(
        {"motor_errors": ("MOTOR_COMM_*", "MOTOR_TIMEOUT_*"), "sensor_issues": ("SENSOR_*",)}
    )
    assert matcher.matches("MOTOR_COMM_FL", "motor_errors") is True
    assert matcher.matches("MOTOR_COMM_FR", "motor_errors") is True
    assert matcher.matches("MOTOR_TIMEOUT_DRIVE", "motor_errors") is True
    assert matcher.matches("SENSOR_COMM_FL", "motor_errors") is False
    assert matcher.matches("SENSOR_LIDAR", "sensor_issues") is True
    assert matcher.matches("SENSOR_IMU_TIMEOUT", "sensor_issues") is True
    assert matcher.matches("MOTOR_COMM_FL", "sensor_issues") is False
    assert matcher.matches("MOTOR_COMM_FL", "nonexistent") is False


def test_matches_any_from_list() -> None:
    """13.2 test 10 MatchesAnyFromList [A]."""
    patterns = ["MOTOR_COMM_*", "DRIVE_*", "ESTOP_001"]
    assert matches_any("MOTOR_COMM_FL", patterns) is True
    assert matches_any("DRIVE_FAULT", patterns) is True
    assert matches_any("ESTOP_001", patterns) is True
    assert matches_any("SENSOR_TIMEOUT", patterns) is False
    assert matches_any("ESTOP_002", patterns) is False


def test_find_matching_patterns() -> None:
    """13.2 test 11 FindMatchingPatterns: two ids [A], in ascending id order [I]."""
    matcher = PatternMatcher(
        {
            "motor_errors": ("MOTOR_*",),
            "comm_errors": ("*_COMM_*",),
            "timeout_errors": ("*_TIMEOUT",),
        }
    )
    found = matcher.find_matching_patterns("MOTOR_COMM_FL")
    assert len(found) == 2
    assert set(found) == {"motor_errors", "comm_errors"}
    assert found == ["comm_errors", "motor_errors"]
    assert matcher.find_matching_patterns("SENSOR_TIMEOUT") == ["timeout_errors"]
    assert matcher.find_matching_patterns("UNKNOWN_ERROR") == []


def test_empty_patterns() -> None:
    """13.2 test 12 EmptyPatterns [A]."""
    matcher = PatternMatcher({})
    assert matcher.matches("MOTOR_COMM_FL", "any_pattern") is False
    assert matcher.find_matching_patterns("MOTOR_COMM_FL") == []


def test_pattern_with_no_codes() -> None:
    """13.2 test 13 PatternWithNoCodes [A]."""
    matcher = PatternMatcher({"empty_pattern": ()})
    assert matcher.matches("MOTOR_COMM_FL", "empty_pattern") is False


def test_exact_match_performance() -> None:
    """13.2 test 14 ExactMatchPerformance [A] (the lookup results; timing is not ported)."""
    matcher = PatternMatcher(
        {"exact": ("MOTOR_COMM_FL", "MOTOR_COMM_FR", "MOTOR_COMM_RL", "MOTOR_COMM_RR")}
    )
    assert matcher.matches("MOTOR_COMM_FL", "exact") is True
    assert matcher.matches("MOTOR_COMM_FR", "exact") is True
    assert matcher.matches("MOTOR_COMM_FRONT", "exact") is False


def test_mixed_exact_and_wildcard() -> None:
    """13.2 test 15 MixedExactAndWildcard [A]."""
    matcher = PatternMatcher({"mixed": ("ESTOP_001", "MOTOR_*", "SENSOR_LIDAR")})
    assert matcher.matches("ESTOP_001", "mixed") is True
    assert matcher.matches("MOTOR_COMM", "mixed") is True
    assert matcher.matches("SENSOR_LIDAR", "mixed") is True
    assert matcher.matches("ESTOP_002", "mixed") is False
    assert matcher.matches("SENSOR_IMU", "mixed") is False
