"""Spool: a list that spills to a temporary file, and the report streamed from spilled records."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from medkit_replay import replay, spool
from medkit_replay.outputs.json_report import dumps, to_report
from medkit_replay.spool import Spool

ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.parametrize("chunk", [1, 3, 7, 100])
def test_spool_behaves_like_a_list(chunk: int) -> None:
    items: Spool[int] = Spool(chunk)
    expected = list(range(25))
    for i in expected:
        items.append(i)
    assert len(items) == 25
    assert list(items) == expected
    assert [items[i] for i in range(-25, 25)] == expected + expected
    assert items[5:12] == expected[5:12]
    assert items == expected
    with pytest.raises(IndexError):
        items[25]
    items.close()


def test_report_from_spilled_records_is_byte_identical(monkeypatch: pytest.MonkeyPatch) -> None:
    args = ([ROOT / "examples" / "nav2_mission.jsonl"], [ROOT / "rules/nav2/fault_manager.yaml"])
    in_memory = dumps(replay(*args))
    monkeypatch.setattr(spool, "DEFAULT_CHUNK", 2)
    result = replay(*args)
    assert dumps(result) == in_memory
    assert json.loads(dumps(result)) == to_report(result)
