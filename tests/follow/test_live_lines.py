"""The lines follow prints: s from the start and the time of day, code, from -> to, cause, source;
recorded text escaped."""

from __future__ import annotations

from medkit_replay.model import FaultEvent, FaultSnapshot, Transition
from medkit_replay.outputs.live import bag_time, live_line, start_line

T0_NS = 1_773_480_413_047_999_250  # 2026-03-14 09:26:53.047 UTC


def test_a_transition_line() -> None:
    line = live_line(
        Transition(
            t_ns=T0_NS,
            fault_code="MOTOR_OVERHEAT",
            from_status="PREFAILED",
            to_status="CONFIRMED",
            cause="report",
            source_id="/powertrain/motor",
        ),
        T0_NS - 12_500_000_000,
    )
    assert line == (
        "12.500 s 09:26:53.047  MOTOR_OVERHEAT  PREFAILED -> CONFIRMED  "
        "(report, source /powertrain/motor)"
    )


def test_a_first_transition_and_recorded_text_escaped() -> None:
    line = live_line(
        Transition(
            t_ns=T0_NS,
            fault_code="EVIL\x1b[2J\nCODE",
            from_status=None,
            to_status="PREFAILED",
            cause="report",
            source_id=None,
        )
    )
    assert "\x1b" not in line and "\n" not in line
    assert "EVIL\\x1b[2J CODE  - -> PREFAILED  (report)" in line


def test_an_event_line() -> None:
    fault = FaultSnapshot(
        fault_code="BATTERY_LOW",
        severity=1,
        description="low",
        first_occurred_ns=T0_NS,
        last_occurred_ns=T0_NS,
        last_passed_ns=0,
        occurrence_count=1,
        status="CONFIRMED",
        reporting_sources=("/a", "/b", "/c", "/d"),
        muted=False,
        root_cause_code=None,
        cluster_ids=(),
    )
    line = live_line(FaultEvent(t_ns=T0_NS, event_type="fault_confirmed", fault=fault), T0_NS)
    assert line == (
        "0.000 s 09:26:53.047  BATTERY_LOW  event fault_confirmed "
        "(status CONFIRMED, sources /a, /b, /c +1)"
    )


def test_bag_times_that_are_not_dates() -> None:
    assert bag_time(12_345_000_000, 2_000_000_000) == "10.345 s"
    assert bag_time(12_345_000_000, None) == "t=12.345"


def test_the_start_header_and_a_line_before_the_start_is_known() -> None:
    assert start_line(T0_NS) == (
        "recording starts 2026-03-14 09:26:53.047 UTC: times are s from the start; "
        "then the time of day, UTC"
    )
    assert start_line(0) == "recording starts t = 0.000 s: times are s from the start"
    assert bag_time(T0_NS, None) == "09:26:53.047"
