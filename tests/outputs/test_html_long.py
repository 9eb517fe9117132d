"""The page of a long, dense mission: light, and down-sampled without losing what matters.

Dense series are thinned for drawing, but every status change stays in the counter trace, and
every kind of marker stays in every stretch of the timeline where it happened (the rare ones,
confirmed and cleared, each at its own instant). Not a timed test.
"""

from __future__ import annotations

from collections import defaultdict
from typing import TYPE_CHECKING

import pytest

from medkit_replay.outputs.html import render_html
from medkit_replay.outputs.html_timeline import (
    MARKER_BINS,
    MARKER_CAP,
    TRACE_BINS,
    TRACE_CAP,
    Span,
    build_lanes,
)
from medkit_replay.result import STATUSES
from tests.outputs.html_support import Page, long_mission

if TYPE_CHECKING:
    from medkit_replay.outputs.html_timeline import Lane
    from medkit_replay.result import Result

PAGE_LIMIT = 10 * 1024 * 1024


@pytest.fixture(scope="module")
def mission(tmp_path_factory: pytest.TempPathFactory) -> Result:
    return long_mission(tmp_path_factory.mktemp("long"))


@pytest.fixture(scope="module")
def lanes(mission: Result) -> dict[str, Lane]:
    return {lane.fault.fault_code: lane for lane in build_lanes(mission, Span.of(mission))}


def test_the_mission_is_dense_enough_to_downsample(mission: Result, lanes: dict[str, Lane]) -> None:
    dense = lanes["DENSE"]
    assert dense.trace_count > 10 * TRACE_CAP and len(dense.trace) < dense.trace_count / 10
    assert dense.marker_count > 10 * MARKER_CAP and len(dense.markers) < dense.marker_count / 10
    flappy = lanes["FLAPPY"]
    assert flappy.band_periods > 200 and any("downsampled" in b.tip for b in flappy.bands)


def test_every_status_change_stays_in_the_trace(mission: Result, lanes: dict[str, Lane]) -> None:
    span = Span.of(mission)
    changes = defaultdict(list)
    for transition in mission.transitions:
        if transition.cause == "report":
            changes[transition.fault_code].append(
                (span.seconds(transition.t_ns), STATUSES.index(transition.to_status))
            )
    assert len(changes["DENSE"]) >= 20 and len(changes["FLAPPY"]) >= 400
    for code, expected in changes.items():
        drawn = {(point[0], point[5]) for point in lanes[code].trace}
        assert [change for change in expected if change not in drawn] == [], code
    assert len(lanes["FLAPPY"].trace) <= 2 * TRACE_BINS + TRACE_CAP


def test_no_event_marker_is_lost(mission: Result, lanes: dict[str, Lane]) -> None:
    span = Span.of(mission)
    events = defaultdict(list)
    for event in mission.events:
        events[event.fault.fault_code, event.event_type].append(event.t_ns)
    for (code, kind), times in events.items():
        drawn = [m.t_ns for m in lanes[code].markers if m.kind == kind]
        if len(times) < MARKER_CAP:  # a rare kind: every one at its instant
            assert drawn == times, (code, kind)
        else:  # a dense kind: in every time bin it happened in
            assert {span.bin(t, MARKER_BINS) for t in drawn} == {
                span.bin(t, MARKER_BINS) for t in times
            }, (code, kind)
    assert len(events["DENSE", "fault_updated"]) > 10_000


def test_the_page_stays_light(mission: Result) -> None:
    text = render_html(mission)
    assert len(text.encode("utf-8")) < PAGE_LIMIT / 4
    page = Page(text)
    data_lanes = {lane["code"]: lane for lane in page.lanes()}
    assert set(data_lanes) == {"DENSE", "FLAPPY", "QUIET"}
    assert data_lanes["DENSE"]["trace_count"] == len(
        [r for r in mission.reports if r.fault_code == "DENSE" and r.debounce_counter is not None]
    )
