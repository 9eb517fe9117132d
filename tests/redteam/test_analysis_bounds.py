"""The analysis commands on inputs built to make them grow: ``explain`` on a fault that reports
without end, ``suggest-rules`` on a fleet of many codes, ``sweep`` on a grid that cannot finish.

Each runs in a child process under ``resource.setrlimit`` (tests/redteam/support.py): memory
stays bounded by what is told, and every bound is said in one line.
"""

from __future__ import annotations

import json
import re
from typing import TYPE_CHECKING

from tests.redteam.support import MIB, Outcome, assert_one_line_error, run_limited

if TYPE_CHECKING:
    from pathlib import Path

S = 1_000_000_000
MEMORY = 1024 * MIB
"""The child's address space: the interpreter and its modules need some 300-400 MiB."""


def write_script(path: Path, requests: list[tuple[float, str, str]]) -> Path:
    """A JSON-lines script of ReportFault requests: (seconds, code, FAILED or PASSED)."""
    lines = [
        json.dumps(
            {
                "t_ns": round(t * S),
                "op": "report",
                "fault_code": code,
                "event_type": event,
                "severity": 2,
                "description": "built by the test",
                "source_id": "/robot/motor",
            }
        )
        for t, code, event in requests
    ]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def write_params(path: Path, **values: int | bool) -> Path:
    body = "".join(f"    {name}: {json.dumps(value)}\n" for name, value in values.items())
    path.write_text(f"fault_manager:\n  ros__parameters:\n{body}", encoding="utf-8")
    return path


def run(*argv: str | Path, memory: int = MEMORY) -> Outcome:
    return run_limited(argv, memory=memory, cpu_seconds=60, timeout=120)


# -- explain ----------------------------------------------------------------------------------


def flapping(tmp_path: Path, reports: int) -> Path:
    """One code failing once and passing twice, a report every 10 ms, ``reports`` reports (it
    confirms and heals every 30 ms)."""
    requests = [
        (1 + i / 100, "MOTOR_FLAP", "PASSED" if i % 3 else "FAILED") for i in range(reports)
    ]
    return write_script(tmp_path / f"flap_{reports}.jsonl", requests)


def flap_params(tmp_path: Path) -> Path:
    return write_params(
        tmp_path / "flap.yaml", confirmation_threshold=-1, healing_threshold=1, healing_enabled=True
    )


def test_explain_holds_memory_by_what_it_tells_not_by_the_recording(tmp_path: Path) -> None:
    params = flap_params(tmp_path)
    peaks = []
    for reports in (5_000, 40_000):
        script = flapping(tmp_path, reports)
        outcome = run("explain", script, "MOTOR_FLAP", "--config", params, "--limit", "300")
        assert outcome.status == 0, outcome.stderr[-2000:]
        text = " ".join(outcome.stdout.split())
        assert "story cut after 300 items:" in text
        assert "(narrow it with --from and --at, or raise --limit)" in text
        assert "HEALED" in text
        assert outcome.stdout.count(" report ") < 300
        peaks.append(outcome.peak_rss_kib)
    # Eight times the reports, the same story: the peak grows by far less than the trace would.
    assert peaks[1] - peaks[0] < 40 * 1024, peaks


def test_explain_json_counts_what_it_left_out_the_same_every_time(tmp_path: Path) -> None:
    params = flap_params(tmp_path)
    script = flapping(tmp_path, 2_000)
    argv = ("explain", script, "MOTOR_FLAP", "--config", params, "--json")
    first = run(*argv, "--limit", "100", "--from", "5")
    assert first.status == 0, first.stderr[-2000:]
    assert run(*argv, "--limit", "100", "--from", "5").stdout == first.stdout
    story = json.loads(first.stdout)
    left_out = story["summary"]["left_out"]
    told = [e for e in story["entries"] if e["kind"] != "repeat"]
    assert left_out["limit"] == 100 and left_out["before_from"] > 0 and left_out["past_limit"] > 0
    assert min(e["offset_ns"] for e in told) >= 5 * S
    assert left_out["past_limit_from_ns"] >= max(e["t_ns"] for e in told)
    whole = json.loads(run(*argv).stdout)  # within the default limit: nothing left out
    assert "left_out" not in whole["summary"]
    assert whole["summary"]["reports"] == 2_000


def test_explain_from_past_every_report_tells_nothing_but_knows_the_code(tmp_path: Path) -> None:
    script = flapping(tmp_path, 100)
    outcome = run("explain", script, "MOTOR_FLAP", "--from", "3600", "--json")
    assert outcome.status == 0, outcome.stderr[-2000:]
    story = json.loads(outcome.stdout)
    assert story["entries"] == [] and story["summary"]["left_out"]["before_from"] > 0


# -- suggest-rules --------------------------------------------------------------------------


def fleet(tmp_path: Path, runs: int, codes: int) -> Path:
    """``runs`` scripts in which ``codes`` codes all confirm within a second (every pair is a
    candidate); code i is missing from the runs below i % runs, so fewer codes are common."""
    folder = tmp_path / "fleet"
    folder.mkdir()
    for run_index in range(runs):
        requests = [
            (1 + c / 1000, f"CODE_{c:04d}", "FAILED") for c in range(codes) if run_index >= c % runs
        ]
        write_script(folder / f"run{run_index:02d}.jsonl", requests)
    return folder


def test_suggest_rules_caps_the_pairs_it_weighs_and_says_so(tmp_path: Path) -> None:
    folder = fleet(tmp_path, runs=4, codes=80)
    rules = tmp_path / "rules.yaml"
    argv = ("suggest-rules", folder, "--jobs", "1", "--out", rules, "--max-pairs", "190")
    outcome = run(*argv)
    assert outcome.status == 0, outcome.stderr[-2000:]
    warnings = [line for line in outcome.stderr.splitlines() if "warning" in line]
    # Codes in at least 3 runs: c % 4 in (0, 1), 40 of them (780 pairs); 20 codes make 190.
    assert warnings == [
        "medkit-replay: warning: 40 codes confirmed in at least 3 runs make 780 pairs, more "
        "than --max-pairs 190: only the 20 confirmed in the most runs were paired (590 pairs "
        "dropped; raise --max-pairs to weigh them)"
    ]
    text = rules.read_text()
    again = run(*argv)
    assert again.status == 0 and rules.read_text() == text  # the same codes kept every time
    # The 20 kept: the codes in all four runs (c % 4 == 0), the only ones in the rules.
    named = {int(number) for number in re.findall(r"CODE_(\d+)", text)}
    assert len(named) == 20 and all(number % 4 == 0 for number in named), named
    wide = run("suggest-rules", folder, "--jobs", "1", "--out", rules, "--max-pairs", "780")
    assert wide.status == 0 and "warning" not in wide.stderr


def test_suggest_rules_memory_stays_bounded_on_many_codes(tmp_path: Path) -> None:
    folder = fleet(tmp_path, runs=6, codes=1200)  # 1,200 codes: 719,400 pairs uncapped
    outcome = run("suggest-rules", folder, "--jobs", "1", "--out", tmp_path / "r.yaml")
    assert outcome.status == 0, outcome.stderr[-2000:]
    assert "more than --max-pairs 20,000" in outcome.stderr
    assert outcome.peak_rss_kib < 400 * 1024, outcome.peak_rss_kib


# -- sweep ----------------------------------------------------------------------------------


def values(count: int, sign: int = 1) -> str:
    return ",".join(str(sign * (i + 1)) for i in range(count))


def test_sweep_refuses_a_grid_that_cannot_finish_before_it_starts(tmp_path: Path) -> None:
    script = write_script(
        tmp_path / "short.jsonl", [(1 + i / 10, "MOTOR", "FAILED") for i in range(20)]
    )
    out = tmp_path / "out"
    outcome = run(
        "sweep", script, "--out", out, "--jobs", "1",
        "--vary", f"fault_manager.confirmation_threshold={values(316, -1)}",
        "--vary", f"fault_manager.healing_threshold={values(316)}",
    )  # fmt: skip
    assert_one_line_error(
        outcome,
        "the grid has 99,856 variants x 1 recording(s) = 99,856 replays, more than "
        "--max-runs 20,000: vary fewer values, or raise --max-runs",
    )
    assert not out.exists()  # refused before anything was written
    assert outcome.peak_rss_kib < 200 * 1024, outcome.peak_rss_kib


def test_sweep_max_runs_counts_every_recording_and_can_be_raised(tmp_path: Path) -> None:
    for name in ("a", "b"):
        write_script(
            tmp_path / f"{name}.jsonl", [(1 + i / 10, "MOTOR", "FAILED") for i in range(5)]
        )
    vary = ("--vary", f"fault_manager.confirmation_threshold={values(6, -1)}")
    common = ("sweep", tmp_path / "a.jsonl", tmp_path / "b.jsonl", "--jobs", "1", *vary)
    refused = run(*common, "--max-runs", "11")
    assert_one_line_error(refused, "6 variants x 2 recording(s) = 12 replays")
    tables = []
    for name in ("one", "two"):
        out = tmp_path / name
        outcome = run(*common, "--max-runs", "12", "--out", out, "--quiet")
        assert outcome.status == 0, outcome.stderr[-2000:]
        tables.append((out / "variants.csv").read_bytes())
    assert tables[0] == tables[1] and tables[0].count(b"\n") == 7
