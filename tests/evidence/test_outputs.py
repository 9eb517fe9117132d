"""Evidence where users look: the HTML report (freeze frames, recording links, escaped values),
the terminal summary (counts), the CSV/Parquet tables (one row per captured topic)."""

from __future__ import annotations

import dataclasses
from html.parser import HTMLParser
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from medkit_replay import replay
from medkit_replay.captures import EvidenceRecording, RecordingTopic, SnapshotCapture, SnapshotTopic
from medkit_replay.outputs.html import render_html
from medkit_replay.outputs.tables import result_tables
from medkit_replay.outputs.terminal import render_summary

if TYPE_CHECKING:
    from medkit_replay.result import Result

ROOT = Path(__file__).resolve().parents[2]
HOSTILE = "<script>alert(1)</script>\u202e"


@pytest.fixture(scope="module")
def result() -> Result:
    base = replay([ROOT / "examples/nav2_mission.jsonl"], [ROOT / "rules/nav2/fault_manager.yaml"])
    code = base.faults[0].fault_code
    start = base.summary.start_ns or 0
    frame = SnapshotCapture(
        fault_code=code,
        capture_id=1,
        t_ns=start + 1_000,
        retained=True,
        freeze_frame=True,
        topics=(
            SnapshotTopic(
                topic="/battery",
                message_type="sensor_msgs/msg/BatteryState",
                message_t_ns=start + 2_000,
                data={"location": HOSTILE, "temperature": ".nan", "percentage": 0.5},
            ),
        ),
    )
    recording = EvidenceRecording(
        recording_id=f"fault_{code}_1",
        fault_codes=(code,),
        start_ns=start,
        end_ns=start + 5_000,
        topics=(RecordingTopic(topic="/battery", type="sensor_msgs/msg/BatteryState", messages=3),),
        messages=3,
        bytes=300,
        deleted_ns=None,
        deleted_reason=None,
        path="clips/fault_x",
    )
    gone = dataclasses.replace(
        recording,
        recording_id="fault_old",
        path=None,
        deleted_ns=start + 9_000,
        deleted_reason="auto_cleanup: X was cleared",
    )
    return dataclasses.replace(base, snapshots=(frame,), recordings=(recording, gone))


def test_html_shows_the_freeze_frame_and_links_the_recording(result: Result) -> None:
    page = render_html(result)
    section = page[page.index('<section id="evidence">') :]
    section = section[: section.index("</section>")]
    assert "/battery" in section and "&quot;.nan&quot;" in section
    assert "<script>alert" not in section and "&lt;script&gt;" in section
    assert "\u202e" not in section
    assert f'href="{(Path("clips/fault_x").absolute()).as_uri()}"' in section
    assert "auto_cleanup: X was cleared" in section


def test_html_has_no_evidence_section_without_captures(result: Result) -> None:
    plain = dataclasses.replace(result, snapshots=(), recordings=())
    assert 'id="evidence"' not in render_html(plain)


def test_the_terminal_counts_captures_and_recordings(result: Result) -> None:
    text = render_summary(result)
    assert "Evidence: 1 freeze-frame capture (1 retained), 2 recordings (1 deleted" in text
    assert "fault_old" in text and "auto_cleanup: X was cleared" in text


def test_the_snapshot_table_has_one_row_per_topic(result: Result) -> None:
    tables = result_tables(result)
    rows = tables["snapshots"].to_dict("records")
    assert len(rows) == 1 and rows[0]["topic"] == "/battery"
    assert '"temperature": ".nan"' in rows[0]["data"]
    assert list(tables["recordings"]["recording_id"]) == [
        result.recordings[0].recording_id,
        "fault_old",
    ]


def test_parquet_writes_the_evidence_tables(result: Result, tmp_path: Path) -> None:
    from medkit_replay.outputs.parquet import write_parquet  # noqa: PLC0415

    written = {p.name for p in write_parquet(result, tmp_path)}
    assert {"snapshots.parquet", "recordings.parquet"} <= written


class _Tags(HTMLParser):
    """Checks that every element opened in a fragment is closed in order."""

    def __init__(self) -> None:
        super().__init__()
        self.open: list[str] = []
        self.broken: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.open.append(tag)

    def handle_endtag(self, tag: str) -> None:
        if not self.open or self.open.pop() != tag:
            self.broken.append(tag)


def test_the_evidence_section_is_well_formed(result: Result) -> None:
    page = render_html(result)
    start = page.index('<section id="evidence">')
    end = page.index("</section>", start) + len("</section>")
    parser = _Tags()
    parser.feed(page[start:end])
    assert parser.open == [] and parser.broken == []
