"""The bulk JSON encoder against the stdlib one it replaced: the same bytes for any records.

Adversarial text (lone surrogates, U+2028, bidirectional controls, DEL, controls, quotes,
backslashes, the batch boundary ``}, "", {`` itself) and numbers (beyond 64 bits, negative), in
records held in lists and in spools that spilled rows to disk.
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Any
from unittest.mock import patch

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from medkit_replay.model import (
    CLEAR_ROWS,
    EVENT_ROWS,
    REPORT_ROWS,
    TRANSITION_ROWS,
    ClearRecord,
    FaultEvent,
    FaultSnapshot,
    NearMiss,
    ReportRecord,
    Transition,
)
from medkit_replay.outputs import json_rows
from medkit_replay.outputs.json_report import dumps, to_report, write_json_bytes
from medkit_replay.outputs.json_rows import RecordLines
from medkit_replay.result import Result, Summary
from medkit_replay.spool import Spool
from tests.oracle.json_report import stdlib_dumps

if TYPE_CHECKING:
    from collections.abc import Iterator
    from pathlib import Path

    from medkit_replay.rows import RecordRows

PIECES = [
    '}, "", {',
    '"',
    "\\",
    "\\u0000",
    "\ud800",
    "\udfff",
    "\ud83d\ude00",
    "\U0001f600",
    "\u2028",
    "\u2029",
    "\u202e",
    "\u061c",
    "\x7f",
    "\x00",
    "\x1b[31m",
    "\n",
    "\t",
    "\x85",
    "\ufeff",
    "é",
    "</script>",
    ", ",
    ": ",
]
texts = st.lists(
    st.one_of(st.text(st.characters(exclude_categories=()), max_size=6), st.sampled_from(PIECES)),
    max_size=5,
).map("".join)
numbers = st.one_of(
    st.integers(min_value=-(2**70), max_value=2**70),
    st.sampled_from([0, -1, 2**63 - 1, 2**63, 2**64, -(2**63) - 1, 10**40]),
)
maybe_text = st.none() | texts
statuses = st.sampled_from(["PREFAILED", "PREPASSED", "CONFIRMED", "HEALED", "CLEARED"])
text_tuples = st.lists(texts, max_size=3).map(tuple)

snapshots = st.builds(
    FaultSnapshot,
    fault_code=texts,
    severity=numbers,
    description=texts,
    first_occurred_ns=numbers,
    last_occurred_ns=numbers,
    last_passed_ns=numbers,
    occurrence_count=numbers,
    status=statuses,
    reporting_sources=text_tuples,
    muted=st.booleans(),
    root_cause_code=maybe_text,
    cluster_ids=text_tuples,
)
events = st.builds(
    FaultEvent,
    t_ns=numbers,
    event_type=st.sampled_from(["fault_confirmed", "fault_updated", "fault_cleared"]),
    fault=snapshots,
    auto_cleared_codes=text_tuples,
)
transitions = st.builds(
    Transition,
    t_ns=numbers,
    fault_code=texts,
    from_status=st.none() | statuses,
    to_status=statuses,
    cause=st.sampled_from(["report", "auto_confirm", "clear", "auto_clear"]),
    source_id=maybe_text,
)
reports = st.builds(
    ReportRecord,
    t_ns=numbers,
    origin=st.sampled_from(["report_fault", "log_bridge", "script"]),
    topic=maybe_text,
    fault_code=texts,
    event_type=texts,
    severity=numbers,
    description=texts,
    source_id=texts,
    accepted=st.booleans(),
    reject_reason=maybe_text,
    status=st.none() | statuses,
    debounce_counter=st.none() | numbers,
    confirmation_threshold=st.none() | numbers,
    healing_threshold=st.none() | numbers,
    withheld_event=st.none() | st.just("fault_confirmed"),
)
clears = st.builds(
    ClearRecord,
    t_ns=numbers,
    fault_code=texts,
    skip_correlation_auto_clear=st.booleans(),
    success=st.booleans(),
    message=texts,
    auto_cleared_codes=text_tuples,
)
near_misses = st.builds(
    NearMiss,
    fault_code=texts,
    t_ns=numbers,
    debounce_counter=numbers,
    confirmation_threshold=numbers,
    severity=numbers,
    source_id=texts,
    resulting_status=statuses,
)


def _spooled(records: list[Any], codec: RecordRows[Any], chunk: int, as_rows: bool) -> Spool[Any]:
    """A spool that spilled most of ``records`` to disk; some appended as rows."""
    spool: Spool[Any] = Spool(chunk, codec=codec)
    for number, record in enumerate(records):
        if as_rows and number % 2:
            spool.append_row(codec.encode(record))
        else:
            spool.append(record)
    return spool


def _result(
    lists: tuple[list[Any], ...], near: list[NearMiss], warnings: list[str], spooled: int
) -> Result:
    ev, tr, rp, cl = lists
    if spooled:
        ev = _spooled(ev, EVENT_ROWS, spooled, as_rows=True)  # type: ignore[assignment]
        tr = _spooled(tr, TRANSITION_ROWS, spooled, as_rows=False)  # type: ignore[assignment]
        rp = _spooled(rp, REPORT_ROWS, spooled, as_rows=True)  # type: ignore[assignment]
        cl = _spooled(cl, CLEAR_ROWS, spooled, as_rows=True)  # type: ignore[assignment]
    summary = Summary(
        messages_read=0,
        reports=len(rp),
        reports_accepted=0,
        reports_rejected=0,
        clears=len(cl),
        events={},
        faults=0,
        faults_by_status={},
        transitions=len(tr),
        start_ns=None,
        end_ns=None,
    )
    return Result(
        tool_version="0.1.0",
        inputs=(),
        faults=(),
        events=ev,
        transitions=tr,
        reports=rp,
        clears=cl,
        muted_faults=(),
        clusters=(),
        near_misses=tuple(near),
        warnings=tuple(warnings),
        summary=summary,
    )


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    ev=st.lists(events, max_size=6),
    tr=st.lists(transitions, max_size=6),
    rp=st.lists(reports, max_size=6),
    cl=st.lists(clears, max_size=4),
    near=st.lists(near_misses, max_size=4),
    warnings=st.lists(texts, max_size=2),
    spooled=st.sampled_from([0, 1, 2, 5]),
)
def test_bulk_report_matches_the_stdlib_encoder(
    ev: list[FaultEvent],
    tr: list[Transition],
    rp: list[ReportRecord],
    cl: list[ClearRecord],
    near: list[NearMiss],
    warnings: list[str],
    spooled: int,
) -> None:
    result = _result((ev, tr, rp, cl), near, warnings, spooled)
    expected = stdlib_dumps(result)
    fallbacks: list[int] = []
    stdlib = RecordLines._stdlib

    def counted(self: RecordLines, records: Any) -> bytes | memoryview:
        fallbacks.append(1)
        return stdlib(self, records)

    with patch.object(RecordLines, "_stdlib", counted):
        assert dumps(result) == expected
    assert expected.isascii()
    # Only a lone surrogate (which UTF-8 cannot carry) sends a batch to the stdlib encoder.
    assert bool(fallbacks) <= any(map(_has_surrogate, _strings(to_report(result))))


def _strings(value: object) -> Iterator[str]:
    if isinstance(value, str):
        yield value
    elif isinstance(value, dict):
        for item in value.values():
            yield from _strings(item)
    elif isinstance(value, list | tuple):
        for item in value:
            yield from _strings(item)


def _has_surrogate(text: str) -> bool:
    return any("\ud800" <= char <= "\udfff" for char in text)


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(rp=st.lists(reports, min_size=1, max_size=40), spooled=st.sampled_from([0, 4]))
def test_batches_meet_exactly(
    rp: list[ReportRecord], spooled: int, monkeypatch_batch: None
) -> None:
    """Records split over many small batches join as one list (BATCH is 3 here; the fixture
    only sets that constant, so sharing it between examples is harmless)."""
    result = _result(([], [], rp, []), [], [], spooled=spooled)
    assert dumps(result) == stdlib_dumps(result)


@pytest.fixture
def monkeypatch_batch(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(json_rows, "BATCH", 3)


def test_binary_and_text_writers_agree(tmp_path: Path) -> None:
    record = ReportRecord(
        t_ns=1,
        origin="script",
        topic=None,
        fault_code="X\u2028\ud800",
        event_type="FAILED",
        severity=2,
        description='é}, "", {',
        source_id="/s",
        accepted=True,
        reject_reason=None,
    )
    result = _result(([], [], [record] * 3, []), [], [], spooled=2)
    target = tmp_path / "report.json"
    with target.open("wb") as stream:
        write_json_bytes(result, stream)
    assert target.read_text("ascii") == dumps(result) == stdlib_dumps(result)
    assert json.loads(dumps(result))["reports"][0]["fault_code"] == "X\u2028\ud800"


def test_a_class_with_a_float_is_left_to_the_stdlib() -> None:
    """Floats would print differently (and NaN as null): such a class never goes in bulk."""
    from dataclasses import dataclass  # noqa: PLC0415

    @dataclass(frozen=True)
    class Sample:
        t_ns: int
        ratio: float

    lines = RecordLines(Sample, lambda s: {"t_ns": s.t_ns, "ratio": s.ratio})
    assert b"".join(lines.chunks([Sample(1, 1e16), Sample(2, 0.1)])) == (
        b'{"t_ns": 1, "ratio": 1e+16},\n    {"t_ns": 2, "ratio": 0.1}'
    )
    with pytest.raises(ValueError, match="not JSON compliant"):
        b"".join(lines.chunks([Sample(3, float("nan"))]))
