"""The terminal summary's layout: no code split at any width, bounded, worst first, each story.

Runs are generated in code: long codes and descriptions, 400 faults, a 6-hour mission with 150
clusters, the Nav2 sample's muting, bags whose bridges ran and reported nothing.
"""

from __future__ import annotations

import re
from collections import Counter
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from medkit_replay.cli import main
from medkit_replay.outputs.terminal import MAX_LINES, render_summary
from medkit_replay.pipeline import replay
from medkit_replay.text import severity_name
from tests.inputs.builders import log
from tests.outputs.scripts import SEC, T0, clear, report, write_script
from tests.pipeline_support import SUCCEEDED, bag, config, goals
from tests.test_sample_bags import readme_first_command

if TYPE_CHECKING:
    from medkit_replay.result import Result

ROOT = Path(__file__).resolve().parents[2]
NAV2 = ROOT / "rules" / "nav2" / "fault_manager.yaml"
WIDTHS = (60, 80, 120, 200)
RANK = {"CONFIRMED": 0, "PREFAILED": 1, "HEALED": 2}


def long_codes(tmp_path: Path) -> Result:
    """Codes of 10 to 256 characters, descriptions of 600, confirmed, healed, cleared."""
    lines = []
    for number, size in enumerate((10, 40, 59, 61, 100, 256)):
        code = f"C{number}_" + "X" * (size - 3)
        text = f"a long description {number} " + "word " * 120
        lines.append(report(T0 + number * SEC, code, severity=number % 4, description=text))
    lines.append(clear(T0 + 20 * SEC, "C5_" + "X" * 253))
    return replay([write_script(tmp_path / "long.jsonl", lines)])


def codes_of(result: Result) -> list[str]:
    return [fault.fault_code for fault in result.faults]


def split_tokens(text: str, width: int) -> list[str]:
    """Lines wider than ``width`` that are more than one word (a layout that overflowed)."""
    return [line for line in text.splitlines() if len(line) > width and len(line.split()) > 1]


@pytest.mark.parametrize("width", WIDTHS)
@pytest.mark.parametrize("everything", [False, True])
def test_no_code_is_ever_split(tmp_path: Path, width: int, everything: bool) -> None:
    result = long_codes(tmp_path)
    text = render_summary(result, width, everything=everything)
    lines = text.splitlines()
    for code in codes_of(result):
        # Whole on one line: alone when wider than the code column, else at a row's start.
        assert any(line.split()[:1] == [code] for line in lines if line.strip()), code
    assert split_tokens(text, width) == []
    wide = [line for line in lines if len(line) > width]
    # Only a word wider than the line: a code, or the script's path under tmp_path.
    assert all(line in codes_of(result) or line.strip().endswith(".jsonl") for line in wide)
    assert any(line in codes_of(result) for line in wide) == (width < 256)
    if not everything:
        # Descriptions are shortened on one line, whole words kept up to the ellipsis.
        described = [line for line in lines if "a long description" in line]
        assert described and all(line.endswith("…") for line in described)
        assert all(len(line) <= width for line in described)


@pytest.mark.parametrize("width", WIDTHS)
def test_columns_are_sized_to_their_content(tmp_path: Path, width: int) -> None:
    script = write_script(
        tmp_path / "s.jsonl", [report(T0, "SHORT"), report(T0 + SEC, "A_LONGER_CODE")]
    )
    lines = render_summary(replay([script]), width).splitlines()
    heading = next(line for line in lines if line.startswith("code"))
    assert heading == "code           status     severity  occ"
    row = next(line for line in lines if line.startswith("SHORT"))
    assert row.index("CONFIRMED") == heading.index("status")


def many_faults(tmp_path: Path) -> Path:
    """400 codes: confirmed, pre-failed (not confirmed: a threshold of 3), healed, cleared."""
    lines = []
    for number in range(400):
        code, t = f"FAULT_{number:03d}", T0 + number * SEC
        kind = number % 4
        lines.append(report(t, code, severity=number % 4))
        if kind in (0, 2, 3):  # confirmed (by two more FAILED)
            lines += [report(t + 1, code, severity=number % 4), report(t + 2, code)]
        if kind == 2:
            lines += [report(t + 3 + k, code, "PASSED") for k in range(3)]
        if kind == 3:
            lines.append(clear(t + 10, code))
    return write_script(tmp_path / "many.jsonl", lines)


def threshold_config(tmp_path: Path, unknown: int = 0) -> Path:
    """Confirm on 3 FAILED, heal on 3 PASSED; ``unknown`` misspelt names (one warning each)."""
    typos = "".join(f"    confirmaton_threshold_{n}: 1\n" for n in range(unknown))
    return config(
        tmp_path,
        "fault_manager:\n  ros__parameters:\n    confirmation_threshold: -3\n"
        "    healing_enabled: true\n    healing_threshold: 3\n" + typos,
    )


@pytest.mark.parametrize("width", [60, 80, 200])
def test_400_faults_fit_60_lines_worst_first(tmp_path: Path, width: int) -> None:
    result = replay([many_faults(tmp_path)], [threshold_config(tmp_path, unknown=20)])
    assert len(result.faults) == 400 and len(result.warnings) == 20
    text = render_summary(result, width)
    lines = text.splitlines()
    assert len(lines) <= MAX_LINES and split_tokens(text, width) == []
    shown = [line.split()[0] for line in lines if line.startswith("FAULT_")]
    more = next(line for line in lines if line.endswith("more faults"))
    assert more == f"+{400 - len(shown)} more faults"
    assert "--all prints everything" in " ".join(text.split())
    assert "--html or --json FILE" in " ".join(text.split())
    assert "Warnings (20)" in lines and "+15 more warnings" in lines
    by_code = {f.fault_code: f for f in result.faults}

    def key(code: str) -> tuple[int, int]:
        fault = by_code[code]
        return RANK.get(fault.status, 3), -fault.severity

    assert [key(code) for code in shown] == sorted(key(code) for code in shown)
    worst = sorted(by_code, key=lambda code: (*key(code), code))[: len(shown)]
    assert shown == sorted(worst, key=lambda code: (*key(code), code))  # the worst are shown
    everything = render_summary(result, width, everything=True).splitlines()
    assert len([line for line in everything if line.startswith("FAULT_")]) == 400
    assert not any(line.endswith("more faults") for line in everything)


def test_ties_go_to_the_first_confirmation_then_the_code(tmp_path: Path) -> None:
    script = write_script(
        tmp_path / "s.jsonl",
        [report(T0, "Z_EARLY"), report(T0 + SEC, "B_LATE"), report(T0 + SEC, "A_LATE")],
    )
    lines = render_summary(replay([script])).splitlines()
    rows = [line.split()[0] for line in lines if "_LATE" in line or "_EARLY" in line]
    assert rows == ["Z_EARLY", "A_LATE", "B_LATE"]


def long_mission(tmp_path: Path) -> Path:
    """6 hours, a sensor storm (three codes within 2 s: a cluster) every 144 s: 150 clusters."""
    codes = ("LIDAR_SCAN_RATE", "CAMERA_FRAME_RATE", "IMU_DATA_RATE")
    lines = []
    for storm in range(150):
        t = T0 + storm * 144 * SEC
        lines += [
            report(t + n * SEC // 10, code, description="USB hub reset")
            for n, code in enumerate(codes)
            for _ in range(5)
        ]
        lines += [report(t + (10 + k) * SEC, code, "PASSED") for k in range(5) for code in codes]
    return write_script(tmp_path / "mission.jsonl", lines)


@pytest.mark.parametrize("width", [60, 80])
def test_a_six_hour_mission_fits_60_lines(tmp_path: Path, width: int) -> None:
    result = replay([long_mission(tmp_path)], [NAV2])
    assert len(result.clusters) == 150
    text = render_summary(result, width)
    lines = text.splitlines()
    assert len(lines) <= MAX_LINES and split_tokens(text, width) == []
    assert "Clusters: 150" in lines
    assert "  +147 more clusters" in lines
    member = next(line for line in lines if line.startswith("    cluster "))
    assert re.search(r", \+\d+ more$", member)  # 150 cluster ids cut to the line
    assert len(member) <= width
    # The story of a fault confirmed and healed 150 times, cut to the line with the counts.
    story = next(line for line in lines if line.startswith("  confirmed 0.000 s → "))
    assert len(story) <= width
    hidden = re.search(r"\+(\d+) more \((\d+) (\w+), (\d+) (\w+)\)$", story)
    assert hidden is not None
    assert {hidden[3], hidden[5]} == {"confirmed", "healed"}
    assert int(hidden[1]) == int(hidden[2]) + int(hidden[4])
    assert story.count("→") + int(hidden[1]) == 300  # every change told or counted
    whole = render_summary(result, width, everything=True)
    shown = set(re.findall(r"sensor_storm_(\d+)\b", whole))
    assert shown == {str(n) for n in range(1, 151)}
    assert "more" not in whole


def test_each_story_is_told_from_the_transitions(tmp_path: Path) -> None:
    script = write_script(
        tmp_path / "s.jsonl",
        [
            report(T0, "WIFI", severity=1),
            *(report(T0 + (1 + k) * SEC, "WIFI", "PASSED") for k in range(6)),
            *(report(T0 + 65_800_000_000, "WIFI", severity=1) for _ in range(6)),
            clear(T0 + 70 * SEC, "WIFI"),
            report(T0 + 136_800_000_000, "WIFI", severity=1),
        ],
    )
    config_file = threshold_config(tmp_path)
    config_file.write_text(config_file.read_text().replace("-3", "-1"))
    result = replay([script], [config_file])
    lines = render_summary(result, 120).splitlines()
    row = next(n for n, line in enumerate(lines) if line.startswith("WIFI"))
    told = [
        f"{t.to_status.lower()} {(t.t_ns - T0) / SEC:.3f} s"
        for t in result.transitions
        if t.fault_code == "WIFI" and t.to_status in ("CONFIRMED", "HEALED", "CLEARED")
    ]
    assert lines[row + 1] == "  " + " → ".join(told)
    assert lines[row + 1].startswith("  confirmed 0.000 s → healed ")
    assert lines[row + 1].endswith(" → cleared 70.000 s → confirmed 136.800 s")


def nav2_sample(capsys: pytest.CaptureFixture[str], *extra: str) -> str:
    status = main(
        [
            "analyze",
            str(ROOT / "sample_bags" / "nav2_mission_mcap"),
            "--config",
            str(NAV2),
            "--config",
            str(ROOT / "rules" / "nav2" / "bridges.yaml"),
            *extra,
        ]
    )
    out, _ = capsys.readouterr()
    assert status == 0
    return out


def test_near_misses_name_their_faults(capsys: pytest.CaptureFixture[str]) -> None:
    out = nav2_sample(capsys)
    assert "near misses: 7, for WIFI_SIGNAL_STRENGTH (7)" in out.splitlines()
    lines = out.splitlines()
    row = next(n for n, line in enumerate(lines) if line.startswith("WIFI_SIGNAL_STRENGTH"))
    assert lines[row + 1] == "  confirmed 65.751 s → healed 70.751 s → confirmed 136.754 s"
    assert lines[row + 2] == "  7 near misses"


EVENTS = re.compile(r"(\d+) (fault_\w+)")


def said(sentence: str, which: str) -> Counter[str]:
    """The events a muting sentence says were ``withheld`` or ``published`` ("FaultEvents:
    withheld 1 fault_confirmed; published 3 fault_updated" or "no event withheld; none
    published")."""
    withheld, published = sentence.split("FaultEvents: ", 1)[1].split("; ", 2)[:2]
    part = withheld if which == "withheld" else published
    return Counter({kind: int(n) for n, kind in EVENTS.findall(part)})


@pytest.mark.parametrize("release", ["0.6.0", "0.7.0"])
def test_muting_sentences_match_the_events_of_the_report(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], release: str
) -> None:
    chosen = config(
        tmp_path, f"medkit_replay:\n  ros__parameters:\n    upstream_release: '{release}'\n"
    )
    out = nav2_sample(capsys, "--all", "--config", str(chosen))
    result = replay(
        [ROOT / "sample_bags" / "nav2_mission_mcap"],
        [NAV2, ROOT / "rules" / "nav2" / "bridges.yaml", chosen],
    )
    assert result.upstream_release == release
    sent = Counter((e.fault.fault_code, str(e.event_type)) for e in result.events)
    kept = Counter(
        (r.fault_code, str(r.withheld_event)) for r in result.reports if r.withheld_event
    )
    published = {
        code: Counter({k: n for (c, k), n in sent.items() if c == code}) for code, _ in sent
    }
    withheld = {
        code: Counter({k: n for (c, k), n in kept.items() if c == code}) for code, _ in kept
    }
    assert withheld  # the sample mutes
    blocks = re.split(r"\n(?=\S)", out)
    checked = 0
    for code, events in withheld.items():
        block = next(b for b in blocks if b.startswith((code + " ", code + "\n")))
        sentence = " ".join(block.split())
        assert said(sentence, "withheld") == events, code
        assert said(sentence, "published") == published.get(code, Counter()), code
        muted = next((m for m in result.muted_faults if m.fault_code == code), None)
        if muted is not None:
            assert f"muted by {muted.root_cause_code}" in sentence
            assert f"last muted {muted.delay_ms} ms after it" in sentence  # upstream's delay
        checked += 1
    assert checked == len(withheld) >= 3


def test_zero_reports_when_every_goal_succeeded(tmp_path: Path) -> None:
    records = [
        goals(T0 + n * SEC, action, SUCCEEDED)
        for n in range(3)
        for action in ("/navigate_to_pose", "/follow_path")
    ]
    result = replay([bag(tmp_path, "actions", records, "mcap")])
    assert result.summary.reports == 0
    text = render_summary(result)
    assert "no report: 6 action status messages on 2 servers: no goal aborted" in text.splitlines()


def test_zero_reports_when_no_log_line_reaches_warn(tmp_path: Path) -> None:
    records = [log(T0 + n * SEC, 20, f"all good {n}", "vehicle.node") for n in range(17)]
    on = config(tmp_path, "medkit_replay:\n  ros__parameters:\n    enable_log_bridge: true\n")
    result = replay([bag(tmp_path, "vehicle", records, "mcap")], [on])
    assert result.summary.reports == 0
    assert result.consumed is not None and not result.consumed.empty  # the checks' fact
    text = " ".join(render_summary(result).split())
    assert "no report: 17 log lines on /rosout: none at WARN or above reported" in text


def test_severity_names_beside_rows(tmp_path: Path) -> None:
    result = long_codes(tmp_path)
    text = render_summary(result, 200)
    lines = text.splitlines()
    for fault in result.faults:
        row = next(n for n, line in enumerate(lines) if line.startswith(fault.fault_code))
        if lines[row] == fault.fault_code and len(fault.fault_code) > 100:
            row += 1  # a code wider than its column stands above its row
        assert severity_name(fault.severity) in lines[row].split()


def test_the_readme_shows_the_real_summary(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """docs/commands/analyze.md's "What you see" block is the start of what the README's first
    command prints."""
    readme = (ROOT / "docs" / "commands" / "analyze.md").read_text(encoding="utf-8")
    section = readme[readme.index("## What you see") :]
    block = section[section.index("```\n") + 4 : section.index("\n```", section.index("```\n"))]
    shown = block.splitlines()
    assert shown[-1] == "..."
    monkeypatch.chdir(ROOT)
    monkeypatch.delenv("COLUMNS", raising=False)
    assert main(readme_first_command()) == 0
    out, _ = capsys.readouterr()
    assert out.splitlines()[: len(shown) - 1] == shown[:-1]


def test_an_empty_replay_says_it_once(tmp_path: Path) -> None:
    """Nothing reached a bridge: the warning says it (with how to read the log lines)."""
    records = [log(T0 + n * SEC, 40, "bad", "vehicle.node") for n in range(3)]
    result = replay([bag(tmp_path, "logs", records, "mcap")])
    text = render_summary(result, 200)
    assert "no report:" not in text and "nothing replayed" not in text
    assert "holds 3 log message(s)" in text
