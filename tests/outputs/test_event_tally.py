"""The engine's count of each fault's FaultEvents, published and withheld, is the one the records
say, and the terminal summary draws muting from it without reading the spooled records back.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.outputs.muting import event_counts
from medkit_replay.outputs.terminal import render_summary
from medkit_replay.pipeline import replay

if TYPE_CHECKING:
    from collections.abc import Iterator

    from medkit_replay.model import EventTally, FaultEvent, ReportRecord
    from medkit_replay.result import Result

ROOT = Path(__file__).resolve().parents[2]
MISSION = ROOT / "sample_bags" / "nav2_mission_mcap"
RULES = [ROOT / "rules" / "nav2" / "fault_manager.yaml", ROOT / "rules" / "nav2" / "bridges.yaml"]


class Unread(list):  # type: ignore[type-arg]
    """Records an output must not read back (their length is free, as a spool's is)."""

    def __iter__(self) -> Iterator[FaultEvent | ReportRecord]:
        raise AssertionError("the records were read back")


def tally_from_records(result: Result) -> EventTally:
    """The oracle: each code's FaultEvents by kind, counted from the records themselves."""
    withheld: dict[str, dict[str, int]] = {}
    for report in result.reports:
        if report.withheld_event is not None:
            counts = withheld.setdefault(report.fault_code, {})
            counts[report.withheld_event] = counts.get(report.withheld_event, 0) + 1
    published: dict[str, dict[str, int]] = {}
    for event in result.events:
        counts = published.setdefault(event.fault.fault_code, {})
        counts[event.event_type] = counts.get(event.event_type, 0) + 1
    return published, withheld


def test_the_engine_counts_what_the_records_say() -> None:
    result = replay([MISSION], RULES)
    assert result.event_tally != ({}, {})
    counted = event_counts(replace(result, event_tally=tally_from_records(result)))
    assert any(events.withheld for events in counted.values())  # the sample mutes
    assert event_counts(result) == counted


def test_muting_is_drawn_without_reading_the_records_back() -> None:
    result = replay([MISSION], RULES)
    assert result.muted_faults
    unread = replace(result, events=Unread(result.events), reports=Unread(result.reports))
    assert render_summary(unread, everything=True) == render_summary(result, everything=True)
