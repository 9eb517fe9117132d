"""Every sweep row agrees with ``analyze`` (``replay``) run with that variant's config: the base
configs, then the variant's parameter file the sweep writes under ``variants/``."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from medkit_replay.cli import main
from medkit_replay.pipeline import replay
from tests.tuning.oracle import as_cell, code_figures, run_figures

if TYPE_CHECKING:
    from collections.abc import Iterator

ROOT = Path(__file__).resolve().parents[2]
BAG = ROOT / "sample_bags" / "nav2_mission_mcap"
SCRIPT = ROOT / "examples" / "nav2_mission.jsonl"
NAV2 = ROOT / "rules" / "nav2"

OTHER_RULES = """correlation:
  enabled: true
  default_window_ms: 3000
  patterns:
    anything: {codes: ["*"]}
  rules:
    - id: storm
      mode: auto_cluster
      match: [{pattern: anything}]
      min_count: 2
      window_ms: 3000
    - id: actions_follow_logs
      root_cause: {codes: ["LOG_*"]}
      symptoms: [{codes: ["ACTION_*"]}]
      window_ms: 10000
"""


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="", encoding="utf-8") as stream:
        return list(csv.DictReader(stream))


@pytest.fixture(scope="module")
def swept(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    folder = tmp_path_factory.mktemp("sweep")
    other = folder / "other_rules.yaml"
    other.write_text(OTHER_RULES, encoding="utf-8")
    out = folder / "out"
    status = main(
        [
            "sweep",
            str(BAG),
            str(SCRIPT),
            "--config",
            str(NAV2 / "fault_manager.yaml"),
            "--config",
            str(NAV2 / "bridges.yaml"),
            "--vary",
            "fault_manager.confirmation_threshold=-1,-2",
            "--vary",
            f"fault_manager.correlation.config_file={NAV2 / 'correlation.yaml'},{other},",
            "--vary",
            "action_status_bridge.canceled_is_fault=false,true",
            "--vary",
            "fault_manager.auto_confirm_after_sec=0.0,1.5",
            "--out",
            str(out),
            "--jobs",
            "1",
            "--quiet",
        ]
    )
    assert status == 0
    yield out


def test_every_row_agrees_with_a_replay_of_its_variant(swept: Path) -> None:
    runs = _rows(swept / "runs.csv")
    codes = _rows(swept / "run_codes.csv")
    assert len(runs) == 2 * 24
    configs = [NAV2 / "fault_manager.yaml", NAV2 / "bridges.yaml"]
    checked = 0
    for row in runs:
        assert row["error"] == ""
        variant_file = swept / "variants" / f"{row['variant']}.yaml"
        result = replay([row["input"]], [*configs, variant_file])
        for name, value in run_figures(result).items():
            assert row[name] == as_cell(value), (row["variant"], row["input"], name)
        expected = code_figures(result)
        got = {
            c["fault_code"]: c
            for c in codes
            if c["variant"] == row["variant"] and c["input"] == row["input"]
        }
        assert sorted(got) == sorted(expected)
        for code, figures in expected.items():
            for name, value in figures.items():
                assert got[code][name] == as_cell(value), (row["variant"], code, name)
        confirmed = sum(1 for f in expected.values() if f["confirmations"])
        assert row["faults_confirmed"] == str(confirmed)
        checked += 1
    assert checked == 48


def test_the_grid_makes_a_difference(swept: Path) -> None:
    """The varied settings change the figures (so the test above compares something)."""
    runs = [r for r in _rows(swept / "runs.csv") if r["input"] == str(BAG)]
    assert len({(r["events"], r["flaps"], r["muted_events"]) for r in runs}) > 4
    bridges = {r["action_status_bridge.canceled_is_fault"]: r["reports"] for r in runs}
    assert bridges["True"] != bridges["False"]
    muted = {r["fault_manager.correlation.config_file"]: r["muted_events"] for r in runs}
    assert muted[""] == "0"
