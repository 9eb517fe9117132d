"""The three HTML pages (analyze's report, a fleet's index.html, a sweep's page) built from the
bundled samples, measured and photographed in headless Chromium at a 1,400-px window.

Shared by ``benchmarks/screenshots.py`` (PNGs for people to look at) and the test that holds
each page to the window's width (``document.documentElement.scrollWidth``).
"""

from __future__ import annotations

import base64
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.cli import main

if TYPE_CHECKING:
    from tests.outputs.cdp import Browser

ROOT = Path(__file__).resolve().parents[2]
WINDOW = 1400
"""Pixels: the window the pages must fit without a horizontal scroll bar."""
HEIGHT = 1000


def build_pages(folder: Path) -> dict[str, Path]:
    """Write the three pages for the bundled samples into ``folder``; by name."""
    samples = ROOT / "sample_bags"
    tuning = ROOT / "examples" / "tuning_fleet"
    pages = {
        "analyze": folder / "analyze.html",
        "fleet": folder / "fleet" / "index.html",
        "sweep": folder / "sweep.html",
    }
    quiet = ("--quiet", "--jobs", "1")
    runs = [
        ["analyze", str(samples / "nav2_mission_mcap"), "--quiet", "--html", str(pages["analyze"])],
        ["fleet", str(samples), str(ROOT / "examples" / "nav2_mission.jsonl"), *quiet,
         "--out", str(folder / "fleet")],
        ["sweep", str(tuning), "--config", str(tuning / "params.yaml"), *quiet,
         "--vary", "fault_manager.confirmation_threshold=-1,-2,-3",
         "--vary", "fault_manager.healing_threshold=1,4", "--html", str(pages["sweep"])],
    ]  # fmt: skip
    for argv in runs:
        status = main(argv)
        if status != 0:
            raise RuntimeError(f"medkit-replay {argv[0]} exited {status}")
    return pages


def measure(browser: Browser, page: Path, png: Path | None = None) -> int:
    """The page's ``scrollWidth`` at a WINDOW-px window; with ``png``, a full-page screenshot."""
    browser.call(
        "Emulation.setDeviceMetricsOverride",
        width=WINDOW,
        height=HEIGHT,
        deviceScaleFactor=1,
        mobile=False,
    )
    browser.open(page.as_uri())
    width = int(browser.eval("document.documentElement.scrollWidth"))
    if png is not None:
        height = int(browser.eval("document.documentElement.scrollHeight"))
        shot = browser.call(
            "Page.captureScreenshot",
            format="png",
            captureBeyondViewport=True,
            clip={"x": 0, "y": 0, "width": max(width, WINDOW), "height": height, "scale": 1},
        )
        png.write_bytes(base64.b64decode(shot["data"]))
    return width
