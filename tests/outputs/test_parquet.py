"""Parquet tables: same rows as the DataFrames, typed columns, and a clear error without pyarrow."""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING

import pandas as pd
import pyarrow.parquet as pq
import pytest

from medkit_replay.cli import main
from medkit_replay.outputs.parquet import EXTRA_HINT, MissingDependencyError, write_parquet
from medkit_replay.outputs.tables import TABLE_COLUMNS, result_tables
from medkit_replay.pipeline import replay
from tests.outputs.scripts import T0, healing_config, mission, report, write_script

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.result import Result


@pytest.fixture
def result(tmp_path: Path) -> Result:
    return replay([mission(tmp_path)], [healing_config(tmp_path)])


def test_one_file_per_table_with_the_report_columns(result: Result, tmp_path: Path) -> None:
    written = write_parquet(result, tmp_path / "out" / "tables")
    assert sorted(p.name for p in written) == sorted(f"{name}.parquet" for name in TABLE_COLUMNS)
    frames = result_tables(result)
    for name, columns in TABLE_COLUMNS.items():
        read = pd.read_parquet(tmp_path / "out" / "tables" / f"{name}.parquet")
        assert list(read.columns) == columns
        assert len(read) == len(frames[name])


def test_values_round_trip(result: Result, tmp_path: Path) -> None:
    write_parquet(result, tmp_path)
    faults = pd.read_parquet(tmp_path / "faults.parquet")
    battery = faults[faults["fault_code"] == "BATTERY_LOW"].iloc[0]
    assert battery["status"] == "CLEARED"
    assert list(battery["reporting_sources"]) == ["/power/bms", "/power/bms2"]
    assert int(battery["first_occurred_ns"]) == T0 + 6_000_000_000  # nanoseconds stay exact
    assert not bool(battery["muted"]) and pd.isna(battery["root_cause_code"])
    events = pd.read_parquet(tmp_path / "events.parquet")
    assert [int(t) for t in events["t_ns"]] == [e.t_ns for e in result.events]
    assert list(events["event_type"]) == [e.event_type for e in result.events]


def test_arrow_types_are_fixed_even_for_empty_and_null_columns(
    result: Result, tmp_path: Path
) -> None:
    write_parquet(result, tmp_path)
    reports = pq.read_schema(tmp_path / "reports.parquet")
    assert str(reports.field("t_ns").type) == "int64"
    assert str(reports.field("debounce_counter").type) == "int64"  # null for the rejected one
    assert str(reports.field("accepted").type) == "bool"
    table = pq.read_table(tmp_path / "reports.parquet")
    rejected = [row for row in table.to_pylist() if not row["accepted"]]
    assert rejected[0]["debounce_counter"] is None
    assert rejected[0]["reject_reason"].startswith("fault_code contains invalid character")
    near = pq.read_schema(tmp_path / "near_misses.parquet")  # no near miss in this run
    assert pq.read_metadata(tmp_path / "near_misses.parquet").num_rows == 0
    assert str(near.field("t_ns").type) == "int64"
    faults = pq.read_schema(tmp_path / "faults.parquet")
    assert str(faults.field("reporting_sources").type) == "list<element: string>"
    assert str(faults.field("cluster_ids").type) == "list<element: string>"


def test_empty_replay_writes_empty_typed_tables(tmp_path: Path) -> None:
    script = write_script(tmp_path / "e.jsonl", [report(T0, "bad code!")])
    write_parquet(replay([script]), tmp_path / "t")
    assert pq.read_metadata(tmp_path / "t" / "faults.parquet").num_rows == 0
    schema = pq.read_schema(tmp_path / "t" / "faults.parquet")
    assert str(schema.field("first_occurred_ns").type) == "int64"


def test_cli_parquet(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out_dir = tmp_path / "pq"
    assert main(["analyze", str(mission(tmp_path)), "--parquet", str(out_dir), "--quiet"]) == 0
    assert sorted(p.name for p in out_dir.iterdir()) == sorted(
        f"{name}.parquet" for name in TABLE_COLUMNS
    )
    assert capsys.readouterr() == ("", "")


def test_without_pyarrow_one_line_naming_the_extra(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "pyarrow", None)  # import pyarrow now raises ImportError
    out_dir = tmp_path / "pq"
    status = main(["analyze", str(mission(tmp_path)), "--parquet", str(out_dir)])
    out, err = capsys.readouterr()
    assert status == 2
    assert out == ""  # refused before the replay: no summary
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("medkit-replay: error: --parquet needs pyarrow")
    assert EXTRA_HINT in err and "pip install 'medkit-replay[parquet]'" in err
    assert not out_dir.exists()
    with pytest.raises(MissingDependencyError):
        write_parquet(replay([mission(tmp_path)]), out_dir)


def test_unwritable_directory_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("x")
    status = main(["analyze", str(mission(tmp_path)), "--parquet", str(blocker / "t"), "--quiet"])
    _, err = capsys.readouterr()
    assert status == 2
    assert err.startswith("medkit-replay: error: ") and "cannot write Parquet" in err
