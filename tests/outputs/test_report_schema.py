"""docs/report.schema.json describes the JSON report: real reports validate, and it names every
key and record field the report writes, in the report's order."""

from __future__ import annotations

import json
from dataclasses import fields
from pathlib import Path

import jsonschema
import pytest

from medkit_replay import captures, model
from medkit_replay.cli import main
from medkit_replay.releases import RELEASES

ROOT = Path(__file__).resolve().parents[2]
SCHEMA = json.loads((ROOT / "docs" / "report.schema.json").read_text(encoding="utf-8"))
NAV2 = ["--config", "rules/nav2/fault_manager.yaml", "--config", "rules/nav2/bridges.yaml"]
CASES = {
    "recordings and near misses": [
        "sample_bags/nav2_mission_mcap",
        "--config",
        "rules/bringup/fault_manager.yaml",
        "--config",
        "rules/nav2/bridges.yaml",
    ],
    "clusters, clears, retroactive mutes": ["examples/nav2_mission.jsonl", *NAV2],
    "parity with recorded events": ["sample_bags/service_calls.mcap", *NAV2],
    "freeze frames": [
        "sample_bags/nav2_mission_mcap",
        *NAV2,
        "--config",
        "examples/evidence/capture.yaml",
        "--graph",
        "examples/evidence/nav2_graph.txt",
    ],
}


def test_the_schema_is_valid_draft_2020_12() -> None:
    jsonschema.Draft202012Validator.check_schema(SCHEMA)


def test_the_release_is_one_the_replay_models() -> None:
    assert SCHEMA["properties"]["upstream_release"]["enum"] == list(RELEASES)


@pytest.mark.parametrize("case", list(CASES))
def test_real_reports_validate_key_by_key_in_order(
    case: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(ROOT)
    out = tmp_path / "report.json"
    assert main(["analyze", *CASES[case], "--json", str(out), "--quiet"]) == 0
    report = json.loads(out.read_text())
    jsonschema.Draft202012Validator(SCHEMA).validate(report)
    assert list(report) == list(SCHEMA["properties"]) == SCHEMA["required"]
    written = {
        "freeze frames": "snapshots",
        "parity with recorded events": "parity",
        "recordings and near misses": "recordings",
        "clusters, clears, retroactive mutes": "retroactive_cluster_mutes",
    }[case]
    assert report[written], f"the case writes no {written}: it checks nothing of them"


def test_a_report_of_0_6_0_validates_too(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    release = tmp_path / "release.yaml"
    release.write_text('medkit_replay:\n  ros__parameters:\n    upstream_release: "0.6.0"\n')
    out = tmp_path / "report.json"
    argv = ["analyze", "examples/nav2_mission.jsonl", *NAV2, "--config", str(release)]
    assert main([*argv, "--json", str(out), "--quiet"]) == 0
    report = json.loads(out.read_text())
    assert report["upstream_release"] == "0.6.0"
    jsonschema.Draft202012Validator(SCHEMA).validate(report)


@pytest.mark.parametrize("name", sorted(SCHEMA["$defs"]))
def test_every_record_lists_its_fields_in_order(name: str) -> None:
    # The report writes a record's fields in declaration order (outputs/json_report.py).
    record = SCHEMA["$defs"][name]
    cls = getattr(model, name, None) or getattr(captures, name)  # the evidence values: captures
    names = [field.name for field in fields(cls)]
    assert list(record["properties"]) == names == record["required"]
    assert record["additionalProperties"] is False
