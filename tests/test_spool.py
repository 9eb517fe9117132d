"""Spool: a list that spills to a temporary file, and the report streamed from spilled records."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from medkit_replay import replay, spool
from medkit_replay.model import EVENT_ROWS, FaultEvent
from medkit_replay.outputs.json_report import dumps, to_report
from medkit_replay.spool import Spool
from tests.gateway.values import fault

ROOT = Path(__file__).resolve().parent.parent
EVENT = FaultEvent(t_ns=0, event_type="fault_confirmed", fault=fault("MOTOR_OVERHEAT"))


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


@pytest.mark.parametrize("chunk", [1, 3, 7, 100])
@pytest.mark.parametrize("codec", [False, True])
def test_iter_from_starts_at_any_index(chunk: int, codec: bool) -> None:
    # chunk 100: nothing spilled, the tail only; the others: spilled chunks and a tail.
    items: Spool[FaultEvent] = Spool(chunk, codec=EVENT_ROWS if codec else None)
    expected = [replace(EVENT, t_ns=i) for i in range(25)]
    for event in expected:
        items.append(event)
    for start in range(30):
        assert list(items.iter_from(start)) == expected[start:]
    with pytest.raises(ValueError, match="-1"):
        items.iter_from(-1)
    items.close()


def test_iter_from_reads_no_chunk_before_its_start(monkeypatch: pytest.MonkeyPatch) -> None:
    items: Spool[int] = Spool(4)
    for i in range(20):
        items.append(i)
    read: list[int] = []
    chunk = items._chunk

    def logged(index: int) -> list[object]:
        read.append(index)
        return chunk(index)

    monkeypatch.setattr(items, "_chunk", logged)
    assert list(items.iter_from(13)) == list(range(13, 20))
    assert read == [3, 4]
    items.close()
