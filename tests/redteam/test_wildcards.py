"""Red team: wildcard patterns match in linear time, exactly as the regexes they replace.

The old regex translations are kept here as oracles for hypothesis; the CLI runs use limits.
"""

from __future__ import annotations

import json
import re
from typing import TYPE_CHECKING

from hypothesis import example, given, settings, strategies as st

from medkit_replay.checks.budget import Pattern
from medkit_replay.engine.correlation.patterns import matches_wildcard
from medkit_replay.wildcards import compile_wildcard
from tests.redteam.support import run_limited

if TYPE_CHECKING:
    from pathlib import Path

BOMB = "*A" * 12 + "*Z"
LONG_CODE = "A" * 100
# Small alphabets make coincidences (and so every branch of the matcher) likely.
CODE_CHARS = "ab\n\r?.*[\\$é"
PATTERN_CHARS = CODE_CHARS + "***"


def correlation_oracle(code: str, pattern: str) -> bool:
    """The correlation matcher as it was: `*` → `[^\\n\\r]*` in a backtracking regex."""
    if "*" not in pattern:
        return code == pattern
    regex = "[^\\n\\r]*".join(re.escape(piece) for piece in pattern.split("*"))
    return re.fullmatch(regex, code) is not None


def budget_oracle(code: str, glob: str) -> bool:
    """The budget glob as it was: `*` → `.*`, `?` → `.`, DOTALL, whole code."""
    parts = (".*" if c == "*" else "." if c == "?" else re.escape(c) for c in glob)
    return re.compile("".join(parts), re.DOTALL).fullmatch(code) is not None


patterns = st.text(alphabet=PATTERN_CHARS, max_size=9)
codes = st.text(alphabet=CODE_CHARS.replace("*", ""), max_size=12) | st.text(
    alphabet=CODE_CHARS, max_size=12
)


@settings(max_examples=3000, deadline=None)
@given(pattern=patterns, code=codes)
@example(pattern="*", code="a\nb")
@example(pattern="a*\n*b", code="a\nb")
@example(pattern="*a\na*", code="a\na\na")
@example(pattern="?*?", code="\n")
@example(pattern="**", code="")
def test_correlation_matcher_equals_the_regex(pattern: str, code: str) -> None:
    assert matches_wildcard(code, pattern) == correlation_oracle(code, pattern)


@settings(max_examples=3000, deadline=None)
@given(pattern=patterns.filter(bool), code=codes)
@example(pattern="?", code="\n")
@example(pattern="*?a?*", code="aaa")
@example(pattern="a?b*?", code="a\nb\r")
@example(pattern="*??*a", code="ba")
def test_budget_glob_equals_the_regex(pattern: str, code: str) -> None:
    assert Pattern.of(pattern).matches(code) == budget_oracle(code, pattern)


@settings(max_examples=1000, deadline=None)
@given(
    segments=st.lists(st.text(alphabet="ab?\n", max_size=4), min_size=1, max_size=6),
    code=st.text(alphabet="ab\n", max_size=30),
)
def test_longer_codes_and_many_stars(segments: list[str], code: str) -> None:
    pattern = "*".join(segments)
    assert compile_wildcard(pattern, one="?").matches(code) == budget_oracle(code, pattern)
    assert matches_wildcard(code, pattern) == correlation_oracle(code, pattern)


def test_the_pathological_pattern_returns_at_once() -> None:
    """Minutes with the backtracking regexes; one left-to-right pass now."""
    assert not matches_wildcard(LONG_CODE, BOMB)
    assert not Pattern.of(BOMB).matches(LONG_CODE)
    assert matches_wildcard(LONG_CODE + "Z", BOMB)
    assert Pattern.of(BOMB.replace("Z", "?")).matches(LONG_CODE)
    many = "*" + "*".join("A" * 3 for _ in range(2000)) + "*Z"
    assert not compile_wildcard(many).matches("A" * 50_000)


def _script(tmp_path: Path) -> Path:
    path = tmp_path / "run.jsonl"
    lines = [
        {
            "t_ns": 1_000_000_000 + k,
            "op": "report",
            "fault_code": LONG_CODE,
            "event_type": "FAILED",
            "severity": 2,
            "source_id": "/node",
        }
        for k in range(3)
    ]
    path.write_text("".join(json.dumps(line) + "\n" for line in lines))
    return path


def test_budget_glob_bomb_on_the_command_line(tmp_path: Path) -> None:
    budget = tmp_path / "budget.yaml"
    budget.write_text(f'version: 1\nrules:\n  - never_confirm: ["{BOMB}"]\n')
    outcome = run_limited(
        ["check", _script(tmp_path), "--budget", budget], cpu_seconds=60, timeout=120
    )
    assert outcome.status == 0, outcome.stderr[-2000:]
    assert "Traceback" not in outcome.stderr


def test_correlation_pattern_bomb_on_the_command_line(tmp_path: Path) -> None:
    correlation = tmp_path / "correlation.yaml"
    correlation.write_text(
        "correlation:\n  enabled: true\n  patterns:\n    bomb:\n"
        f'      codes: ["{BOMB}"]\n'
        "  rules:\n    - id: storm\n      mode: auto_cluster\n"
        "      match:\n        - pattern: bomb\n      min_count: 2\n      window_ms: 1000\n"
    )
    config = tmp_path / "params.yaml"
    config.write_text(
        "fault_manager:\n  ros__parameters:\n"
        "    correlation:\n      config_file: correlation.yaml\n"
    )
    report = tmp_path / "report.json"
    outcome = run_limited(
        ["analyze", _script(tmp_path), "--config", config, "--json", report, "--quiet"],
        cpu_seconds=60,
        timeout=120,
    )
    assert outcome.status == 0, outcome.stderr[-2000:]
    data = json.loads(report.read_text())
    assert len(data["reports"]) == 3
