"""Red team, partial reads: a recording read only in part says how much was lost, everywhere.

An MCAP with one corrupt chunk, one cut short, an sqlite3 bag with a damaged page and one cut
short, a split bag missing a file, a ROS 1 bag with a corrupt chunk: each warning and the
Result's losses give the messages, bytes and bag time the damage cost (or say it is unknown),
checked against what was damaged.
The verdict of ``check``, ``fleet --budget``, ``sweep --budget`` and the pytest plugin stands;
``--strict`` fails them, in one line naming the input and the loss.
"""

from __future__ import annotations

import json
import textwrap
import xml.etree.ElementTree as ET
from dataclasses import replace
from typing import TYPE_CHECKING

import pytest
import yaml

from medkit_replay.checks.github import markdown
from medkit_replay.model import Loss, total_loss
from medkit_replay.pipeline import replay
from tests.checks.support import write_budget
from tests.inputs.builders import chunks, diag, flipped, storage_file, truncated, write_bag
from tests.inputs.ros1_builders import diag1, patched, records, write_bag1
from tests.redteam.support import run_limited

if TYPE_CHECKING:
    from pathlib import Path

    from tests.redteam.support import Outcome

pytest_plugins = ["pytester"]

SECOND = 1_000_000_000
T0 = 100 * SECOND
STEP = SECOND // 2
COUNT = 40
CHUNK = 5
PASSING = "- never_confirm: ['NOTHING_*']"


def mcap_bag(tmp_path: Path) -> Path:
    """40 diagnostics, one every 0.5 s from 100 s, 5 to a zstd chunk: a bare MCAP."""
    recs = [diag(T0 + k * STEP, f"s{k}") for k in range(COUNT)]
    bag = write_bag(tmp_path / "good", recs, compression="chunk", chunk_every=CHUNK)
    return storage_file(bag)


def corrupt_chunk(tmp_path: Path) -> tuple[Path, Loss]:
    """The good MCAP with its fourth chunk (messages 15 to 19) corrupt, and what that costs."""
    source = mcap_bag(tmp_path)
    start, end = chunks(source)[3]
    damaged = flipped(source, tmp_path / "corrupt.mcap", end - 10)
    lost = Loss(
        input=str(damaged),
        messages=CHUNK,
        bytes=end - start,
        start_ns=T0 + 15 * STEP,
        end_ns=T0 + 19 * STEP,
    )
    return damaged, lost


def replayed(path: Path) -> tuple[int, tuple[str, ...], tuple[Loss, ...]]:
    result = replay([path])
    return result.summary.messages_read, result.warnings, result.losses


def test_a_corrupt_mcap_chunk_costs_its_messages_bytes_and_span(tmp_path: Path) -> None:
    damaged, lost = corrupt_chunk(tmp_path)
    messages, warnings, losses = replayed(damaged)
    assert messages == COUNT - CHUNK
    assert losses == (lost,)
    (warning,) = warnings
    assert "cannot be decompressed" in warning
    assert warning.endswith(
        f"; 5 messages ({lost.bytes:,} bytes) from bag time 107.500 s to 109.500 s skipped"
    )
    # Read without the summary (a linear scan), the count is unknown; bytes and span are not.
    source = mcap_bag(tmp_path / "b")
    start, end = chunks(source)[3]
    cut = tmp_path / "noindex.mcap"
    data = bytearray(flipped(source, cut, end - 10).read_bytes())
    data[-8:] = b"\0" * 8  # no magic at the end: no footer, so no summary
    cut.write_bytes(bytes(data))
    _, warnings, losses = replayed(cut)
    chunk_losses = [loss for loss in losses if loss.start_ns is not None]
    assert chunk_losses == [
        Loss(input=str(cut), bytes=end - start, start_ns=T0 + 15 * STEP, end_ns=T0 + 19 * STEP)
    ]
    assert any(
        w.endswith(
            f"; an unknown number of messages ({end - start:,} bytes) from bag time 107.500 s "
            "to 109.500 s skipped"
        )
        for w in warnings
    )


def test_a_truncated_mcap_says_what_is_known_and_what_is_not(tmp_path: Path) -> None:
    source = mcap_bag(tmp_path)
    start, _ = chunks(source)[3]
    cut = truncated(source, tmp_path / "cut.mcap", start + 80)
    messages, warnings, losses = replayed(cut)
    assert messages == 15
    assert losses == (
        Loss(input=str(cut)),  # no footer: how much the recorder never wrote is unknown
        Loss(input=str(cut), bytes=80, start_ns=T0 + 15 * STEP, end_ns=T0 + 19 * STEP),
    )
    assert warnings[0].endswith("scanning the file from the start; how much was lost is unknown")
    assert warnings[-1].endswith(
        "the last 80 bytes are lost; an unknown number of messages (80 bytes) from bag time "
        "107.500 s to 109.500 s skipped"
    )


def test_a_damaged_sqlite_page_costs_its_message(tmp_path: Path) -> None:
    recs = [diag(T0 + k * STEP, f"s{k}", 1, f"{k:04d}" * 2000) for k in range(COUNT)]
    source = storage_file(write_bag(tmp_path / "good", recs, storage="sqlite3"))
    data = bytearray(source.read_bytes())
    page = 4096
    at = data.index(b"0007" * 1000) // page  # an overflow page of message 7's payload
    data[at * page : (at + 1) * page] = b"\xa5" * page
    damaged = tmp_path / "page.db3"
    damaged.write_bytes(bytes(data))
    messages, warnings, losses = replayed(damaged)
    assert messages == COUNT - 1
    assert losses == (
        Loss(input=str(damaged), messages=1, start_ns=T0 + 7 * STEP, end_ns=T0 + 7 * STEP),
    )
    assert warnings[0].endswith(
        "; 1 message (size unknown) from bag time 103.500 s to 103.500 s skipped"
    )


def test_a_truncated_sqlite_bag_says_the_loss_is_unknown(tmp_path: Path) -> None:
    recs = [diag(T0 + k * STEP, f"s{k}", 1, "x" * 300) for k in range(300)]
    source = storage_file(write_bag(tmp_path / "good", recs, storage="sqlite3"))
    cut = truncated(source, tmp_path / "cut.db3", source.stat().st_size - 4096)
    messages, warnings, losses = replayed(cut)
    assert 250 < messages < 300
    assert losses and all(loss == Loss(input=str(cut)) for loss in losses)
    assert sum(w.endswith("; how much was lost is unknown") for w in warnings) == len(losses)


def test_a_missing_split_file_costs_what_metadata_yaml_lists(tmp_path: Path) -> None:
    bag = tmp_path / "split"
    bag.mkdir()
    files = []
    for index in range(2):
        recs = [diag(T0 + (10 * index + k) * STEP, f"s{index}{k}") for k in range(10)]
        source = storage_file(write_bag(tmp_path / f"part{index}", recs))
        target = source.rename(bag / f"split_{index}.mcap")
        files.append(
            {
                "path": target.name,
                "starting_time": {"nanoseconds_since_epoch": recs[0].t_ns},
                "duration": {"nanoseconds": recs[-1].t_ns - recs[0].t_ns},
                "message_count": len(recs),
            }
        )
    info = {"version": 9, "storage_identifier": "mcap", "files": files}
    (bag / "metadata.yaml").write_text(yaml.safe_dump({"rosbag2_bagfile_information": info}))
    (bag / "split_1.mcap").unlink()
    messages, warnings, losses = replayed(bag)
    assert messages == 10
    assert losses == (
        Loss(input=str(bag), messages=10, start_ns=T0 + 10 * STEP, end_ns=T0 + 19 * STEP),
    )
    assert warnings[0] == (
        f"{bag}/split_1.mcap: listed in metadata.yaml but missing; 10 messages (size unknown) "
        "from bag time 105.000 s to 109.500 s skipped"
    )


def test_a_corrupt_ros1_chunk_costs_what_its_index_says(tmp_path: Path) -> None:
    recs = [diag1(T0 + k * STEP, f"s{k}") for k in range(COUNT)]
    bag = write_bag1(tmp_path / "good.bag", recs, "bz2", chunk_bytes=600)
    spans = [(r.start, r.data_start, r.end) for r in records(bag) if r.op == 0x05]
    pos, start, end = spans[2]
    damaged = patched(bag, tmp_path / "corrupt.bag", (start + end) // 2, b"\xa5\x5a" * 3)
    result = replay([damaged])
    read = sorted({t.t_ns for t in result.transitions} | {r.t_ns for r in result.reports})
    lost_times = sorted({T0 + k * STEP for k in range(COUNT)} - set(read))
    (loss,) = result.losses
    assert loss == Loss(
        input=str(damaged),
        messages=len(lost_times),
        bytes=end - pos,
        start_ns=lost_times[0],
        end_ns=lost_times[-1],
    )
    assert result.summary.messages_read == COUNT - len(lost_times)


def test_a_total_says_what_it_cannot_know() -> None:
    cut = Loss(bytes=80, start_ns=T0, end_ns=T0 + SECOND)
    chunk = Loss(messages=5, bytes=191, start_ns=T0 + 2 * SECOND, end_ns=T0 + 3 * SECOND)
    assert total_loss([Loss(), cut]).text() == (
        "an unknown number of messages (at least 80 bytes) from bag time 100.000 s to "
        "101.000 s and at unknown bag times skipped"
    )
    assert total_loss([cut, chunk]).text() == (
        "at least 5 messages (271 bytes) from bag time 100.000 s to 103.000 s skipped"
    )
    assert total_loss([Loss(messages=0), chunk]) == chunk
    assert total_loss([Loss(messages=0)]).text() == "no message lost"
    assert total_loss([Loss()]).text() == "how much was lost is unknown"
    assert (
        Loss(messages=1, bytes=3_400_000).text()
        == "1 message (3.4 MB) at unknown bag times skipped"
    )


# -- the commands --------------------------------------------------------------------------------


def check(tmp_path: Path, *inputs: Path, strict: bool = False) -> tuple[Outcome, ET.Element, str]:
    budget = write_budget(tmp_path, PASSING)
    out = tmp_path / "out"
    out.mkdir(exist_ok=True)
    junit = out / "check.xml"
    summary = out / "summary.md"
    summary.unlink(missing_ok=True)
    argv: list[str | Path] = ["check", *inputs, "--budget", budget, "--junit", junit, "--github"]
    outcome = run_limited(
        [*argv, "--strict"] if strict else argv, env={"GITHUB_STEP_SUMMARY": str(summary)}
    )
    assert "Traceback" not in outcome.stderr and "internal error" not in outcome.stderr
    return outcome, ET.parse(junit).getroot(), summary.read_text(encoding="utf-8")


def properties(suite: ET.Element) -> dict[str, str]:
    return {p.get("name") or "": p.get("value") or "" for p in suite.iter("property")}


def test_check_keeps_its_verdict_and_says_the_loss(tmp_path: Path) -> None:
    damaged, lost = corrupt_chunk(tmp_path)
    outcome, junit, summary = check(tmp_path, damaged)
    assert outcome.status == 0, outcome.stdout[-2000:]
    total = f"{damaged}: read only in part: {lost.text()}"
    assert any(
        line.startswith("!") and line.endswith(total) for line in outcome.stdout.splitlines()
    )
    assert "budget holds" in outcome.stdout
    (suite,) = junit
    assert properties(suite)["medkit_replay.lost_messages"] == "5"
    assert properties(suite)["medkit_replay.lost_bytes"] == str(lost.bytes)
    assert properties(suite)["medkit_replay.lost_span_ns"] == f"{lost.start_ns}..{lost.end_ns}"
    assert lost.text() in (suite.findtext("system-err") or "")
    assert junit.get("failures") == "0"
    title = f"recording read only in part ({damaged})".replace(":", "%3A").replace(",", "%2C")
    assert f"::warning title={title}::{total}" in outcome.stdout.splitlines()
    assert f"- ⚠️ {markdown(total)}" in summary.splitlines()


def test_check_strict_fails_a_recording_read_in_part(tmp_path: Path) -> None:
    damaged, lost = corrupt_chunk(tmp_path)
    outcome, junit, summary = check(tmp_path, damaged, strict=True)
    assert outcome.status == 1
    line = f"{damaged}: read only in part: {lost.text()} (--strict fails it)"
    assert f"FAIL {line}" in outcome.stdout
    assert "check failed: 1 of 1 run read only in part (--strict)" in outcome.stdout
    (suite,) = junit
    assert (suite.get("tests"), suite.get("failures")) == ("2", "1")
    case = next(c for c in suite.iter("testcase") if c.get("name") == "the recording is read whole")
    failure = case.find("failure")
    assert failure is not None and failure.get("message") == line
    assert any(
        command.startswith("::error title=recording read only in part") and command.endswith(line)
        for command in outcome.stdout.splitlines()
    )
    assert summary.startswith(
        "## medkit-replay check: a recording was read only in part (--strict) ❌"
    )
    assert f"- ❌ {markdown(line)}" in summary.splitlines()


def test_check_strict_passes_a_whole_recording(tmp_path: Path) -> None:
    outcome, junit, _ = check(tmp_path, mcap_bag(tmp_path), strict=True)
    assert outcome.status == 0, outcome.stdout[-2000:]
    (suite,) = junit
    assert (suite.get("tests"), suite.get("failures")) == ("2", "0")
    assert "medkit_replay.lost_messages" not in properties(suite)
    assert "read only in part" not in outcome.stdout


def fleet_folder(tmp_path: Path) -> tuple[Path, Path, Loss]:
    folder = tmp_path / "runs"
    folder.mkdir()
    damaged, lost = corrupt_chunk(tmp_path)
    moved = damaged.rename(folder / damaged.name)
    mcap_bag(tmp_path / "whole").rename(folder / "whole.mcap")
    return folder, moved, replace(lost, input=str(moved))


@pytest.mark.parametrize("command", ["fleet", "sweep"])
def test_fleet_and_sweep_fail_damage_under_strict(tmp_path: Path, command: str) -> None:
    folder, damaged, lost = fleet_folder(tmp_path)
    budget = write_budget(tmp_path, PASSING)
    out = tmp_path / "out"
    argv: list[str | Path] = [command, folder, "--budget", budget, "--quiet", "--jobs", "1"]
    argv += ["--out", out]
    if command == "sweep":
        argv += ["--vary", "fault_manager.confirmation_threshold=-1,-2"]
    held = run_limited(argv)
    assert held.status == 0, held.stderr[-2000:]
    strict = run_limited([*argv, "--strict"])
    assert strict.status == 1, strict.stderr[-2000:]
    line = f"{damaged}: read only in part: {lost.text()} (--strict fails it)"
    assert strict.stderr.splitlines() == [line]
    no_budget = [a for a in argv if a not in ("--budget", budget)]
    refused = run_limited([*no_budget, "--strict"])
    assert refused.status == 2
    assert "--strict fails" in refused.stderr and "give --budget too" in refused.stderr


def test_the_pytest_plugin_fails_damage_under_strict(
    tmp_path: Path, pytester: pytest.Pytester
) -> None:
    damaged, lost = corrupt_chunk(tmp_path)
    budget = write_budget(tmp_path, PASSING)
    body = f"""
        from pathlib import Path
        from medkit_replay.pytest_plugin import assert_within_budget

        def test_budget(replay_recording):
            assert_within_budget(replay_recording(Path({str(damaged)!r})), Path({str(budget)!r}))

        def test_budget_strict_keyword(replay_recording):
            result = replay_recording(Path({str(damaged)!r}))
            assert_within_budget(result, Path({str(budget)!r}), strict=True)
    """
    pytester.makepyfile(test_damage=textwrap.dedent(body))
    pytester.runpytest("-p", "no:randomly").assert_outcomes(passed=1, failed=1)
    strict = pytester.runpytest("-p", "no:randomly", "--strict-replay")
    strict.assert_outcomes(failed=2)
    strict.stdout.fnmatch_lines(
        [f"*{damaged}: read only in part: {lost.text()} (--strict fails it)*"]
    )


def test_analyze_summary_and_report_say_the_loss(tmp_path: Path) -> None:
    damaged, lost = corrupt_chunk(tmp_path)
    report = tmp_path / "report.json"
    outcome = run_limited(["analyze", damaged, "--json", report], env={"COLUMNS": "400"})
    assert outcome.status == 0, outcome.stderr[-2000:]
    assert f"{damaged}: read only in part: {lost.text()}" in outcome.stdout
    warnings = json.loads(report.read_text())["warnings"]
    assert [w for w in warnings if w.endswith(lost.text())] == warnings[:1]
