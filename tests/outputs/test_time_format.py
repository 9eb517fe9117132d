"""One time format for people: seconds from the recording's start (its UTC time in a header) in
the HTML report, ``explain`` and the tables, where exact nanoseconds stay beside them."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import pandas as pd
import pyarrow.parquet as pq
import pytest

from medkit_replay.explaining import build_story, render_story
from medkit_replay.model import SEVERITY_NAMES
from medkit_replay.outputs.html import _utc as html_utc, render_html
from medkit_replay.outputs.json_report import dumps
from medkit_replay.outputs.parquet import write_parquet
from medkit_replay.outputs.tables import (
    SECONDS_COLUMNS,
    TABLE_COLUMNS,
    TIME_COLUMNS,
    result_tables,
    seconds_column,
    write_csv,
)
from medkit_replay.outputs.times import start_text
from medkit_replay.pipeline import replay
from medkit_replay.text import seconds
from medkit_replay.trace import FaultTrace

if TYPE_CHECKING:
    from medkit_replay.result import Result

ROOT = Path(__file__).resolve().parents[2]
MISSION = ROOT / "sample_bags" / "nav2_mission_mcap"
RULES = [ROOT / "rules" / "nav2" / "fault_manager.yaml", ROOT / "rules" / "nav2" / "bridges.yaml"]


@pytest.fixture(scope="module")
def mission() -> Result:
    return replay([MISSION], RULES)


def test_every_time_column_has_seconds_from_the_start_beside_it() -> None:
    for name, columns in TABLE_COLUMNS.items():
        for i, column in enumerate(columns):
            if column in TIME_COLUMNS:
                assert columns[i + 1] == seconds_column(column), (name, column)
            if column == "severity":
                assert columns[i + 1] == "severity_name", name
        assert not SECONDS_COLUMNS & set(columns) - {
            seconds_column(c) for c in columns if c in TIME_COLUMNS
        }


def test_the_seconds_and_names_are_those_of_the_json_report(mission: Result) -> None:
    report = json.loads(dumps(mission))
    start = report["summary"]["start_ns"]
    assert start == mission.span()[0]
    frames = result_tables(mission)
    checked = 0
    for name, frame in frames.items():
        for row in frame.to_dict("records"):
            for column in TIME_COLUMNS & set(row):
                value, shown = row[column], row[seconds_column(column)]
                if value is None or (column == "last_passed_ns" and value == 0):
                    assert pd.isna(shown), (name, column)  # empty
                    continue
                assert f"{shown:.3f}" == seconds(value - start), (name, column)
                assert abs(shown * 1e9 - (value - start)) < 1e3  # to the microsecond
                checked += 1
            if "severity" in row and row["severity"] is not None:
                assert row["severity_name"] == SEVERITY_NAMES[row["severity"]]
    events = frames["events"]
    assert list(events["t_ns"]) == [e["t_ns"] for e in report["events"]]  # exact, unchanged
    assert checked > 100


def test_csv_and_parquet_carry_them(mission: Result, tmp_path: Path) -> None:
    write_csv(mission, tmp_path / "csv")
    write_parquet(mission, tmp_path / "pq")
    start = mission.span()[0]
    assert start is not None
    with (tmp_path / "csv" / "transitions.csv").open(newline="", encoding="utf-8") as stream:
        rows = list(csv.DictReader(stream))
    assert rows and all(f"{float(r['t_s']):.3f}" == seconds(int(r["t_ns"]) - start) for r in rows)
    with (tmp_path / "csv" / "faults.csv").open(newline="", encoding="utf-8") as stream:
        faults = list(csv.DictReader(stream))
    assert {f["severity_name"] for f in faults} <= set(SEVERITY_NAMES)
    schema = pq.read_schema(tmp_path / "pq" / "events.parquet")
    assert str(schema.field("t_s").type) == "double" and str(schema.field("t_ns").type) == "int64"
    assert str(schema.field("severity_name").type) == "string"


def test_html_and_explain_count_from_the_same_start(mission: Result) -> None:
    start = mission.span()[0]
    assert start is not None
    page = render_html(mission)
    assert "times below are seconds from the start" in page
    assert f"from {start} ns ({start_text(start)}) to" in page
    code = "WIFI_SIGNAL_STRENGTH"
    trace = FaultTrace(fault_code=code)
    result = replay([MISSION], RULES, trace=trace)
    text = render_story(build_story(result, trace), width=1000)
    assert f"s from the start, {start_text(start)}" in text
    first = next(t for t in mission.transitions if t.fault_code == code)
    assert f" {seconds(first.t_ns - start)} " in text


def test_bag_times_have_one_home_without_rich() -> None:
    """outputs/times.py holds the cut-off and the formats; importing it loads no rich."""
    code = (
        "import sys; from medkit_replay.outputs import times; "
        "print(times.EPOCH_FLOOR_NS, 'rich' in sys.modules)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.split() == [str(10**18), "False"]


DATE = "2023-11-14 22:13:20.123 UTC"


@pytest.mark.parametrize(
    ("t_ns", "summary", "page"),
    [
        (1_700_000_000_123_456_789, DATE, f" ({DATE})"),
        (5 * 10**17, "t = 500000000.000 s", ""),  # 1985: the page now agrees with the summary
        (
            300_000_000_000 * 10**9,
            "t = 300,000,000,000 s",
            "",
        ),  # past year 10000: whole seconds, grouped
        (12_500_000_000, "t = 12.500 s", ""),
    ],
)
def test_the_start_is_said_alike(t_ns: int, summary: str, page: str) -> None:
    assert start_text(t_ns, whole_beyond=True) == summary
    assert html_utc(t_ns) == page
