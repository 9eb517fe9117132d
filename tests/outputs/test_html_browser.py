"""The HTML report in a real browser: headless Chromium renders it, with no console message.

Skipped only when no Chromium is installed and CI is not set; under CI=true it must run (.ci/run
installs Debian's chromium). Two drivers: ``--dump-dom`` (the DOM after the script ran, console
lines from Chromium's log on stderr) and the DevTools protocol for zoom, sort, filter and clicks.
"""

from __future__ import annotations

import os
import re
import subprocess
from typing import TYPE_CHECKING

import pytest

from medkit_replay.outputs.html import write_html
from medkit_replay.pipeline import replay
from tests.outputs.cdp import CHROMIUM_FLAGS, Browser, chromium_binary
from tests.outputs.html_support import (
    SEC,
    Page,
    example_result,
    long_mission,
    report,
    write_script,
)
from tests.outputs.test_html import HOSTILE, hostile_result

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.result import Result

CONSOLE = re.compile(r":CONSOLE[(:]")  # Chromium's log line for a console message
IN_CI = os.environ.get("CI", "").strip().lower() not in {"", "0", "false", "no"}


@pytest.fixture
def chromium() -> str:
    """The Chromium binary; a missing one fails under CI and skips elsewhere."""
    binary = chromium_binary()
    if binary is None:
        if IN_CI:
            pytest.fail("CI is set but no chromium is installed (.ci/run installs it)")
        pytest.skip("no chromium binary; install Debian's chromium to run the browser tests")
    return binary


def run_chromium(binary: str, profile: Path, *args: str) -> subprocess.CompletedProcess[str]:
    """One headless Chromium run with its log (console messages included) on stderr."""
    return subprocess.run(
        [binary, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", "--enable-logging=stderr", *args],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
        stdin=subprocess.DEVNULL,
    )


def rendered(binary: str, tmp_path: Path, result: Result, fault: str) -> tuple[Page, list[str]]:
    """The DOM after the page's script ran (with one fault's detail open) and console lines."""
    path = tmp_path / "report.html"
    write_html(result, path)
    done = run_chromium(binary, tmp_path / "dump", "--dump-dom", f"{path.as_uri()}#fault={fault}")
    assert done.returncode == 0, done.stderr[-2000:]
    return Page(done.stdout), [line for line in done.stderr.splitlines() if CONSOLE.search(line)]


def body_of(page: Page) -> dict[str, str | None]:
    """The <body> element's attributes."""
    return next(attrs for tag, attrs in page.tags if tag == "body")


def test_mission_report_renders_in_chromium(chromium: str, tmp_path: Path) -> None:
    result = example_result()
    page, console = rendered(chromium, tmp_path, result, "LIDAR_SCAN_DROPOUT")
    assert console == []
    body = body_of(page)
    assert body.get("data-rendered") == "ok"
    assert "data-js-errors" not in body
    assert body.get("data-rows") == str(len(result.faults))
    assert [r["data-code"] for r in page.with_class("fault-row")] == [
        f.fault_code for f in result.faults
    ]
    errors_box = page.by_id("js-errors")
    assert errors_box is not None and "hidden" in errors_box
    (detail,) = page.with_class("fault-detail")
    assert detail["data-code"] == "LIDAR_SCAN_DROPOUT"
    assert len([t for t, _ in page.tags if t == "path"]) == 3  # counter and both thresholds
    assert len([t for t, _ in page.tags if t == "circle"]) == 5  # one dot per report
    assert page.with_class("gl")  # grid lines only the script draws
    shot = tmp_path / "report.png"
    done = run_chromium(
        chromium,
        tmp_path / "shot",
        f"--screenshot={shot}",
        "--window-size=1400,1000",
        f"{(tmp_path / 'report.html').as_uri()}#fault=MOTOR_OVERHEAT",
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert shot.stat().st_size > 20_000


def test_hostile_report_runs_nothing(chromium: str, tmp_path: Path) -> None:
    page, console = rendered(chromium, tmp_path, hostile_result(tmp_path), "MOTOR_OVERHEAT")
    assert console == []  # a blocked inline handler or script would be logged here
    assert body_of(page).get("data-rendered") == "ok"
    assert not any(tag == "img" for tag, _ in page.tags)
    assert len(page.with_class("fault-row")) == 2
    (detail,) = page.with_class("fault-detail")
    assert detail["data-code"] == "MOTOR_OVERHEAT"
    tips = [a.get("data-tip") or "" for a in page.with_class("fault-label")]
    assert any(HOSTILE in tip for tip in tips)  # shown as text, whole


def test_near_misses_are_shown(chromium: str, tmp_path: Path) -> None:
    config = tmp_path / "params.yaml"
    config.write_text(
        "fault_manager:\n  ros__parameters:\n    confirmation_threshold: -3\n", encoding="utf-8"
    )
    script = write_script(
        tmp_path / "near.jsonl",
        [report(t * SEC, "WIFI", "FAILED", severity=1, source_id="/wifi") for t in (1, 2)],
    )
    path = tmp_path / "near.html"
    write_html(replay([script], [config]), path)
    done = run_chromium(chromium, tmp_path / "p", "--dump-dom", f"{path.as_uri()}#fault=WIFI")
    assert [line for line in done.stderr.splitlines() if CONSOLE.search(line)] == []
    assert "Closest: counter -2 against threshold -3 \u2014 1 FAILED report short" in done.stdout
    assert "Near misses (2)" in done.stdout


def test_long_dense_mission_renders(chromium: str, tmp_path: Path) -> None:
    """Half an hour of 10 Hz reports: the down-sampled page opens with no console message."""
    result = long_mission(tmp_path)
    page, console = rendered(chromium, tmp_path, result, "DENSE")
    assert console == []
    body = body_of(page)
    assert body.get("data-rendered") == "ok"
    assert "data-js-errors" not in body
    assert body.get("data-rows") == "3"
    (detail,) = page.with_class("fault-detail")
    assert detail["data-code"] == "DENSE"


def test_empty_recording_renders(chromium: str, tmp_path: Path) -> None:
    script = tmp_path / "empty.jsonl"
    script.write_text("# nothing\n", encoding="utf-8")
    page, console = rendered(chromium, tmp_path, replay([script]), "NONE")
    assert console == []
    assert body_of(page).get("data-rendered") == "ok"
    assert body_of(page).get("data-rows") == "0"


# ---------------------------------------------------------------- interaction over DevTools

INNER_WIDTH = "document.getElementById('tl-inner').getBoundingClientRect().width"
RANGE = "document.getElementById('tl-range').textContent"
SHOWN_ROWS = (
    "Array.from(document.querySelectorAll('#faults-table tbody tr'))"
    ".filter(r => !r.classList.contains('gone')).map(r => r.cells[0].textContent)"
)


def rect(browser: Browser, selector: str) -> dict[str, float]:
    """An element's viewport rectangle."""
    value: dict[str, float] = browser.eval(
        f"(() => {{ const r = document.querySelector({selector!r}).getBoundingClientRect();"
        " return {x: r.x, y: r.y, w: r.width, h: r.height}; })()"
    )
    return value


def test_timeline_and_tables_respond(chromium: str, tmp_path: Path) -> None:
    result = example_result()
    path = tmp_path / "report.html"
    write_html(result, path)
    with Browser(chromium, tmp_path / "cdp") as browser:
        browser.open(path.as_uri())
        assert browser.eval("document.body.dataset.rendered") == "ok"
        full = browser.eval(INNER_WIDTH)
        assert browser.eval(RANGE) == "0.0 \u2013 25.0 s"
        # Buttons: zoom in doubles the track, reset restores it.
        browser.eval("document.querySelector('[data-zoom=in]').click()")
        label = browser.eval("document.querySelector('.fault-label').offsetWidth")
        assert browser.eval(INNER_WIDTH) == pytest.approx(2 * full - label, abs=2)
        assert browser.eval(RANGE).endswith("\u00d72.00")
        browser.eval("document.querySelector('[data-zoom=reset]').click()")
        assert browser.eval(INNER_WIDTH) == pytest.approx(full, abs=1)
        # Wheel on the axis zooms in around the cursor.
        axis = rect(browser, "#tl-axis")
        browser.mouse("mouseWheel", axis["x"] + 200, axis["y"] + 10, deltaX=0, deltaY=-120)
        assert browser.eval(INNER_WIDTH) == pytest.approx(label + 1.25 * (full - label), abs=2)
        browser.eval("document.querySelector('[data-zoom=reset]').click()")
        # Dragging over the axis zooms to the range: a fifth of the track is 5 s.
        x0, x1, y = axis["x"] + axis["w"] * 0.2, axis["x"] + axis["w"] * 0.4, axis["y"] + 10
        browser.mouse("mousePressed", x0, y, button="left", clickCount=1)
        browser.mouse("mouseMoved", x1, y, button="left")
        browser.mouse("mouseReleased", x1, y, button="left", clickCount=1)
        low, high = (float(v) for v in re.findall(r"[\d.]+", browser.eval(RANGE))[:2])
        assert low == pytest.approx(5.0, abs=0.1) and high == pytest.approx(10.0, abs=0.1)
        browser.eval("document.querySelector('[data-zoom=reset]').click()")
        # Hover tooltips.
        browser.eval(
            "document.querySelector('.fault-row[data-code=MOTOR_OVERHEAT]')"
            ".scrollIntoView({block: 'center'})"
        )
        band = rect(browser, ".fault-row[data-code=MOTOR_OVERHEAT] .band")
        browser.mouse("mouseMoved", band["x"] + band["w"] / 2, band["y"] + band["h"] / 2)
        tip = browser.eval("(t => t.hidden ? '' : t.textContent)(document.getElementById('tip'))")
        assert tip.startswith("CONFIRMED  9.000 s \u2013 19.000 s")
        # A click on a row opens its counter trace; a second click closes it.
        browser.eval("document.querySelector('.fault-row[data-code=BATTERY_LOW]').click()")
        assert browser.eval("document.querySelectorAll('.fault-detail svg path').length") == 3
        browser.eval("document.querySelector('.fault-row[data-code=BATTERY_LOW]').click()")
        assert browser.eval("document.querySelectorAll('.fault-detail').length") == 0
        # Sorting: by first occurrence, then reversed; by status as text.
        browser.eval("document.querySelector('#faults-table th[data-col=\"4\"]').click()")
        assert browser.eval(SHOWN_ROWS)[0] == "LIDAR_SCAN_DROPOUT"
        browser.eval("document.querySelector('#faults-table th[data-col=\"4\"]').click()")
        assert browser.eval(SHOWN_ROWS)[0] == "ACTION_FOLLOW_PATH_ABORTED"
        browser.eval("document.querySelector('#faults-table th[data-col=\"1\"]').click()")
        assert browser.eval(SHOWN_ROWS)[:3] == [
            "ACTION_NAVIGATE_TO_POSE_ABORTED",
            "MOTOR_LEFT_COMM_TIMEOUT",
            "MOTOR_OVERHEAT",
        ]
        # Filtering a table and the timeline.
        browser.eval(
            "(() => { const i = document.querySelector('[data-filter-for=faults-table]');"
            " i.value = 'motor'; i.dispatchEvent(new Event('input')); })()"
        )
        assert sorted(browser.eval(SHOWN_ROWS)) == ["MOTOR_LEFT_COMM_TIMEOUT", "MOTOR_OVERHEAT"]
        assert browser.eval(
            "document.querySelector('[data-shown-for=faults-table]').textContent"
        ) == ("2 of 8 rows match")
        browser.eval(
            "(() => { const i = document.getElementById('tl-filter');"
            " i.value = '/sensors/'; i.dispatchEvent(new Event('input')); })()"
        )
        visible = browser.eval(
            "Array.from(document.querySelectorAll('.fault-row:not(.gone)'), r => r.dataset.code)"
        )
        assert visible == ["CAMERA_FRAME_TIMEOUT", "LIDAR_SCAN_DROPOUT"]
        # A fault code in a table opens that fault's row.
        browser.eval("document.querySelector('#events-table td.code').click()")
        assert browser.eval(
            "Array.from(document.querySelectorAll('.fault-detail'), d => d.dataset.code)"
        ) == ["LIDAR_SCAN_DROPOUT"]
        assert browser.eval("document.body.dataset.jsErrors || ''") == ""
        assert browser.problems() == []
