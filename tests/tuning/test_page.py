"""The sweep's HTML page: self-contained, offline, escaped, and showing what the tables say."""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

from medkit_replay.cli import main
from tests.fleet.fleet_support import report, write_script

if TYPE_CHECKING:
    from pathlib import Path

    import pytest


def test_the_page_is_self_contained_escaped_and_complete(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lines = [report(1.0 + i, "WIFI_WEAK", "FAILED" if i % 2 else "PASSED") for i in range(12)]
    script = write_script(tmp_path / "run.jsonl", [report(0.5, "WIFI_WEAK"), *lines])
    page = tmp_path / "sweep.html"
    hostile = "/<script>alert(1)</script>"
    argv = ["sweep", str(script), "--html", str(page), "--jobs", "1", "--quiet"]
    argv += ["--vary", "fault_manager.healing_enabled=true,false"]
    argv += ["--vary", "fault_manager.healing_threshold=1,2"]
    argv += ["--vary", f"medkit_replay.action_sources.nav={hostile},/ok"]
    assert main(argv) == 0
    capsys.readouterr()
    html = page.read_text(encoding="utf-8")
    assert "<script>alert(1)" not in html
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in html
    # Offline: nothing fetched (the SVG namespace is a name, not a request).
    assert re.findall(r"(?:src|href)=", html) == []
    assert html.count("<script>") == 1  # the sorting script, inline
    assert "<svg" in html and html.count("<circle") == 8
    # Every variant in the ranked table, and the code in the per-code view.
    for index in range(1, 9):
        assert f"<td>v{index:02d}</td>" in html
    assert "<td>WIFI_WEAK</td>" in html
    # Same inputs and grid, same bytes.
    again = tmp_path / "again.html"
    assert main([*argv[:2], "--html", str(again), *argv[4:]]) == 0
    assert again.read_bytes() == page.read_bytes()
