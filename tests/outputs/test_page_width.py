"""analyze's, fleet's and sweep's pages for the bundled samples fit a 1,400-px window in
headless Chromium: ``document.documentElement.scrollWidth`` is at most 1,400 (wide tables scroll
in their own box). The same check ``benchmarks/screenshots.py`` makes before its screenshots."""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.fleet.report import write_report
from medkit_replay.fleet.run import RunSummary
from tests.outputs.cdp import Browser
from tests.outputs.page_shots import WINDOW, build_pages, measure
from tests.outputs.test_html_browser import chromium

if TYPE_CHECKING:
    from pathlib import Path

__all__ = ["chromium"]  # the fixture: a missing browser fails under CI and skips elsewhere


def test_every_page_fits_a_1400_px_window(chromium: str, tmp_path: Path) -> None:
    pages = build_pages(tmp_path / "pages")
    widths = {}
    with Browser(chromium, tmp_path / "profile", f"{WINDOW},1000") as browser:
        for name, page in pages.items():
            widths[name] = measure(browser, page)
            assert browser.eval("document.querySelectorAll('table').length") > 0, name
        assert browser.problems() == []
    assert set(widths) == {"analyze", "fleet", "sweep"}
    assert all(0 < width <= WINDOW for width in widths.values()), widths


def test_a_wide_table_would_be_caught(chromium: str, tmp_path: Path) -> None:
    # The measure is not blind: a page with a table wider than the window is measured wider.
    page = tmp_path / "wide.html"
    cells = "".join(f"<td>{'x' * 40}&nbsp;{'y' * 40}</td>" for _ in range(30))
    page.write_text(f"<!DOCTYPE html><html><body><table><tr>{cells}</tr></table></body></html>")
    with Browser(chromium, tmp_path / "profile", f"{WINDOW},1000") as browser:
        assert measure(browser, page) > WINDOW


def test_a_fleet_of_long_unbroken_text_still_fits(chromium: str, tmp_path: Path) -> None:
    runs = [
        RunSummary(
            path="x" * 600 + f"{i}.mcap",
            kind="mcap",
            messages=10**9,
            error=None if i % 2 else "E" * 3000,
            top_codes=tuple((f"{'C' * 200}{j}", 5) for j in range(5)),
        )
        for i in range(40)
    ]
    write_report(runs, tmp_path / "fleet")
    with Browser(chromium, tmp_path / "profile", f"{WINDOW},1000") as browser:
        assert measure(browser, tmp_path / "fleet" / "index.html") <= WINDOW
