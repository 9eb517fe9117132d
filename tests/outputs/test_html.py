"""The HTML report: structure, escaping of hostile recording text, determinism, offline, bounds."""

from __future__ import annotations

import base64
import hashlib
import json
import os
import re
import subprocess
import sys
from dataclasses import replace
from typing import TYPE_CHECKING

import pytest

from medkit_replay.outputs.html import render_html, script_json, write_html
from medkit_replay.outputs.html_tables import TABLE_CAP
from medkit_replay.outputs.html_timeline import (
    BAND_BINS,
    MARKER_BINS,
    TRACE_BINS,
    TRACE_CAP,
    Span,
    build_lanes,
)
from medkit_replay.pipeline import replay
from tests.outputs.html_support import (
    MS,
    ROOT,
    SEC,
    Page,
    example_result,
    report,
    write_script,
)

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.result import Result

HOSTILE = "</script><img src=x onerror=alert(1)>"
HOSTILE_SOURCE = '/m"><script>alert(2)</script>'
HOSTILE_QUOTE = "/m' onmouseover='alert(3)"
SEPARATORS = "line\u2028para\u2029end"
AMP = "a & b <c> \"d\" 'e' "


@pytest.fixture(scope="module")
def mission() -> Result:
    """The bundled Nav2 mission script under the Nav2 rules."""
    return example_result()


@pytest.fixture(scope="module")
def mission_page(mission: Result) -> str:
    """Its page."""
    return render_html(mission)


def hostile_result(tmp_path: Path) -> Result:
    """Descriptions, sources, a file name, warnings and config made to break out of HTML."""
    path = write_script(
        tmp_path / "run<img src=y onerror=alert(4)>&.jsonl",
        [
            report(
                SEC,
                "MOTOR_OVERHEAT",
                "FAILED",
                severity=2,
                description=HOSTILE,
                source_id=HOSTILE_SOURCE,
            ),
            report(
                2 * SEC,
                "MOTOR_OVERHEAT",
                "FAILED",
                description=SEPARATORS,
                source_id=HOSTILE_QUOTE,
            ),
            report(3 * SEC, "BATTERY_LOW", "FAILED", severity=3, description=AMP + HOSTILE),
            {"t_ns": 4 * SEC, "op": "clear", "fault_code": "MOTOR_OVERHEAT"},
            report(5 * SEC, "bad </script> code", "FAILED", description=HOSTILE),
        ],
    )
    result = replay([path])
    return replace(
        result,
        warnings=(HOSTILE, f"topic {HOSTILE_SOURCE} could not be decoded"),
        config={**result.config, "note": HOSTILE},
        parity={"verdict": "differ", "missing": [{"fault_code": HOSTILE}], "matched": 1},
    )


# ---------------------------------------------------------------- structure


def test_one_timeline_row_per_fault_in_code_order(mission: Result, mission_page: str) -> None:
    page = Page(mission_page)
    rows = page.with_class("fault-row")
    assert [r["data-code"] for r in rows] == [f.fault_code for f in mission.faults]
    assert len(rows) == 8
    assert [r["data-index"] for r in rows] == [str(i) for i in range(8)]
    assert [lane["code"] for lane in page.lanes()] == [f.fault_code for f in mission.faults]


def test_page_has_every_section(mission_page: str) -> None:
    page = Page(mission_page)
    for element_id in (
        "warnings",
        "inputs",
        "timeline",
        "tl-scroll",
        "tl-axis",
        "correlation",
        "muted-table",
        "retro-table",
        "records",
        "faults-table",
        "events-table",
        "reports-table",
        "transitions-table",
        "clears-table",
        "config",
    ):
        assert page.by_id(element_id) is not None, element_id
    assert page.by_id("parity") is None  # the script holds no recorded FaultEvents
    assert len(page.with_class("tick")) == 11  # an axis even without JavaScript
    assert [a.get("data-zoom") for a in page.with_class("tl-toolbar")] == [None]
    assert {a["data-zoom"] for t, a in page.tags if t == "button"} == {"in", "out", "reset"}
    assert len(page.with_class("sortable")) == 7
    assert len(page.with_class("filter")) == 7


def test_header_shows_span_inputs_and_counts(mission_page: str) -> None:
    assert "25.000 s of bag time, from 1000000000 ns to 26000000000 ns" in mission_page
    assert "examples/nav2_mission.jsonl" in mission_page
    assert "12 accepted · 1 rejected" in mission_page
    assert '<span class="badge s-CONFIRMED">CONFIRMED 4</span>' in mission_page
    assert "No warnings." in mission_page


def test_bands_follow_transitions(mission: Result) -> None:
    span = Span.of(mission)
    lanes = {lane.fault.fault_code: lane for lane in build_lanes(mission, span)}
    lidar = lanes["LIDAR_SCAN_DROPOUT"].bands
    assert [(b.status, b.start_ns, b.end_ns) for b in lidar] == [
        ("CONFIRMED", 1 * SEC, 5 * SEC),
        ("HEALED", 5 * SEC, 26 * SEC),
    ]
    motor = lanes["MOTOR_OVERHEAT"]
    assert [b.status for b in motor.bands] == ["CONFIRMED", "CLEARED"]
    assert [m.kind for m in motor.markers] == ["fault_confirmed", "fault_cleared", "clear"]
    assert "entered by report from /powertrain/motor_left" in motor.bands[0].tip
    symptom = lanes["MOTOR_LEFT_COMM_TIMEOUT"]
    assert [b.status for b in symptom.bands] == ["CONFIRMED", "CLEARED"]
    assert "entered by auto_clear" in symptom.bands[1].tip


def test_counter_trace_and_thresholds_come_from_reports(mission: Result) -> None:
    page = Page(render_html(mission))
    lanes = {lane["code"]: lane for lane in page.lanes()}
    lidar = lanes["LIDAR_SCAN_DROPOUT"]
    expected = [
        [
            round((r.t_ns - SEC) / SEC, 6),
            r.debounce_counter,
            r.confirmation_threshold,
            r.healing_threshold,
            int(r.event_type == "PASSED"),
        ]
        for r in mission.reports
        if r.fault_code == "LIDAR_SCAN_DROPOUT" and r.accepted
    ]
    assert isinstance(lidar["trace"], list)
    assert [p[:5] for p in lidar["trace"]] == expected
    assert [p[1] for p in lidar["trace"]] == [-1, 0, 1, 2, 3]
    assert {p[2] for p in lidar["trace"]} == {-1} and {p[3] for p in lidar["trace"]} == {3}
    assert lidar["trace_count"] == 5 and lidar["near"] == [] and lidar["near_count"] == 0


def test_near_misses_are_embedded_per_fault(tmp_path: Path) -> None:
    config = tmp_path / "params.yaml"
    config.write_text(
        "fault_manager:\n  ros__parameters:\n    confirmation_threshold: -3\n", encoding="utf-8"
    )
    script = write_script(
        tmp_path / "near.jsonl",
        [
            report(1 * SEC, "WIFI", "FAILED", severity=1, source_id="/wifi"),
            report(2 * SEC, "WIFI", "FAILED", severity=1, source_id="/wifi"),
            report(3 * SEC, "WIFI", "PASSED", source_id="/wifi"),
        ],
    )
    page = Page(render_html(replay([script], [config])))
    (wifi,) = page.lanes()
    assert wifi["near"] == [
        [0.0, -1, -3, "WARN", "/wifi", "PREFAILED"],
        [1.0, -2, -3, "WARN", "/wifi", "PREFAILED"],
    ]
    assert wifi["near_count"] == 2


def test_correlation_is_explained(mission_page: str) -> None:
    page = Page(mission_page)
    assert "estop_cascade \u2014 E-stop stops everything" in mission_page
    assert "a symptom of root cause ESTOP_PRESSED (window 3000 ms). FaultEvents: " in mission_page
    assert "last muted 100 ms after its root ESTOP_PRESSED" in mission_page
    (cluster,) = page.with_class("cluster")
    assert cluster == {"class": "cluster"}
    assert "sensor_storm_1" in mission_page and "0.000 s \u2013 0.400 s (0.400 s)" in mission_page
    links = [a["data-open"] for a in page.with_class("code-link")]
    assert links == ["CAMERA_FRAME_TIMEOUT", "LIDAR_SCAN_DROPOUT", "CAMERA_FRAME_TIMEOUT"]
    assert "Retroactive cluster mutes (information only)" in mission_page


def test_config_parity_and_warnings(mission: Result) -> None:
    parity = {"verdict": "match", "recorded_events": 3, "differences": [], "missing": [{"a": 1}]}
    page_text = render_html(replace(mission, parity=parity, warnings=("first", "second")))
    page = Page(page_text)
    assert page.by_id("parity") is not None
    assert '<span class="verdict v-match">match</span>' in page_text
    assert "<dt>recorded_events</dt><dd>3</dd>" in page_text
    assert page.by_id("parity-missing") is not None  # a list of objects becomes a table
    assert page.by_id("warnings") == {"id": "warnings", "class": "warnings", "role": "alert"}
    assert "<li>first</li><li>second</li>" in page_text
    assert "&quot;confirmation_threshold&quot;: -1" in page_text  # the effective config


def test_tables_carry_sort_keys(mission_page: str) -> None:
    page = Page(mission_page)
    numeric = [a for t, a in page.tags if t == "th" and a.get("class") == "num"]
    assert numeric  # time and count columns sort as numbers
    assert '<td data-v="24100000000">24.100</td>' in mission_page
    assert '<td class="code">ESTOP_PRESSED</td>' in mission_page


def test_empty_recording_renders(tmp_path: Path) -> None:
    script = tmp_path / "empty.jsonl"
    script.write_text("# nothing\n", encoding="utf-8")
    text = render_html(replay([script]))
    page = Page(text)
    assert page.with_class("fault-row") == []
    assert "No fault was reported." in text and "nothing was read" in text
    assert page.lanes() == []


# ---------------------------------------------------------------- escaping


def test_hostile_text_stays_text(tmp_path: Path) -> None:
    result = hostile_result(tmp_path)
    text = render_html(result)
    page = Page(text)
    assert HOSTILE not in text and HOSTILE_SOURCE not in text
    assert not any(tag in {"img", "iframe", "object", "embed", "link"} for tag, _ in page.tags)
    handlers = [name for _, attrs in page.tags for name in attrs if name.startswith("on")]
    assert handlers == []
    assert text.count("<script") == 2 and text.count("</script>") == 2
    assert [attrs for attrs, _ in page.scripts] == [
        {"type": "application/json", "id": "medkit-data"},
        {},
    ]
    assert len(page.with_class("fault-row")) == len(result.faults) == 2
    # The escaped text reads back exactly from the JSON for the script.
    lanes = {lane["code"]: lane for lane in page.lanes()}
    # The latest FAILED's; line and paragraph separators are shown as escapes.
    assert lanes["MOTOR_OVERHEAT"]["description"] == "line\\u2028para\\u2029end"
    assert lanes["MOTOR_OVERHEAT"]["sources"] == [HOSTILE_SOURCE, HOSTILE_QUOTE]
    assert lanes["BATTERY_LOW"]["description"] == AMP + HOSTILE
    data_text = next(t for a, t in page.scripts if a.get("id") == "medkit-data")
    for raw in ("<", ">", "&", "\u2028", "\u2029"):
        assert raw not in data_text
    assert "&lt;/script&gt;&lt;img src=x onerror=alert(1)&gt;" in text  # warnings, tables
    assert "run&lt;img src=y onerror=alert(4)&gt;&amp;.jsonl" in text  # the input's path


def test_hostile_text_in_attributes_is_quoted(tmp_path: Path) -> None:
    page = Page(render_html(hostile_result(tmp_path)))
    tips = [a.get("data-tip") or "" for a in page.with_class("fault-label")]
    motor = next(t for t in tips if t.startswith("MOTOR_OVERHEAT"))
    assert f"sources: {HOSTILE_SOURCE}, {HOSTILE_QUOTE}" in motor  # parsed back whole
    assert [a["data-code"] for a in page.with_class("fault-row")] == [
        "BATTERY_LOW",
        "MOTOR_OVERHEAT",
    ]


def test_rejected_code_is_listed_escaped(tmp_path: Path) -> None:
    text = render_html(hostile_result(tmp_path))
    assert "bad &lt;/script&gt; code" in text  # the reports table keeps the rejected request
    assert "bad </script> code" not in text


def test_script_json_escapes_what_could_end_a_script() -> None:
    value = {"d": "</script><!-- & \u2028 \u2029 >", "n": [1, None, True]}
    text = script_json(value)
    assert re.search(r"[<>&\u2028\u2029]", text) is None
    assert json.loads(text) == value


# ---------------------------------------------------------------- determinism and offline


def test_same_result_same_bytes(tmp_path: Path) -> None:
    first, second = example_result(), example_result()
    assert render_html(first) == render_html(second)
    write_html(first, tmp_path / "a.html")
    write_html(second, tmp_path / "b.html")
    assert (tmp_path / "a.html").read_bytes() == (tmp_path / "b.html").read_bytes()
    assert (tmp_path / "a.html").read_bytes() == render_html(first).encode("utf-8")


def test_same_bytes_whatever_the_hash_seed() -> None:
    code = (
        "import hashlib; from tests.outputs.html_support import example_result;"
        "from medkit_replay.outputs.html import render_html;"
        "print(hashlib.sha256(render_html(example_result()).encode()).hexdigest())"
    )
    digests = {
        subprocess.run(
            [sys.executable, "-c", code],
            env={**os.environ, "PYTHONHASHSEED": seed},
            cwd=ROOT,
            capture_output=True,
            text=True,
            check=True,
        ).stdout
        for seed in ("1", "2")
    }
    assert len(digests) == 1


def test_no_generation_stamp_or_random_id(mission_page: str) -> None:
    ids = [a["id"] for _, a in Page(mission_page).tags if a.get("id")]
    assert len(ids) == len(set(ids))
    assert all(re.fullmatch(r"[a-z][a-z0-9-]*", i or "") for i in ids)


def test_offline(mission_page: str) -> None:
    assert "http://" not in mission_page and "https://" not in mission_page
    page = Page(mission_page)
    refs = [a[name] for _, a in page.tags for name in ("src", "href", "action") if name in a]
    assert refs == []
    lowered = mission_page.lower()
    for needle in ("<link", "<iframe", "@import", "url(", "fetch(", "xmlhttprequest", "eval("):
        assert needle not in lowered, needle
    assert "new function" not in lowered


def test_policy_allows_only_the_inline_script(mission_page: str) -> None:
    page = Page(mission_page)
    (policy,) = [a["content"] for t, a in page.tags if t == "meta" and "http-equiv" in a]
    assert policy is not None and "default-src 'none'" in policy
    script = next(text for attrs, text in page.scripts if not attrs)
    digest = base64.b64encode(hashlib.sha256(script.encode("utf-8")).digest()).decode()
    assert f"script-src 'sha256-{digest}'" in policy


# ---------------------------------------------------------------- bounds


@pytest.fixture(scope="module")
def flapping(tmp_path_factory: pytest.TempPathFactory) -> Result:
    """4000 reports of one fault confirming and healing a thousand times."""
    folder = tmp_path_factory.mktemp("flap")
    config = folder / "params.yaml"
    config.write_text(
        "fault_manager:\n  ros__parameters:\n    confirmation_threshold: -1\n"
        "    healing_enabled: true\n    healing_threshold: 1\n",
        encoding="utf-8",
    )
    pattern = ["FAILED", "FAILED", "PASSED", "PASSED"]
    lines = [report((i + 1) * 10 * MS, "FLAP", pattern[i % 4]) for i in range(4000)]
    lines.append(report(40_001 * MS, "STEADY", "FAILED"))
    return replay([write_script(folder / "flap.jsonl", lines)], [config])


def test_long_recordings_are_bounded(flapping: Result) -> None:
    assert len(flapping.reports) == 4001 and len(flapping.transitions) > 1000
    lanes = {lane.fault.fault_code: lane for lane in build_lanes(flapping, Span.of(flapping))}
    flap = lanes["FLAP"]
    assert flap.band_periods == len([t for t in flapping.transitions if t.fault_code == "FLAP"])
    assert 0 < len(flap.bands) <= BAND_BINS
    assert all("downsampled" in b.tip for b in flap.bands)
    assert flap.marker_count > 1000 and len(flap.markers) <= 4 * MARKER_BINS
    assert flap.trace_count == 4000 and len(flap.trace) <= min(TRACE_CAP, 2 * TRACE_BINS)
    assert {p[1] for p in flap.trace} == {-1, 1}  # lowest and highest per bin
    assert len(lanes["STEADY"].bands) == 1
    text = render_html(flapping)
    page = Page(text)
    assert len(page.with_class("fault-row")) == 2
    reports_rows = text.split('id="reports-table"')[1].split("</table>")[0].count("<tr>")
    assert reports_rows == TABLE_CAP + 1  # the header row, then the cap
    assert f"Showing the first {TABLE_CAP:,} of 4,001 rows" in text
    assert len(text) < 3_000_000


def test_bounding_is_deterministic(flapping: Result) -> None:
    assert render_html(flapping) == render_html(flapping)
