"""No code, file name or number is split across lines, at any width from 60 columns up.

fleet, sweep, check and diff are rendered with long paths and long codes (up to 256
characters) at 60, 80 and 120 columns: every such token must appear whole on one line.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest
from rich.console import Group

from medkit_replay import replay
from medkit_replay.captures import EvidenceRecording, RecordingTopic
from medkit_replay.checks.budget_file import parse_budget
from medkit_replay.checks.evaluate import CheckRun, Verdict
from medkit_replay.checks.facts import Offender
from medkit_replay.checks.terminal import run_renderable
from medkit_replay.cli import main
from medkit_replay.diffing import diff_reports, render_diff
from medkit_replay.fleet.run import RunSummary
from medkit_replay.fleet.terminal import render_summary as fleet_summary
from medkit_replay.outputs.console import plain_text
from medkit_replay.outputs.terminal import render_summary
from medkit_replay.result import STATUSES
from medkit_replay.tuning.metrics import RunRow
from medkit_replay.tuning.ranking import VariantTotal
from medkit_replay.tuning.terminal import summary_renderables as sweep_renderables
from tests.checks.support import budget_text
from tests.diff.reports import base_report, fault

ROOT = Path(__file__).resolve().parents[2]
WIDTHS = (60, 80, 120)
SEC = 1_000_000_000
LONG_CODE = "ACTION_FOLLOW_PATH_ABORTED_" + "X" * (256 - 27)
MIDDLE_CODE = "ACTION_FOLLOW_PATH_ABORTED_WHILE_NAVIGATING"
LONG_PATH = "/tmp/pytest-of-someone/pytest-42/recordings0/unrelated/" + "deep/" * 8 + "bag"
BAG = "fleet/nav2_mission_ros1.bag"


def whole(text: str, tokens: list[str]) -> None:
    """Each token is on one line of ``text``."""
    lines = text.splitlines()
    for token in tokens:
        assert any(token in line for line in lines), (token, text)


def statuses(**counts: int) -> tuple[tuple[str, int], ...]:
    return tuple((s, counts.get(s.lower(), 0)) for s in STATUSES)


def fleet_runs() -> list[RunSummary]:
    return [
        RunSummary(
            path=LONG_PATH,
            kind="rosbag2",
            start_ns=0,
            end_ns=1234567 * SEC,
            messages=123456789,
            faults_by_status=statuses(confirmed=1, healed=1),
            confirmed=((LONG_CODE, SEC), (MIDDLE_CODE, 2 * SEC)),
            heals=((MIDDLE_CODE, 3 * SEC),),
            warnings=1,
            first_warnings=(f"{LONG_PATH}: topic {LONG_CODE} has no bridge",),
            budget="fail",
            budget_failures=(f"no {MIDDLE_CODE}",),
        ),
        RunSummary(
            path=BAG,
            kind="rosbag1",
            start_ns=0,
            end_ns=5 * SEC,
            messages=2,
            faults_by_status=statuses(confirmed=1),
            confirmed=((MIDDLE_CODE, 5 * SEC),),
            budget="pass",
        ),
        RunSummary(path=f"{LONG_PATH}2", kind="mcap", error=f"{LONG_PATH}2: cannot be read"),
    ]


@pytest.mark.parametrize("width", WIDTHS)
def test_fleet(width: int) -> None:
    text = fleet_summary(fleet_runs(), None, width=width)
    whole(
        text,
        [LONG_PATH, BAG, LONG_CODE, MIDDLE_CODE, "123,456,789", "1,234,567.0", f"{LONG_PATH}2"],
    )
    long_lines = [line for line in text.splitlines() if len(line) > width]
    assert all(LONG_CODE in line or LONG_PATH in line for line in long_lines), (
        long_lines
    )  # only a token wider than the line is


def sweep_text(width: int) -> str:
    totals = [
        VariantTotal(
            rank=rank,
            variant=f"v{rank:02d}",
            label=f"correlation.config_file=/very/long/{LONG_PATH}/suggested_correlation.yaml "
            f"healing_threshold={rank}",
            upstream_release="0.7.0",
            runs=12,
            failed_runs=0,
            faults_confirmed=123456789,
            latency_mean_ns=1234 * SEC,
            flaps=12,
            confirmed_ns=0,
            events=328,
            muted_events=68,
            near_misses=178,
            muted_faults=0,
            budget_failed=rank,
        )
        for rank in (1, 2)
    ]
    failed = [RunRow(variant="v01", input=LONG_PATH, error=f"{LONG_PATH}: {LONG_CODE}")]
    over = [(LONG_PATH, f"no {MIDDLE_CODE}", 2)]
    parts = sweep_renderables(totals, 12, failed, None, budget=True, over_budget=over)
    return plain_text(Group(*parts), width, crop=False)


@pytest.mark.parametrize("width", WIDTHS)
def test_sweep(width: int) -> None:
    text = sweep_text(width)
    tokens = ["suggested_correlation.yaml", "123,456,789", "1,234.00", LONG_PATH, LONG_CODE]
    whole(text, [*tokens, MIDDLE_CODE, "healing_threshold=2", "v01", "v02"])
    # every variant's figures are on one line with it
    assert any(line.startswith("1  v01") and "123,456,789" in line for line in text.splitlines())


def check_text(width: int) -> str:
    budget = parse_budget(
        budget_text("- name: no motor faults\n  never_confirm: ['*']\n- allow_confirm: ['*']"),
        "budgets/ci.yaml",
    )
    failed = Verdict(
        budget.rules[0],
        False,
        f"{MIDDLE_CODE} confirmed in {LONG_PATH}",
        tuple(
            Offender(code, 10, 123456 * SEC, f"seen on {LONG_PATH}")
            for code in (LONG_CODE, MIDDLE_CODE)
        ),
    )
    run = CheckRun(
        label=LONG_PATH,
        inputs=(LONG_PATH,),
        budget=budget,
        verdicts=(failed, Verdict(budget.rules[1], True, "all fine")),
        warnings=(f"topic {LONG_CODE} in {LONG_PATH} has no bridge",),
    )
    return plain_text(Group(*run_renderable(run)), width, crop=False)


@pytest.mark.parametrize("width", WIDTHS)
def test_check(width: int) -> None:
    text = check_text(width)
    whole(text, [LONG_PATH, LONG_CODE, MIDDLE_CODE, "123456.000", "ci.yaml:"])


def diff_text(width: int) -> str:
    current = base_report()
    current["faults"][0]["severity"] = 3
    current["faults"][0]["reporting_sources"] = [LONG_PATH]
    current["faults"].append(fault(LONG_CODE, reporting_sources=[LONG_PATH]))
    current["faults"].append(fault(MIDDLE_CODE))
    diff = diff_reports(
        base_report(),
        current,
        time_tolerance_ns=0,
        baseline_name=f"{LONG_PATH}/baseline.json",
        current_name=f"{LONG_PATH}/current.json",
    )
    return render_diff(diff, width)


@pytest.mark.parametrize("width", WIDTHS)
def test_diff(width: int) -> None:
    text = diff_text(width)
    whole(text, [f"{LONG_PATH}/baseline.json", f"{LONG_PATH}/current.json", LONG_CODE, MIDDLE_CODE])
    assert "CONFIRMED" in text


@pytest.mark.parametrize("width", WIDTHS)
def test_evidence_list(width: int) -> None:
    base = replay([ROOT / "examples/nav2_mission.jsonl"], [ROOT / "rules/nav2/fault_manager.yaml"])
    start = base.summary.start_ns or 0
    recording = EvidenceRecording(
        recording_id=LONG_CODE,
        fault_codes=(LONG_CODE,),
        start_ns=start,
        end_ns=start + 5 * SEC,
        topics=(RecordingTopic(topic="/battery", type="sensor_msgs/msg/BatteryState", messages=3),),
        messages=123456,
        bytes=98_765_432,
        deleted_ns=start + 9 * SEC,
        deleted_reason=f"auto_cleanup: {MIDDLE_CODE} was cleared, {LONG_PATH} removed",
        path=None,
    )
    result = dataclasses.replace(base, recordings=(recording,))
    text = render_summary(result, width, everything=True)
    whole(text, [LONG_CODE, "123456 msg, 98765.4 kB", MIDDLE_CODE, LONG_PATH])
    whole(text, ["deleted at 9.000 s:"])


@pytest.mark.parametrize("width", WIDTHS)
def test_explain(
    width: int,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    script = tmp_path / "run.jsonl"
    lines = [
        {
            "t_ns": (n + 1) * SEC,
            "op": "report",
            "fault_code": LONG_CODE,
            "event_type": "FAILED",
            "severity": 2,
            "description": f"seen on {LONG_PATH}",
            "source_id": f"/robot/{MIDDLE_CODE.lower()}",
        }
        for n in range(3)
    ]
    script.write_text("".join(json.dumps(line) + "\n" for line in lines), encoding="utf-8")
    monkeypatch.setenv("COLUMNS", str(width))
    assert main(["explain", str(script), LONG_CODE, "--quiet"]) == 0
    text = capsys.readouterr().out
    whole(text, [LONG_CODE, LONG_PATH, f"/robot/{MIDDLE_CODE.lower()}"])
