"""The fleet's files (CSV, JSON, HTML), the terminal summary and the progress bar."""

from __future__ import annotations

import csv
import io
import json
from html.parser import HTMLParser
from typing import TYPE_CHECKING

from medkit_replay.fleet.report import FILES, write_report
from medkit_replay.fleet.run import RunSummary
from medkit_replay.fleet.stats import CODE_COLUMNS, RUN_COLUMNS
from medkit_replay.fleet.terminal import (
    MAX_RUN_ROWS,
    FleetProgress,
    fleet_progress,
    print_summary,
    render_summary,
)
from medkit_replay.result import STATUSES

if TYPE_CHECKING:
    from pathlib import Path

    import pytest

SEC = 1_000_000_000
NASTY = '<script>alert("x")</script> & [bold red]loud[/]\x1b[31m'


def statuses(**counts: int) -> tuple[tuple[str, int], ...]:
    return tuple((s, counts.get(s.lower(), 0)) for s in STATUSES)


def sample_runs() -> list[RunSummary]:
    return [
        RunSummary(
            path="fleet/a.jsonl",
            kind="script",
            start_ns=0,
            end_ns=10 * SEC,
            messages=12,
            faults_by_status=statuses(confirmed=1, healed=1),
            top_codes=(("MOTOR_HOT", 3), ("WIFI", 1)),
            confirmed=(("MOTOR_HOT", 1 * SEC), ("WIFI", 2 * SEC)),
            heals=(("WIFI", 3 * SEC),),
            warnings=1,
            budget="pass",
        ),
        RunSummary(
            path=f"fleet/{NASTY}.jsonl",
            kind="script",
            start_ns=5 * SEC,
            end_ns=6 * SEC,
            messages=2,
            faults_by_status=statuses(confirmed=1),
            top_codes=(("MOTOR_HOT", 1),),
            confirmed=(("MOTOR_HOT", 5 * SEC),),
            budget="fail",
            budget_failures=("no motor faults", NASTY),
        ),
        RunSummary(path="fleet/broken.mcap", kind="mcap", error=f"fleet/broken.mcap: {NASTY}"),
    ]


def test_write_report_writes_every_file(tmp_path: Path) -> None:
    written = write_report(sample_runs(), tmp_path / "out" / "deep")
    assert [p.name for p in written] == list(FILES)
    assert all(p.read_bytes() for p in written)


def test_csv_tables(tmp_path: Path) -> None:
    write_report(sample_runs(), tmp_path)
    with (tmp_path / "runs.csv").open(newline="", encoding="utf-8") as stream:
        rows = list(csv.DictReader(stream))
    assert list(rows[0]) == list(RUN_COLUMNS)
    assert rows[0]["top_codes"] == "MOTOR_HOT:3; WIFI:1"
    assert rows[0]["confirmed_codes"] == "MOTOR_HOT; WIFI"
    assert rows[0]["span_s"] == "10.0" and rows[0]["messages"] == "12"
    assert rows[1]["path"] == f"fleet/{NASTY}.jsonl"  # quoted by the CSV writer, intact
    assert rows[1]["budget_failures"] == f"no motor faults; {NASTY}"
    assert rows[2]["messages"] == "" and rows[2]["error"].startswith("fleet/broken.mcap: ")
    with (tmp_path / "codes.csv").open(newline="", encoding="utf-8") as stream:
        codes = list(csv.DictReader(stream))
    assert list(codes[0]) == list(CODE_COLUMNS)
    assert [(c["fault_code"], c["runs_confirmed"], c["share_of_runs"]) for c in codes] == [
        ("MOTOR_HOT", "2", "1.0"),
        ("WIFI", "1", "0.5"),
    ]
    assert codes[0]["mean_first_confirmed_s"] == "0.5"  # (1 + 0) / 2
    assert codes[0]["mean_time_to_heal_s"] == ""
    assert codes[1]["median_time_to_heal_s"] == "3.0"


def test_json_tables(tmp_path: Path) -> None:
    write_report(sample_runs(), tmp_path)
    runs = json.loads((tmp_path / "runs.json").read_text(encoding="utf-8"))
    assert [list(r) for r in runs] == [list(RUN_COLUMNS)] * 3
    assert runs[0]["top_codes"] == [
        {"fault_code": "MOTOR_HOT", "failed_reports": 3},
        {"fault_code": "WIFI", "failed_reports": 1},
    ]
    assert runs[0]["budget"] == "pass" and runs[0]["error"] is None
    assert runs[1]["path"] == f"fleet/{NASTY}.jsonl"
    assert runs[2]["messages"] is None and runs[2]["span_s"] is None
    codes = json.loads((tmp_path / "codes.json").read_text(encoding="utf-8"))
    assert codes[1] == {
        "fault_code": "WIFI",
        "runs_confirmed": 1,
        "share_of_runs": 0.5,
        "mean_first_confirmed_s": 2.0,
        "heals": 1,
        "mean_time_to_heal_s": 3.0,
        "median_time_to_heal_s": 3.0,
    }


class _Collector(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.tags: list[str] = []
        self.cells: list[str] = []
        self.attrs: list[tuple[str, str | None]] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.append(tag)
        self.attrs += attrs

    def handle_data(self, data: str) -> None:
        self.cells.append(data)


def test_html_is_escaped_self_contained_and_sortable(tmp_path: Path) -> None:
    write_report(sample_runs(), tmp_path)
    page = (tmp_path / "index.html").read_text(encoding="utf-8")
    assert page.startswith("<!DOCTYPE html>")
    assert "<script>alert" not in page and "&lt;script&gt;alert" in page
    assert page.count("<script>") == 1  # ours, the sorter
    assert "http://" not in page and "https://" not in page  # nothing fetched
    parser = _Collector()
    parser.feed(page)
    assert parser.tags.count("table") == 2
    assert ("class", "data sortable") in parser.attrs  # analyze's table style, sortable
    shown = NASTY.replace("\x1b", "\\x1b")  # controls shown as escapes, the rest exactly
    assert f"fleet/{shown}.jsonl" in parser.cells
    assert "MOTOR_HOT:3; WIFI:1" in parser.cells
    assert ("class", "failed") in parser.attrs  # the broken run's row


def test_files_are_the_same_bytes_every_time(tmp_path: Path) -> None:
    write_report(sample_runs(), tmp_path / "one")
    write_report(sample_runs(), tmp_path / "two")
    for name in FILES:
        assert (tmp_path / "one" / name).read_bytes() == (tmp_path / "two" / name).read_bytes()


def test_plain_summary(tmp_path: Path) -> None:
    text = render_summary(sample_runs(), tmp_path / "rep")
    assert "\x1b" not in text
    assert all(len(line) <= 80 for line in text.splitlines())
    flat = " ".join(text.split())  # lines wrapped at 80 columns joined again
    assert "fleet: 3 recordings, 2 replayed, 1 failed" in flat
    assert "budget: 1 fail, 1 pass" in flat
    assert "[bold red]loud[/]" in flat  # shown literally, not as markup
    assert "\\x1b[31m" in flat  # the escape character is shown, not sent
    assert "over budget: fleet/<script>" in flat and ".jsonl: no motor faults;" in flat
    assert "not replayed: fleet/broken.mcap: <script>" in flat
    assert f"report: {tmp_path / 'rep'}/" in text.replace("\n", "")
    assert "MOTOR_HOT 2 100% 0 WIFI 1 50% 1 3.0 3.0" in flat


def test_summary_lists_the_first_runs_only() -> None:
    runs = [RunSummary(path=f"r{i}.jsonl", kind="script", messages=1) for i in range(45)]
    text = render_summary(runs)
    assert "r39.jsonl" in text and "r40.jsonl" not in text
    assert f"... {45 - MAX_RUN_ROWS} more runs in runs.csv" in text
    assert "budget" not in text  # no budget column without a budget


def test_summary_on_a_file_is_plain_and_on_a_terminal_drawn(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    plain = io.StringIO()
    print_summary(sample_runs(), plain)
    assert plain.getvalue() == render_summary(sample_runs())

    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    monkeypatch.setenv("TERM", "xterm-256color")
    monkeypatch.delenv("NO_COLOR", raising=False)
    monkeypatch.setenv("COLUMNS", "140")
    drawn = Terminal()
    print_summary(sample_runs(), drawn)
    assert "\x1b[" in drawn.getvalue()  # colour
    assert "fleet/broken.mcap" in drawn.getvalue()


def test_progress_only_on_a_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    monkeypatch.setenv("TERM", "xterm-256color")
    assert fleet_progress(io.StringIO(), 3) is None
    assert fleet_progress(Terminal(), 3, quiet=True) is None
    stream = Terminal()
    bar = fleet_progress(stream, 3)
    assert isinstance(bar, FleetProgress)
    with bar:
        for index, run in enumerate(sample_runs()):
            bar(index, run)
    shown = stream.getvalue()
    assert "replaying" in shown and "3/3" in shown and "1 failed" in shown
