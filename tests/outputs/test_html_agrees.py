"""The HTML report and the terminal summary agree on every figure both show: `analyze --html`
on the bundled sample, the summary's events published, faults by status, near misses and
recording span read back from its text and compared with the page's."""

from __future__ import annotations

import re
from html import unescape
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.cli import main
from tests.inputs.builders import string_msg, write_bag
from tests.outputs.html_support import Page

if TYPE_CHECKING:
    import pytest

ROOT = Path(__file__).resolve().parents[2]
MISSION = ROOT / "sample_bags" / "nav2_mission_mcap"
RULES = [ROOT / "rules" / "nav2" / "fault_manager.yaml", ROOT / "rules" / "nav2" / "bridges.yaml"]
SECOND = 1_000_000_000
STATUSES = ("PREFAILED", "PREPASSED", "CONFIRMED", "HEALED", "CLEARED")


def _number(text: str) -> int:
    return int(text.replace(",", ""))


def _card(page: str, key: str) -> tuple[str, str]:
    found = re.search(
        rf'<div class="k">{key}</div><div class="v">([^<]*)</div><div class="d">(.*?)</div></div>',
        page,
    )
    assert found, key
    return unescape(found[1]), found[2]


def _terminal(out: str) -> dict[str, object]:
    events = re.search(
        r"events published: ([\d,]+) confirmed, ([\d,]+) updated, ([\d,]+) cleared", out
    )
    span = re.search(r"recording: ([\d,.]+) s of bag time", out)
    near_line = re.search(r"near misses: ([\d,]+), for (.*)", out)
    near = None
    if near_line:  # "7, for WIFI_SIGNAL_STRENGTH (7), ... +N more": the faults named or counted
        named = re.findall(r"\S+ \(\d+\)", near_line[2])
        more = re.search(r"\+(\d+) more", near_line[2])
        near = (near_line[1], str(len(named) + (int(more[1]) if more else 0)))
    faults = re.search(r"faults: ([\d,]+)\b(.*)", out)
    assert events and span and near and faults, out
    by_status = {status: _number(n) for status, n in re.findall(r"\b([A-Z]+) ([\d,]+)", faults[2])}
    return {
        "events": tuple(_number(n) for n in events.groups()),
        "span": span[1],
        "near": (_number(near[0]), _number(near[1])),
        "faults": _number(faults[1]),
        "by_status": {k: v for k, v in by_status.items() if k in STATUSES and v},
    }


def _html(text: str) -> dict[str, object]:
    page = Page(text)
    _, events = _card(text, "Events")
    counts = dict(re.findall(r"(confirmed|updated|cleared) ([\d,]+)", unescape(events)))
    span, _ = _card(text, "Bag time")
    faults, badges = _card(text, "Faults")
    by_status = {
        status: _number(n)
        for status, n in re.findall(r'class="badge s-(\w+)">\1 ([\d,]+)<', badges)
    }
    lanes = page.lanes()
    near = [int(str(lane["near_count"])) for lane in lanes]
    return {
        "events": tuple(_number(counts[k]) for k in ("confirmed", "updated", "cleared")),
        "span": span.removesuffix(" s"),
        "near": (sum(near), sum(1 for n in near if n)),
        "faults": _number(faults),
        "by_status": {k: v for k, v in by_status.items() if v},
    }


def test_analyze_summary_and_html_agree(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "200")
    page = tmp_path / "report.html"
    args = ["analyze", str(MISSION), *(f"--config={c}" for c in RULES), "--html", str(page)]
    assert main(args) == 0
    out, _ = capsys.readouterr()
    terminal, html = _terminal(out), _html(page.read_text(encoding="utf-8"))
    assert terminal == html
    assert terminal["events"] == (10, 60, 10) and terminal["near"] == (7, 1)  # not all zero


def test_a_bag_nothing_was_read_from_has_the_same_span(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Only /chatter, 1 s to 5 s: the replay reads no message, the recording still spans 4 s."""
    monkeypatch.setenv("COLUMNS", "200")
    bag = write_bag(tmp_path / "bag", [string_msg(k * SECOND) for k in range(1, 6)])
    page = tmp_path / "report.html"
    assert main(["analyze", str(bag), "--html", str(page)]) == 0
    out, _ = capsys.readouterr()
    span = re.search(r"recording: ([\d,.]+) s of bag time", out)
    assert span and span[1] == "4.000", out
    text = page.read_text(encoding="utf-8")
    assert _card(text, "Bag time")[0] == "4.000 s"
    assert "4.000 s of bag time" in text and "no message was read" in text
