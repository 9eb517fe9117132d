"""Muting in words, held against the events of the same report: every sentence the HTML page,
``explain`` and the tables say of a muted fault counts what the JSON report withheld and published.
"""

from __future__ import annotations

import json
import re
from html import unescape
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from medkit_replay.explaining import build_story, render_story
from medkit_replay.outputs.html import render_html
from medkit_replay.outputs.json_report import dumps
from medkit_replay.outputs.tables import result_tables
from medkit_replay.pipeline import replay
from medkit_replay.trace import FaultTrace

if TYPE_CHECKING:
    from medkit_replay.result import Result

ROOT = Path(__file__).resolve().parents[2]
MISSION = ROOT / "sample_bags" / "nav2_mission_mcap"
RULES = [ROOT / "rules" / "nav2" / "fault_manager.yaml", ROOT / "rules" / "nav2" / "bridges.yaml"]
SENTENCE = re.compile(
    r"FaultEvents: (?:withheld (?P<withheld>[^;]+)|no event withheld); "
    r"(?:published (?P<published>[^;]+)|none published); "
    r"(?:first muted (?P<first>\d+) ms, )?last muted (?P<delay>\d+) ms after its root "
    r"(?P<root>[A-Za-z0-9_]+)"
)


def _configs(tmp_path: Path, release: str) -> list[Path]:
    chosen = tmp_path / "release.yaml"
    chosen.write_text(f'medkit_replay:\n  ros__parameters:\n    upstream_release: "{release}"\n')
    return [*RULES, chosen]


def _counts(listed: str | None) -> dict[str, int]:
    if listed is None:
        return {}
    pairs = (item.strip().split(" ") for item in listed.split(","))
    return {kind: int(number) for number, kind in pairs}


def _said(text: str, code: str, codes: list[str]) -> re.Match[str]:
    """The muting sentence said of ``code`` in ``text``: the first whose nearest muted code
    before it (of ``codes``, all those the text may speak of) is ``code``."""
    known = codes

    def nearest(m: re.Match[str]) -> str:
        return max(known, key=lambda c: text.rfind(c, 0, m.start()))

    found = [m for m in SENTENCE.finditer(text) if nearest(m) == code]
    assert found, f"no muting sentence for {code}"
    return found[0]


def _from_json(report: dict[str, object], code: str) -> tuple[dict[str, int], dict[str, int]]:
    """Withheld and published events of one fault, counted from the JSON report itself."""
    withheld: dict[str, int] = {}
    published: dict[str, int] = {}
    for row in report["reports"]:  # type: ignore[attr-defined]
        if row["fault_code"] == code and row.get("withheld_event"):
            withheld[row["withheld_event"]] = withheld.get(row["withheld_event"], 0) + 1
    for event in report["events"]:  # type: ignore[attr-defined]
        if event["fault"]["fault_code"] == code:
            published[event["event_type"]] = published.get(event["event_type"], 0) + 1
    return withheld, published


def _held(said: re.Match[str], report: dict[str, object], code: str) -> None:
    withheld, published = _from_json(report, code)
    assert _counts(said["withheld"]) == withheld
    assert _counts(said["published"]) == published
    (muted,) = [m for m in report["muted_faults"] if m["fault_code"] == code]  # type: ignore[attr-defined]
    assert int(said["delay"]) == muted["delay_ms"] and said["root"] == muted["root_cause_code"]


@pytest.fixture(scope="module", params=["0.7.0", "0.6.0"])
def mission(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Result:
    return replay([MISSION], _configs(tmp_path_factory.mktemp("rel"), request.param))


def test_the_sample_has_muted_faults_with_events_published(mission: Result) -> None:
    report = json.loads(dumps(mission))
    codes = [m["fault_code"] for m in report["muted_faults"]]
    assert "WHEEL_ODOMETRY_SLIP" in codes
    withheld, published = _from_json(report, "WHEEL_ODOMETRY_SLIP")
    assert withheld
    if mission.upstream_release == "0.7.0":  # the case: not all withheld
        assert published == {"fault_updated": 3, "fault_cleared": 1}


def test_the_html_table_says_what_the_report_holds(mission: Result) -> None:
    report = json.loads(dumps(mission))
    page = unescape(render_html(mission))
    assert "its FaultEvents were withheld" not in page
    codes = [m["fault_code"] for m in report["muted_faults"]]
    assert len(list(SENTENCE.finditer(page))) == len(codes)
    for code in codes:
        _held(_said(page, code, codes), report, code)


def test_healing_at_0_6_0_publishes_no_clear_and_the_words_follow(tmp_path: Path) -> None:
    old = replay([MISSION], _configs(tmp_path, "0.6.0"))
    new = replay([MISSION], RULES)
    old_report, new_report = json.loads(dumps(old)), json.loads(dumps(new))
    code = "WHEEL_ODOMETRY_SLIP"
    assert _from_json(old_report, code)[1] != _from_json(new_report, code)[1]
    for result, report in ((old, old_report), (new, new_report)):
        codes = [m["fault_code"] for m in report["muted_faults"]]
        _held(_said(unescape(render_html(result)), code, codes), report, code)


def test_explain_says_the_same_sentence_and_the_first_mute() -> None:
    for code in ("WHEEL_ODOMETRY_SLIP", "MOTOR_LEFT_COMM_LINK"):
        trace = FaultTrace(fault_code=code)
        result = replay([MISSION], RULES, trace=trace)
        story = build_story(result, trace)
        text = render_story(story, width=1000)
        report = json.loads(dumps(result))
        said = _said(text, code, [code])
        _held(said, report, code)
        mutes = [
            e.fields["delay_ms"]
            for e in story.entries
            if e.kind == "correlation"
            and e.fields["fault_code"] == code
            and e.fields["should_mute"]
        ]
        assert said["first"] is not None and int(said["first"]) == mutes[0]
        assert f"this report {mutes[0]} ms after the root: muted" in text


def test_the_muted_table_says_it_too(mission: Result) -> None:
    report = json.loads(dumps(mission))
    frame = result_tables(mission)["muted_faults"]
    assert list(frame["delay_ms"]) == [m["delay_ms"] for m in report["muted_faults"]]
    for code, sentence in zip(frame["fault_code"], frame["muting"], strict=True):
        _held(_said(f"{code} {sentence}", code, [code]), report, code)
