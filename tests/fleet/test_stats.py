"""Cross-run statistics on a crafted set of runs whose numbers are known in advance."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import pandas as pd
import pytest

from medkit_replay.fleet.run import RunSummary
from medkit_replay.fleet.stats import CODE_COLUMNS, RUN_COLUMNS, codes_table, overview, runs_table
from medkit_replay.fleet.workers import run_all
from tests.fleet.fleet_support import BRINGUP, SEC, episode, write_script

if TYPE_CHECKING:
    from pathlib import Path


def crafted(tmp_path: Path) -> list[RunSummary]:
    """Three runs (BRINGUP config: heal after four PASSED):

    - r1: A confirmed at 0 s, healed 4 s later; B confirmed at 6 s, never healed;
    - r2: B confirmed at 0 s; A confirmed at 2 s, healed 8 s later, confirmed again (four
      FAILED from HEALED) at 14 s and healed 4 s later; C confirmed at 20 s;
    - r3: cannot be read (does not count in the statistics).
    """
    r1 = [line for _, line in episode("A", 0.0, 4.0) + episode("B", 6.0, None)]
    reconfirm = [(t, episode("A", t, None)[0][1]) for t in (11.0, 12.0, 13.0, 14.0)]
    heal_again = [(t, line) for t, line in episode("A", 14.0, 4.0)[1:]]
    r2 = [
        line
        for _, line in sorted(
            episode("B", 0.0, None)
            + episode("A", 2.0, 8.0)
            + reconfirm
            + heal_again
            + episode("C", 20.0, None)
        )
    ]
    paths = [write_script(tmp_path / "r1.jsonl", r1), write_script(tmp_path / "r2.jsonl", r2)]
    broken = tmp_path / "r3.mcap"
    broken.write_bytes(b"broken")
    return run_all([*paths, broken], [BRINGUP], jobs=1)


def test_crafted_runs_summaries(tmp_path: Path) -> None:
    r1, r2, r3 = crafted(tmp_path)
    assert r1.confirmed == (("A", 0), ("B", 6 * SEC))
    assert r1.heals == (("A", 4 * SEC),)
    assert r2.confirmed == (("B", 0), ("A", 2 * SEC), ("C", 20 * SEC))
    assert r2.heals == (("A", 8 * SEC), ("A", 4 * SEC))
    assert not r3.ok


def test_codes_statistics(tmp_path: Path) -> None:
    codes = codes_table(crafted(tmp_path))
    assert list(codes.columns) == list(CODE_COLUMNS)
    rows = {r["fault_code"]: r for r in codes.to_dict(orient="records")}
    assert list(codes["fault_code"]) == ["A", "B", "C"]  # most runs first, then by code
    a, b, c = rows["A"], rows["B"], rows["C"]
    assert (a["runs_confirmed"], b["runs_confirmed"], c["runs_confirmed"]) == (2, 2, 1)
    assert (a["share_of_runs"], c["share_of_runs"]) == (1.0, 0.5)  # of the 2 replayed runs
    assert a["mean_first_confirmed_s"] == 1.0  # (0 + 2) / 2
    assert b["mean_first_confirmed_s"] == 3.0  # (6 + 0) / 2
    assert a["heals"] == 3
    assert a["mean_time_to_heal_s"] == pytest.approx(16 / 3)  # (4 + 8 + 4) / 3
    assert a["median_time_to_heal_s"] == 4.0
    assert b["heals"] == 0
    assert pd.isna(b["mean_time_to_heal_s"]) and pd.isna(b["median_time_to_heal_s"])


def test_runs_table(tmp_path: Path) -> None:
    table = runs_table(crafted(tmp_path))
    assert list(table.columns) == list(RUN_COLUMNS)
    assert [str(t) for t in table.dtypes] == [
        "string" if t == "string" else t for t in RUN_COLUMNS.values()
    ]
    r1, r2, r3 = table.to_dict(orient="records")
    assert r1["path"].endswith("r1.jsonl") and r1["kind"] == "script"
    assert (r1["confirmed"], r1["healed"], r1["faults"], r1["heals"]) == (1, 1, 2, 1)
    assert r1["span_s"] == 6.0 and r1["messages"] == 6
    assert r1["top_codes"] == [
        {"fault_code": "A", "failed_reports": 1},
        {"fault_code": "B", "failed_reports": 1},
    ]
    assert r2["confirmed_codes"] == ["B", "A", "C"]
    assert r2["top_codes"][0] == {"fault_code": "A", "failed_reports": 5}  # 1 + 4 to reconfirm
    assert pd.isna(r1["budget"]) and pd.isna(r1["error"])
    assert r3["error"].endswith("r3.mcap: not an MCAP file (bad magic)")
    for column in ("span_s", "messages", "faults", "confirmed", "heals", "warnings"):
        assert pd.isna(r3[column])


def test_overview(tmp_path: Path) -> None:
    runs = crafted(tmp_path)
    assert overview(runs) == {
        "runs": 3,
        "replayed": 2,
        "failed": 1,
        "messages": runs[0].messages + runs[1].messages,  # type: ignore[operator]
        "runs_with_confirmed": 2,
    }
    judged = [
        RunSummary(path="a", kind="script", messages=1, budget="pass"),
        RunSummary(path="b", kind="script", messages=1, budget="fail"),
        RunSummary(path="c", kind="script", messages=1, budget="fail"),
    ]
    assert overview(judged)["budget_fail"] == 2
    assert overview(judged)["budget_pass"] == 1


def test_no_runs_and_no_confirmations() -> None:
    assert len(codes_table([])) == 0
    assert list(codes_table([]).columns) == list(CODE_COLUMNS)
    quiet = RunSummary(path="q", kind="script", messages=3, start_ns=0, end_ns=SEC)
    assert len(codes_table([quiet])) == 0
    row = runs_table([quiet]).iloc[0]
    assert row["span_s"] == 1.0 and not math.isnan(row["span_s"])
