"""Red team: parameter, correlation, entity-threshold and budget files under hostile input.

Alias bombs, self-reference, deep nesting, endless and special files, huge numbers: each is
refused with one line (or upstream's non-fatal warning), run under a memory limit.
"""

from __future__ import annotations

import json
import os
from typing import TYPE_CHECKING

import pytest

from tests.redteam.support import assert_one_line_error, run_limited

if TYPE_CHECKING:
    from pathlib import Path

    from tests.redteam.support import Outcome

SCRIPT = (
    '{"t_ns": 1000000000, "op": "report", "fault_code": "MOTOR_A", "event_type": "FAILED", '
    '"severity": 2, "source_id": "/motor"}\n'
    '{"t_ns": 9000000000, "op": "report", "fault_code": "MOTOR_A", "event_type": "PASSED", '
    '"source_id": "/motor"}\n'
)
HUGE = "7" * 5000


def laughs(indent: str, levels: int = 9) -> str:
    """A billion-laughs mapping: level k maps nine keys to level k-1 (9^9 leaves in < 1 KB)."""
    keys = "abcdefghi"
    lines = [f"{indent}l0: &l0 {{{', '.join(f'{k}: lol' for k in keys)}}}"]
    for level in range(1, levels):
        body = ", ".join(f"{k}: *l{level - 1}" for k in keys)
        lines.append(f"{indent}l{level}: &l{level} {{{body}}}")
    return "\n".join(lines) + "\n"


def params(*lines: str) -> str:
    return "fault_manager:\n  ros__parameters:\n" + "".join(f"    {line}\n" for line in lines)


@pytest.fixture
def script(tmp_path: Path) -> Path:
    path = tmp_path / "run.jsonl"
    path.write_text(SCRIPT)
    return path


def analyze(tmp_path: Path, script: Path, config: Path) -> Outcome:
    report = tmp_path / "report.json"
    argv: list[str | Path] = ["analyze", script, "--config", config, "--json", report, "--quiet"]
    return run_limited(argv, timeout=120)


def analyze_warnings(tmp_path: Path, script: Path, config: Path) -> list[str]:
    """Run analyze, expect success, return the report's warnings."""
    outcome = analyze(tmp_path, script, config)
    assert outcome.status == 0, outcome.stderr[-2000:]
    assert "Traceback" not in outcome.stderr
    warnings: list[str] = json.loads((tmp_path / "report.json").read_text())["warnings"]
    return warnings


def check(tmp_path: Path, script: Path, budget: Path | str) -> Outcome:
    return run_limited(["check", script, "--budget", budget], timeout=120)


# -- --config ---------------------------------------------------------------------------------


def test_billion_laughs_config(tmp_path: Path, script: Path) -> None:
    config = tmp_path / "params.yaml"
    config.write_text("fault_manager:\n  ros__parameters:\n" + laughs("    "))
    assert config.stat().st_size < 1024
    line = assert_one_line_error(analyze(tmp_path, script, config), str(config), "alias bomb")
    assert f"{config}:" in line


@pytest.mark.parametrize(
    "body",
    [
        "fault_manager: &a\n  ros__parameters:\n    x: *a\n",
        "fault_manager:\n  ros__parameters:\n    x: &a [1, *a]\n",
    ],
    ids=["map", "list"],
)
def test_self_referring_config(tmp_path: Path, script: Path, body: str) -> None:
    config = tmp_path / "params.yaml"
    config.write_text(body)
    assert_one_line_error(analyze(tmp_path, script, config), str(config), "refers to itself")


@pytest.mark.parametrize("depth", [100, 5000])
def test_deeply_nested_config(tmp_path: Path, script: Path, depth: int) -> None:
    config = tmp_path / "params.yaml"
    config.write_text(params("x: " + "[" * depth + "]" * depth))
    assert_one_line_error(analyze(tmp_path, script, config), f"{config}:3:", "nests deeper")


def test_special_and_oversized_config(tmp_path: Path, script: Path) -> None:
    fifo = tmp_path / "fifo.yaml"
    os.mkfifo(fifo)
    folder = tmp_path / "folder.yaml"
    folder.mkdir()
    big = tmp_path / "big.yaml"
    with big.open("wb") as out:  # sparse: 65 MiB of nothing
        out.truncate(65 * 1024 * 1024)
    for path, what in (
        ("/dev/zero", "character device"),
        (fifo, "FIFO"),
        (folder, "directory"),
        (big, "larger than"),
    ):
        outcome = run_limited(
            ["analyze", script, "--config", path, "--quiet"], timeout=60, cpu_seconds=30
        )
        assert_one_line_error(outcome, str(path), what)


def test_yaml_errors_are_one_line(tmp_path: Path, script: Path) -> None:
    config = tmp_path / "params.yaml"
    config.write_text(params("a: 1", "b: \x00"))
    line = assert_one_line_error(analyze(tmp_path, script, config), f"{config}:4:")
    assert "unacceptable character" in line
    config.write_bytes(params("a: 1").encode() + b"    b: \xff\n")
    assert_one_line_error(analyze(tmp_path, script, config), f"{config}:4:", "utf-8")


def test_huge_integer_parameter_is_a_config_error(tmp_path: Path, script: Path) -> None:
    # rcl: strtoll and strtod both overflow, so the value is a string; an int64 is declared.
    config = tmp_path / "params.yaml"
    config.write_text(params("confirmation_threshold: -3", f"healing_threshold: {HUGE}"))
    line = assert_one_line_error(
        analyze(tmp_path, script, config), f"{config}:4:", "healing_threshold", "integer"
    )
    assert len(line) < 300


def test_integer_past_int64_reads_as_a_double(tmp_path: Path, script: Path) -> None:
    # rcl: strtoll overflows (ERANGE), strtod reads it: a double, refused for an int64.
    config = tmp_path / "params.yaml"
    config.write_text(params("near_miss.max_per_fault: 99999999999999999999"))
    assert_one_line_error(
        analyze(tmp_path, script, config), f"{config}:3:", "max_per_fault", "got double"
    )


@pytest.mark.parametrize(
    ("lines", "conf", "heal"),
    [
        (("confirmation_threshold: 9223372036854775807",), -1, 3),
        (("healing_threshold: -9223372036854775808",), -1, 0),
        (("confirmation_threshold: -9223372036854775808", "healing_threshold: 2147483648"), -1, 3),
        (("confirmation_threshold: -4294967298",), -2, 3),
    ],
    ids=["conf-max", "heal-min", "both", "conf-wraps"],
)
def test_thresholds_past_int32_wrap_as_upstream_casts_them(
    tmp_path: Path, script: Path, lines: tuple[str, ...], conf: int, heal: int
) -> None:
    # Upstream: static_cast<int32_t> of the (negated) int64, then the sanitiser.
    config = tmp_path / "params.yaml"
    config.write_text(params("healing_enabled: true", *lines))
    warnings = analyze_warnings(tmp_path, script, config)
    assert any("outside int32" in w for w in warnings), warnings
    data = json.loads((tmp_path / "report.json").read_text())
    first = data["reports"][0]
    assert (first["confirmation_threshold"], first["healing_threshold"]) == (conf, heal)


@pytest.mark.parametrize("value", [".inf", "1e308", "1.0e10"])
def test_auto_confirm_beyond_int64_never_fires(tmp_path: Path, script: Path, value: str) -> None:
    config = tmp_path / "params.yaml"
    config.write_text(params("confirmation_threshold: -3", f"auto_confirm_after_sec: {value}"))
    warnings = analyze_warnings(tmp_path, script, config)
    assert any("can never fire" in w for w in warnings), warnings
    data = json.loads((tmp_path / "report.json").read_text())
    assert not [t for t in data["transitions"] if t["cause"] == "auto_confirm"]


def test_auto_confirm_nan_is_off(tmp_path: Path, script: Path) -> None:
    config = tmp_path / "params.yaml"
    config.write_text(params("auto_confirm_after_sec: .nan"))
    warnings = analyze_warnings(tmp_path, script, config)
    assert any("nan is not a number" in w for w in warnings), warnings


def test_auto_confirm_overflowing_double_is_a_string(tmp_path: Path, script: Path) -> None:
    # strtod overflows on 1e400 (ERANGE): rcl keeps the text, and a double is declared.
    config = tmp_path / "params.yaml"
    config.write_text(params("auto_confirm_after_sec: 1e400"))
    assert_one_line_error(
        analyze(tmp_path, script, config), f"{config}:3:", "auto_confirm_after_sec", "string"
    )


def test_infinite_cleanup_interval_is_a_config_error(tmp_path: Path, script: Path) -> None:
    (tmp_path / "correlation.yaml").write_text(
        "correlation:\n  enabled: true\n  patterns:\n    m: {codes: [MOTOR_*]}\n"
        "  rules:\n    - {id: r, mode: auto_cluster, match: [{pattern: m}], min_count: 2}\n"
    )
    config = tmp_path / "params.yaml"
    config.write_text(
        params("correlation:", "  config_file: correlation.yaml", "  cleanup_interval_sec: .inf")
    )
    assert_one_line_error(analyze(tmp_path, script, config), f"{config}:5:", "cleanup_interval_sec")


# -- the correlation and entity-threshold files (never fatal upstream) -------------------------


def referenced(tmp_path: Path, key: str, target: str) -> Path:
    config = tmp_path / "params.yaml"
    config.write_text(params(f"{key}:", f"  config_file: {target}"))
    return config


CORRELATION_HEAD = "correlation:\n  enabled: true\n"


@pytest.mark.parametrize(
    ("body", "needle"),
    [
        (CORRELATION_HEAD + laughs("  "), "alias bomb"),
        (CORRELATION_HEAD + "  rules: &r [*r]\n", "refers to itself"),
        (
            CORRELATION_HEAD + "  rules: " + "[" * 5000 + "]" * 5000 + "\n",
            ":3: Failed to load correlation config: the YAML nests deeper",
        ),
        (CORRELATION_HEAD + "  default_window_ms: \x00\n", "unacceptable character"),
        (CORRELATION_HEAD + f"  default_window_ms: {HUGE}\n", "bad conversion"),
    ],
    ids=["laughs", "self", "deep", "nul", "huge"],
)
def test_correlation_file_bombs_turn_correlation_off(
    tmp_path: Path, script: Path, body: str, needle: str
) -> None:
    (tmp_path / "correlation.yaml").write_text(body)
    config = referenced(tmp_path, "correlation", "correlation.yaml")
    warnings = analyze_warnings(tmp_path, script, config)
    hits = [w for w in warnings if "correlation.yaml" in w and needle in w]
    assert hits, warnings
    assert all("correlation is off for this run" in w for w in hits)
    assert all("\n" not in w for w in warnings)


@pytest.mark.parametrize(
    ("body", "needle"),
    [
        (laughs(""), "alias bomb"),
        ("/motor: &m {x: *m}\n", "refers to itself"),
        ("/motor: " + "{a: " * 5000 + "1" + "}" * 5000 + "\n", "nests deeper"),
        (f"/motor: {{confirmation_threshold: {HUGE}}}\n", "bad conversion"),
    ],
    ids=["laughs", "self", "deep", "huge"],
)
def test_entity_threshold_bombs_are_ignored(
    tmp_path: Path, script: Path, body: str, needle: str
) -> None:
    (tmp_path / "entities.yaml").write_text(body)
    config = referenced(tmp_path, "entity_thresholds", "entities.yaml")
    warnings = analyze_warnings(tmp_path, script, config)
    assert [w for w in warnings if "entities.yaml" in w and needle in w], warnings


def test_special_referenced_files_are_refused_unread(tmp_path: Path, script: Path) -> None:
    fifo = tmp_path / "fifo.yaml"
    os.mkfifo(fifo)
    (tmp_path / "folder.yaml").mkdir()
    with (tmp_path / "big.yaml").open("wb") as out:  # sparse, past the 16 MiB bound
        out.truncate(17 * 1024 * 1024)
    for target, what in (
        ("/dev/zero", "character device"),
        ("fifo.yaml", "FIFO"),
        ("folder.yaml", "directory"),
        ("big.yaml", "larger than"),
    ):
        for key in ("correlation", "entity_thresholds"):
            warnings = analyze_warnings(tmp_path, script, referenced(tmp_path, key, target))
            assert [w for w in warnings if target in w and what in w], (key, warnings)


# -- budgets ---------------------------------------------------------------------------------

BUDGET_HEAD = "version: 1\nrules:\n  - never_confirm: [ESTOP]\n"


@pytest.mark.parametrize(
    ("body", "needle"),
    [
        (BUDGET_HEAD + "x:\n" + laughs("  "), "alias bomb"),
        ("version: 1\nrules: &r [*r]\n", "refers to itself"),
        ("version: 1\nrules: " + "[" * 5000 + "]" * 5000 + "\n", ":2: the YAML nests deeper"),
        ("version: 1\nrules:\n  - max_occurrences: {'*': " + HUGE + "}\n", "too long"),
        (f"version: {HUGE}\nrules: []\n", "too long"),
        ("version: 1\nrules:\n  - max_confirmed_duration_sec: {'*': 1.0e+308}\n", "finite"),
        (
            "version: 1\nrules:\n  - max_confirmed_duration_sec: {'*': " + "9" * 400 + "}\n",
            "finite",
        ),
        ("version: 1\nrules:\n  - max_occurrences: {'*': -" + "1:" * 3000 + "1}\n", "0 or more"),
        ("version: 1\nrules: \x00\n", "unacceptable character"),
    ],
    ids=[
        "laughs",
        "self",
        "deep",
        "huge-count",
        "huge-version",
        "1e308",
        "400-digits",
        "sexagesimal",
        "nul",
    ],
)
def test_budget_bombs(tmp_path: Path, script: Path, body: str, needle: str) -> None:
    budget = tmp_path / "budget.yaml"
    budget.write_text(body)
    line = assert_one_line_error(check(tmp_path, script, budget), f"{budget}:", needle)
    assert len(line) < 400


def test_special_and_oversized_budgets(tmp_path: Path, script: Path) -> None:
    fifo = tmp_path / "fifo.yaml"
    os.mkfifo(fifo)
    folder = tmp_path / "folder.yaml"
    folder.mkdir()
    big = tmp_path / "big.yaml"
    with big.open("wb") as out:
        out.truncate(17 * 1024 * 1024)
    for path, what in (
        ("/dev/zero", "character device"),
        (fifo, "FIFO"),
        (folder, "directory"),
        (big, "larger than"),
    ):
        assert_one_line_error(check(tmp_path, script, path), str(path), what)
