"""Red team: scripts, reports read back, budgets, configs and the spool under hostile input.

Deep nesting, numbers of thousands of digits, NaN, lone surrogates, times past int64, a full
temporary folder, multi-line YAML messages: each ends in one ``file:line`` line, exit 2.
"""

from __future__ import annotations

import json
import os
import stat
from typing import TYPE_CHECKING

import pytest

from medkit_replay.diffing import read_report
from medkit_replay.errors import InputError
from tests.inputs.builders import diag, log, write_bag
from tests.redteam.support import (
    DEFAULT_CPU_SECONDS,
    DEFAULT_MEMORY,
    assert_one_line_error,
    run_limited,
)

if TYPE_CHECKING:
    from pathlib import Path

    from tests.redteam.support import Outcome

MIB = 1024 * 1024
HUGE = "7" * 5000
FAILED = '"op": "report", "fault_code": "MOTOR_A", "event_type": "FAILED", "source_id": "/motor"'
GOOD_LINE = '{"t_ns": 1000000000, ' + FAILED + "}\n"


def script(tmp_path: Path, *lines: str, name: str = "run.jsonl") -> Path:
    """A script whose first line is valid and whose next lines are ``lines``."""
    path = tmp_path / name
    path.write_text(GOOD_LINE + "".join(line + "\n" for line in lines))
    return path


def analyze(
    *argv: str | Path, memory: int = DEFAULT_MEMORY, cpu_seconds: int = DEFAULT_CPU_SECONDS
) -> Outcome:
    return run_limited(
        ["analyze", *argv, "--quiet"], memory=memory, cpu_seconds=cpu_seconds, timeout=60
    )


def report(tmp_path: Path, name: str = "report.json") -> Path:
    """A real report of a small script, written by the tool."""
    path = tmp_path / name
    outcome = analyze(script(tmp_path, name=f"{name}.jsonl"), "--json", path)
    assert outcome.status == 0, outcome.stderr
    return path


@pytest.fixture(scope="module")
def good(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One valid report shared by the tests that only read it."""
    return report(tmp_path_factory.mktemp("good"))


def with_line(base: Path, target: Path, key: str, raw_value: str) -> int:
    """Copy a report, adding ``"key": raw_value`` on its own line; returns that line."""
    text = base.read_text().rstrip()
    assert text.endswith("}")
    body = text[:-1].rstrip() + ",\n"
    target.write_text(body + f'  "{key}": {raw_value}\n}}\n')
    return body.count("\n") + 1


def diff(
    *argv: str | Path, memory: int = DEFAULT_MEMORY, cpu_seconds: int = DEFAULT_CPU_SECONDS
) -> Outcome:
    return run_limited(
        ["diff", *argv, "--quiet"], memory=memory, cpu_seconds=cpu_seconds, timeout=60
    )


# -- 1. nesting ----------------------------------------------------------------------------


def test_deeply_nested_script_line(tmp_path: Path) -> None:
    deep = '{"t_ns": 2000000000, ' + FAILED + ', "x": ' + "[" * 100_000 + "]" * 100_000 + "}"
    path = script(tmp_path, deep)
    line = assert_one_line_error(analyze(path), f"{path}:2:", "nests deeper than 64")
    assert len(line) < 300


def test_nesting_within_the_bound_reaches_the_key_check(tmp_path: Path) -> None:
    # 60 levels parse; the line is then refused for its unknown key, not its depth.
    path = script(tmp_path, '{"t_ns": 2, ' + FAILED + ', "x": ' + "[" * 60 + "]" * 60 + "}")
    assert_one_line_error(analyze(path), f"{path}:2:", "unknown key(s) ['x']")


@pytest.mark.parametrize("side", ["baseline", "current"])
def test_deeply_nested_report(tmp_path: Path, good: Path, side: str) -> None:
    bad = tmp_path / "deep.json"
    at = with_line(good, bad, "x", "[" * 50_000 + "]" * 50_000)
    argv = (bad, good) if side == "baseline" else (good, bad)
    assert_one_line_error(diff(*argv), f"{bad}:{at}:", "nests deeper than 64")


# -- 3. numbers of thousands of digits -----------------------------------------------------


@pytest.mark.parametrize(
    "line",
    [
        '{"t_ns": ' + HUGE + ", " + FAILED + "}",
        '{"t_ns": 2000000000, ' + FAILED + ', "severity": ' + HUGE + "}",
        '{"t_ns": 2000000000, ' + FAILED + ', "severity": -' + HUGE + "}",
        '{"t_ns": 2000000000, ' + FAILED + ', "severity": 1' + "0" * 400 + ".0}",
        '{"t_ns": 2000000000, ' + FAILED + ', "severity": 1e400}',
    ],
    ids=["t_ns", "severity", "negative", "400-digit-float", "1e400"],
)
def test_huge_numbers_in_a_script(tmp_path: Path, line: str) -> None:
    path = script(tmp_path, line)
    text = assert_one_line_error(analyze(path), f"{path}:2:")
    assert "too long" in text or "double range" in text, text
    assert len(text) < 300


def test_huge_number_in_a_report(tmp_path: Path, good: Path) -> None:
    bad = tmp_path / "huge.json"
    text = good.read_text()
    assert '"occurrence_count": 1' in text
    bad.write_text(text.replace('"occurrence_count": 1', '"occurrence_count": ' + HUGE, 1))
    line = text[: text.index('"occurrence_count": 1')].count("\n") + 1
    assert_one_line_error(diff(good, bad), f"{bad}:{line}:", "5,000 digits")


def test_report_times_past_int64(tmp_path: Path, good: Path) -> None:
    bad = tmp_path / "late.json"
    bad.write_text(good.read_text().replace('"t_ns": 1000000000', '"t_ns": 1' + "0" * 400))
    assert_one_line_error(diff(good, bad), str(bad), "t_ns is outside int64")


def test_time_tolerance_past_nanoseconds(tmp_path: Path, good: Path) -> None:
    assert_one_line_error(diff(good, good, "--time-tolerance", "1e300"), "too large")


# -- 4. lone surrogates ----------------------------------------------------------------------


@pytest.mark.parametrize("field", ["fault_code", "description", "source_id"])
def test_lone_surrogate_in_a_script(tmp_path: Path, field: str) -> None:
    fields = {"t_ns": 2, "op": "report", "fault_code": "A", "event_type": 0, "source_id": "/m"}
    text = json.dumps(fields | {field: "ok\ud800"})
    assert "\\ud800" in text
    path = script(tmp_path, text)
    assert_one_line_error(analyze(path), f"{path}:2:", field, "lone surrogate")


def test_surrogate_pairs_in_a_script_are_text(tmp_path: Path) -> None:
    fields = {"t_ns": 2000000000, "op": "report", "fault_code": "A", "event_type": 0}
    line = json.dumps(fields | {"description": "\U0001f525", "source_id": "/m"})
    out = tmp_path / "r.json"
    outcome = analyze(script(tmp_path, line), "--json", out)
    assert outcome.status == 0, outcome.stderr
    data = json.loads(out.read_text())
    assert [r["description"] for r in data["reports"]] == ["", "\U0001f525"]
    assert_diff_equal(out)


def assert_diff_equal(path: Path) -> None:
    outcome = diff(path, path)
    assert outcome.status == 0, outcome.stderr


def test_lone_surrogate_in_a_report(tmp_path: Path, good: Path) -> None:
    bad = tmp_path / "surrogate.json"
    at = with_line(good, bad, "note", '"x\\udc00y"')
    assert_one_line_error(diff(good, bad), f"{bad}:{at}:", "lone surrogate")


# -- 5. script times -------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("t_ns", "needle"),
    [
        (str(1 << 63), "below 2^63"),
        ("1" + "0" * 30, "below 2^63"),
        ("-1", "'t_ns' must be in >= 0"),
        ("-" + str(1 << 63), "'t_ns' must be in >= 0"),
        ("1e30", "must be an integer"),
        ("NaN", "NaN is not JSON"),
        ("-Infinity", "-Infinity is not JSON"),
    ],
)
def test_script_times_out_of_range(tmp_path: Path, t_ns: str, needle: str) -> None:
    path = script(tmp_path, '{"t_ns": ' + t_ns + ", " + FAILED + "}")
    assert_one_line_error(analyze(path), f"{path}:2:", needle)


def test_the_last_int64_time_is_accepted(tmp_path: Path) -> None:
    path = script(tmp_path, '{"t_ns": ' + str((1 << 63) - 1) + ", " + FAILED + "}")
    out = tmp_path / "r.json"
    outcome = analyze(path, "--json", out)
    assert outcome.status == 0, outcome.stderr
    assert json.loads(out.read_text())["reports"][-1]["t_ns"] == (1 << 63) - 1


def test_repeated_key_in_a_script_line(tmp_path: Path) -> None:
    path = script(tmp_path, '{"t_ns": 2, "t_ns": 1, ' + FAILED + "}")
    assert_one_line_error(analyze(path), f"{path}:2:", "'t_ns' appears twice")


def test_special_script_files(tmp_path: Path) -> None:
    fifo = tmp_path / "fifo.jsonl"
    os.mkfifo(fifo)
    assert_one_line_error(analyze(fifo, cpu_seconds=20), str(fifo), "FIFO")


# -- 6. the spool when the temporary folder is full -----------------------------------------


def test_spool_write_failure_is_one_line(tmp_path: Path) -> None:
    # 40,000 reports spill past the first 16,384-record chunk; RLIMIT_FSIZE fails that write
    # with EFBIG exactly as a full disk fails it with ENOSPC.
    lines = (
        f'{{"t_ns": {n * 1000}, "op": "report", "fault_code": "F{n % 50}", '
        f'"event_type": "FAILED", "source_id": "/n"}}\n'
        for n in range(40_000)
    )
    path = tmp_path / "long.jsonl"
    path.write_text("".join(lines))
    spool_dir = tmp_path / "tmp"
    spool_dir.mkdir()
    outcome = run_limited(
        ["analyze", path, "--quiet"],
        file_size=256 * 1024,
        env={"TMPDIR": str(spool_dir)},
        timeout=60,
    )
    assert_one_line_error(outcome, str(spool_dir), "EFBIG", "cannot spool")
    assert list(spool_dir.iterdir()) == []


# -- 7. YAML errors on one line ----------------------------------------------------------------


@pytest.mark.parametrize(
    ("body", "line", "needle"),
    [
        ("a: 1\n---\nb: 2\n", 2, "expected a single document in the stream, but found another"),
        ("a: &x 1\nb: &x 2\n", 2, "found duplicate anchor 'x'"),
        ('fault_manager:\n  ros__parameters:\n    "x\\ny": [1, "a"]\n', 3, "x\\x0ay: array"),
        ('"fault\\u2028manager": 5\n', 1, "fault\\u2028manager: expected a node name"),
        ('fault_manager:\n  ros__parameters:\n    "\\u202e": [1, "a"]\n', 3, "\\u202e: array"),
    ],
    ids=["two-documents", "duplicate-anchor", "newline-key", "line-separator", "bidi-key"],
)
def test_config_yaml_errors_are_one_line(tmp_path: Path, body: str, line: int, needle: str) -> None:
    config = tmp_path / "params.yaml"
    config.write_text(body)
    path = script(tmp_path)
    assert_one_line_error(analyze(path, "--config", config), f"{config}:{line}:", needle)


BIDI_KEY = '{max_occurrences: {"*": 1}, "\\u202e' + "x" * 900 + '": 1}'


@pytest.mark.parametrize(
    ("body", "needle"),
    [
        ("version: 1\n---\nrules: []\n", "but found another document"),
        ("version: 1\nrules:\n  - max_occurrences: {'*': 0x" + "f" * 5000 + "}\n", "larger than"),
        ("version: 1\nrules:\n  - max_occurrences: {'*': 0b" + "1" * 9000 + "}\n", "larger than"),
        ("version: 1\nrules:\n  - max_occurrences: {'*': 0o" + "7" * 5000 + "}\n", "a string"),
        ("version: 0x" + "f" * 5000 + "\nrules: []\n", "larger than"),
        ('version: 1\nrules:\n  - max_occurrences: {"a\\nb": x}\n', "max_occurrences.a\\x0ab"),
        ("version: 1\nrules:\n  - " + BIDI_KEY + "\n", "unknown key '\\u202exxx"),
    ],
    ids=["two-documents", "hex", "binary", "octal", "hex-version", "newline-key", "bidi-key"],
)
def test_budget_errors_are_one_short_line(tmp_path: Path, body: str, needle: str) -> None:
    budget = tmp_path / "budget.yaml"
    budget.write_text(body)
    outcome = run_limited(["check", script(tmp_path), "--budget", budget], timeout=60)
    line = assert_one_line_error(outcome, f"{budget}:", needle)
    assert len(line) < 400


def test_referenced_file_warnings_are_one_line(tmp_path: Path) -> None:
    (tmp_path / "correlation.yaml").write_text("a: &x 1\nb: &x 2\n")
    (tmp_path / "entities.yaml").write_text('"/m\\nx": {confirmation_threshold: [1, 2}\n')
    config = tmp_path / "params.yaml"
    config.write_text(
        "fault_manager:\n  ros__parameters:\n"
        "    correlation: {config_file: correlation.yaml}\n"
        "    entity_thresholds: {config_file: entities.yaml}\n"
    )
    out = tmp_path / "r.json"
    outcome = analyze(script(tmp_path), "--config", config, "--json", out)
    assert outcome.status == 0, outcome.stderr
    warnings: list[str] = json.loads(out.read_text())["warnings"]
    assert any("duplicate anchor" in w and "second occurrence" in w for w in warnings), warnings
    assert any("entities.yaml:1:" in w for w in warnings), warnings
    assert all("\n" not in w for w in warnings)


def test_names_in_referenced_file_warnings_are_escaped(tmp_path: Path) -> None:
    (tmp_path / "entities.yaml").write_text(
        '"/m\\nx": 5\n"/a\\u202e": {confirmation_threshold: 3}\n'
    )
    (tmp_path / "correlation.yaml").write_text(
        'correlation:\n  enabled: true\n  default_window_ms: "' + HUGE + '"\n'
    )
    config = tmp_path / "params.yaml"
    config.write_text(
        "fault_manager:\n  ros__parameters:\n"
        "    correlation: {config_file: correlation.yaml}\n"
        "    entity_thresholds: {config_file: entities.yaml}\n"
    )
    out = tmp_path / "r.json"
    outcome = analyze(script(tmp_path), "--config", config, "--json", out)
    assert outcome.status == 0, outcome.stderr
    warnings: list[str] = json.loads(out.read_text())["warnings"]
    assert any("prefix '/m\\x0ax'" in w for w in warnings), warnings
    assert any("'/a\\u202e' should be <= 0" in w for w in warnings), warnings
    assert any("bad conversion" in w for w in warnings), warnings
    assert all("\n" not in w and "\u202e" not in w and len(w) < 500 for w in warnings)


# -- 2. float parameters ---------------------------------------------------------------------


def test_tiny_auto_confirm_window_stays_on(tmp_path: Path) -> None:
    # Upstream enables the check for any value > 0; rounding it to 0 ns turned it off.
    config = tmp_path / "params.yaml"
    config.write_text(
        "fault_manager:\n  ros__parameters:\n"
        "    confirmation_threshold: -3\n    auto_confirm_after_sec: 1.0e-320\n"
    )
    later = '{"t_ns": 5000000000, "op": "clear", "fault_code": "OTHER"}'
    out = tmp_path / "r.json"
    outcome = analyze(script(tmp_path, later), "--config", config, "--json", out)
    assert outcome.status == 0, outcome.stderr
    causes = [t["cause"] for t in json.loads(out.read_text())["transitions"]]
    assert causes == ["report", "auto_confirm"]


def bridge_bag(tmp_path: Path) -> Path:
    """A bag with /diagnostics and /rosout traffic, so both bridges run."""
    records = [diag(1_000_000_000), log(2_000_000_000, name="planner"), diag(3_000_000_000)]
    return write_bag(tmp_path / "bag", records)


def test_log_cooldown_past_nanoseconds_falls_back(tmp_path: Path) -> None:
    # 1e308 s is finite, but not in nanoseconds: treated as inf is, with upstream's default.
    config = tmp_path / "params.yaml"
    config.write_text(
        "log_bridge:\n  ros__parameters:\n    severity_floor: 40\n"
        "    report_cooldown_sec: 1.0e+308\n"
    )
    out = tmp_path / "r.json"
    outcome = analyze(bridge_bag(tmp_path), "--config", config, "--json", out)
    assert outcome.status == 0, outcome.stderr
    warnings: list[str] = json.loads(out.read_text())["warnings"]
    assert any("report_cooldown_sec" in w and "Using default 5.0" in w for w in warnings)


def test_filter_window_past_nanoseconds_is_refused(tmp_path: Path) -> None:
    config = tmp_path / "params.yaml"
    config.write_text(
        "diagnostic_bridge:\n  ros__parameters:\n    fault_reporter:\n"
        "      local_filtering: {default_window_sec: 1.0e+308}\n"
    )
    outcome = analyze(bridge_bag(tmp_path), "--config", config)
    assert_one_line_error(outcome, f"{config}:4:", "default_window_sec", "finite double")


# -- 8. diff --update keeps the baseline's mode ------------------------------------------------


@pytest.mark.parametrize("current_kind", ["script", "report"])
def test_update_keeps_the_baseline_mode(tmp_path: Path, current_kind: str) -> None:
    baseline = report(tmp_path, "baseline.json")
    baseline.chmod(0o640)
    if current_kind == "script":
        current: Path = script(tmp_path, '{"t_ns": 2000000000, ' + FAILED + "}", name="c.jsonl")
    else:
        current = report(tmp_path, "current.json")
        current.write_text(current.read_text().replace("MOTOR_A", "MOTOR_B"))
    outcome = diff(baseline, current, "--update")
    assert outcome.status == 0, outcome.stderr
    assert stat.S_IMODE(baseline.stat().st_mode) == 0o640
    if current_kind == "report":
        assert baseline.read_bytes() == current.read_bytes()
    assert "MOTOR" in baseline.read_text()
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []


# -- 9. reports that are not files, too large, not UTF-8, not strict JSON ------------------------


def test_special_and_oversized_reports(tmp_path: Path, good: Path) -> None:
    fifo = tmp_path / "fifo.json"
    os.mkfifo(fifo)
    zero = tmp_path / "zero.json"
    zero.symlink_to("/dev/zero")
    folder = tmp_path / "folder.json"
    folder.mkdir()
    sparse = tmp_path / "sparse.json"
    with sparse.open("wb") as out:  # past the 1,024 MiB bound, holding nothing
        out.truncate(1024 * MIB + 1)
    zeros = tmp_path / "zeros.json"
    with zeros.open("wb") as out:  # 1 GiB of NUL bytes: refused by its first byte
        out.truncate(1024 * MIB)
    for path, what in (
        (fifo, "FIFO"),
        (zero, "character device"),
        (folder, "directory"),
        (sparse, "a report of 1,073,741,825 bytes is larger than 1,024 MiB"),
        (zeros, "does not start with '{'"),
    ):
        outcome = diff(good, path, memory=768 * MIB, cpu_seconds=20)
        assert_one_line_error(outcome, str(path), what)
        assert outcome.peak_rss_kib < 256 * 1024


def test_report_too_large_for_memory(tmp_path: Path, good: Path) -> None:
    big = tmp_path / "big.json"
    with big.open("wb") as out:  # '{' then 1.5 GiB of nothing: more than the memory allowed
        out.write(b'{"schema": "')
        out.truncate(1536 * MIB)
    # Under a raised size limit, the memory the child may use is what stops it.
    outcome = diff(good, big, "--max-report-mb", "2048", memory=1024 * MIB, cpu_seconds=20)
    assert_one_line_error(outcome, str(big), "too large to load")


@pytest.mark.parametrize(
    ("raw", "needle"),
    [
        ("NaN", "NaN is not JSON"),
        ("Infinity", "Infinity is not JSON"),
        ("-Infinity", "-Infinity is not JSON"),
        ("1e400", "out of the double range"),
        ('"\xff"', "not UTF-8"),
    ],
)
def test_reports_that_are_not_strict_json(
    tmp_path: Path, good: Path, raw: str, needle: str
) -> None:
    bad = tmp_path / "bad.json"
    at = with_line(good, bad, "x", "0")
    bad.write_bytes(bad.read_bytes().replace(b'"x": 0', b'"x": ' + raw.encode("latin-1")))
    assert_one_line_error(diff(good, bad), f"{bad}:{at}:", needle)
    assert_one_line_error(diff(bad, good), f"{bad}:{at}:", needle)


def test_plugin_reads_reports_the_same_way(tmp_path: Path) -> None:
    # The pytest plugin's golden reports are read by read_report: the same refusals.
    bad = tmp_path / "golden.json"
    bad.write_text('{"schema": "medkit-replay/report/v1",\n "x": NaN}\n')
    with pytest.raises(InputError, match="NaN is not JSON") as caught:
        read_report(bad)
    assert caught.value.line == 2
