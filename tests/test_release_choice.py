"""medkit_replay.upstream_release chooses the release in every command and every output names it.

The same input, a 200-character fault code, is accepted at 0.7.0 (codes up to 256 characters,
#591) and rejected at 0.6.0 (up to 128): each command shows which release it ran.
"""

from __future__ import annotations

import csv
import json
from typing import TYPE_CHECKING

import pytest

from medkit_replay.cli import main
from medkit_replay.diffing import diff_reports, render_diff
from medkit_replay.engine.validation import fault_code_error
from medkit_replay.errors import ConfigError
from medkit_replay.pytest_plugin import (
    RecordingReplayer,
    assert_confirmed,
    assert_matches_golden,
    assert_not_confirmed,
)
from medkit_replay.releases import RELEASES
from tests.pipeline_support import bag, report_call

if TYPE_CHECKING:
    from pathlib import Path

LONG = "L" * 200
RELEASE_LINE = "ros2_medkit {} modelled (medkit_replay.upstream_release: 0.6.0, 0.7.0)"
REJECTED = "fault_code exceeds maximum length of 128"


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    status = main(argv)
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return status, out, err


@pytest.fixture
def script(tmp_path: Path) -> Path:
    path = tmp_path / "long.jsonl"
    path.write_text(
        json.dumps(
            {
                "t_ns": 1_000_000_000,
                "op": "report",
                "fault_code": LONG,
                "event_type": "FAILED",
                "severity": 3,
                "source_id": "/motor",
            }
        )
        + "\n"
    )
    return path


def _release_config(tmp_path: Path, name: str) -> Path:
    path = tmp_path / f"release_{name}.yaml"
    path.write_text(f'medkit_replay:\n  ros__parameters:\n    upstream_release: "{name}"\n')
    return path


@pytest.fixture
def v060(tmp_path: Path) -> Path:
    return _release_config(tmp_path, "0.6.0")


@pytest.fixture
def unknown(tmp_path: Path) -> Path:
    return _release_config(tmp_path, "0.5.0")


def _unknown_line(err: str, config: Path) -> None:
    assert err.count("\n") == 1, err
    assert str(config) in err and "'0.5.0'" in err and "(0.6.0, 0.7.0)" in err


# -- the rule: the longest code per release ---------------------------------------------------


@pytest.mark.parametrize(
    ("length", "at_060", "at_070"),
    [
        (128, None, None),
        (129, REJECTED, None),
        (256, REJECTED, None),
        (257, REJECTED, "fault_code exceeds maximum length of 256"),
    ],
)
def test_the_longest_code_is_the_release_s(length: int, at_060: str, at_070: str) -> None:
    code = "A" * length
    assert fault_code_error(code, RELEASES["0.6.0"].max_fault_code_length) == at_060
    assert fault_code_error(code, RELEASES["0.7.0"].max_fault_code_length) == at_070


# -- analyze and its outputs ------------------------------------------------------------------


def test_analyze_json_names_the_release_and_applies_its_limit(
    tmp_path: Path, script: Path, v060: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    reports = {}
    for name, configs in (("0.7.0", []), ("0.6.0", ["--config", str(v060)])):
        out = tmp_path / f"{name}.json"
        status, _, _ = _run(
            ["analyze", str(script), *configs, "--json", str(out), "--quiet"], capsys
        )
        assert status == 0
        reports[name] = json.loads(out.read_text())
    new, old = reports["0.7.0"], reports["0.6.0"]
    assert list(new)[:3] == ["schema", "tool_version", "upstream_release"]
    assert (new["upstream_release"], old["upstream_release"]) == ("0.7.0", "0.6.0")
    assert [f["fault_code"] for f in new["faults"]] == [LONG]
    assert new["reports"][0]["accepted"] and new["reports"][0]["reject_reason"] is None
    assert old["faults"] == [] and old["reports"][0]["reject_reason"] == REJECTED
    assert "effective" not in new and "release" not in json.dumps(new.get("config", {}))


def test_the_summary_header_names_the_release_and_the_html_too(
    tmp_path: Path, script: Path, v060: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    page = tmp_path / "page.html"
    status, out, _ = _run(
        ["analyze", str(script), "--config", str(v060), "--html", str(page)], capsys
    )
    assert status == 0
    assert out.splitlines()[1] == RELEASE_LINE.format("0.6.0")
    assert "requests: 1 report (1 rejected)" in out
    assert RELEASE_LINE.format("0.6.0") in page.read_text()
    status, out, _ = _run(["analyze", str(script)], capsys)
    assert out.splitlines()[1] == RELEASE_LINE.format("0.7.0")
    assert "CONFIRMED 1" in out


# -- check: verdicts, JUnit -------------------------------------------------------------------


def test_check_runs_the_chosen_release_and_junit_names_it(
    tmp_path: Path, script: Path, v060: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    budget = tmp_path / "budget.yaml"
    budget.write_text('version: 1\nrules:\n  - never_confirm: ["L*"]\n')
    junit = tmp_path / "check.xml"
    args = ["check", str(script), "--budget", str(budget), "--junit", str(junit)]
    status, out, _ = _run(args, capsys)
    assert status == 1 and out.splitlines()[0] == RELEASE_LINE.format("0.7.0")
    assert 'name="medkit_replay.upstream_release" value="0.7.0"' in junit.read_text()
    status, out, _ = _run([*args, "--config", str(v060)], capsys)
    assert status == 0 and out.splitlines()[0] == RELEASE_LINE.format("0.6.0")
    assert 'name="medkit_replay.upstream_release" value="0.6.0"' in junit.read_text()


def test_an_unreadable_run_s_junit_still_names_the_release(
    tmp_path: Path, v060: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    budget = tmp_path / "budget.yaml"
    budget.write_text('version: 1\nrules:\n  - never_confirm: ["L*"]\n')
    broken = tmp_path / "broken.mcap"
    broken.write_bytes(b"not an mcap")
    junit = tmp_path / "check.xml"
    args = ["check", str(broken), "--budget", str(budget), "--junit", str(junit)]
    status, _, _ = _run([*args, "--config", str(v060)], capsys)
    assert status == 1
    assert 'name="medkit_replay.upstream_release" value="0.6.0"' in junit.read_text()


# -- fleet and sweep: the tables --------------------------------------------------------------


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as stream:
        return list(csv.DictReader(stream))


def test_fleet_runs_the_chosen_release_in_a_column_of_its_own(
    tmp_path: Path, script: Path, v060: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    runs = tmp_path / "runs"
    runs.mkdir()
    script.rename(runs / script.name)
    for name, configs in (("0.7.0", []), ("0.6.0", ["--config", str(v060)])):
        out_dir = tmp_path / f"fleet-{name}"
        args = ["fleet", str(runs), "--jobs", "1", "--out", str(out_dir), *configs]
        status, out, _ = _run(args, capsys)
        assert status == 0
        assert out.splitlines()[1] == RELEASE_LINE.format(name)
        (row,) = _rows(out_dir / "runs.csv")
        assert row["upstream_release"] == name
        assert row["confirmed"] == ("1" if name == "0.7.0" else "0")
        assert f"<td>{name}</td>" in (out_dir / "index.html").read_text()


def test_sweep_varies_the_release(
    tmp_path: Path, script: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out_dir = tmp_path / "sweep"
    page = tmp_path / "sweep.html"
    args = ["sweep", str(script), "--vary", "medkit_replay.upstream_release=0.6.0,0.7.0",
            "--jobs", "1", "--out", str(out_dir), "--html", str(page)]  # fmt: skip
    status, out, _ = _run(args, capsys)
    assert status == 0
    assert "ros2_medkit 0.6.0 and 0.7.0 modelled" in " ".join(out.split())
    variants = {r["medkit_replay.upstream_release"]: r for r in _rows(out_dir / "variants.csv")}
    assert {name: r["upstream_release"] for name, r in variants.items()} == {
        "0.6.0": "0.6.0",
        "0.7.0": "0.7.0",
    }
    assert (variants["0.6.0"]["faults_confirmed"], variants["0.7.0"]["faults_confirmed"]) == (
        "0",
        "1",
    )
    runs = {r["variant"]: r["upstream_release"] for r in _rows(out_dir / "runs.csv")}
    assert sorted(runs.values()) == ["0.6.0", "0.7.0"]
    assert "<td>0.6.0</td>" in page.read_text()


def test_sweep_on_a_release_chosen_by_the_base_config(
    tmp_path: Path, script: Path, v060: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out_dir = tmp_path / "sweep"
    vary = "fault_manager.confirmation_threshold=-1,-2"
    args = ["sweep", str(script), "--config", str(v060), "--vary", vary,
            "--jobs", "1", "--out", str(out_dir)]  # fmt: skip
    status, out, _ = _run(args, capsys)
    assert status == 0 and out.splitlines()[1] == RELEASE_LINE.format("0.6.0")
    assert {r["upstream_release"] for r in _rows(out_dir / "variants.csv")} == {"0.6.0"}


# -- explain and follow -----------------------------------------------------------------------


def test_explain_tells_the_story_at_the_chosen_release(
    script: Path, v060: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    status, out, _ = _run(["explain", str(script), LONG, "--json", "--quiet"], capsys)
    assert status == 0
    story = json.loads(out)
    assert story["upstream_release"] == "0.7.0"
    assert story["entries"][0]["accepted"] is True
    status, out, _ = _run(["explain", str(script), LONG, "--config", str(v060), "--quiet"], capsys)
    assert status == 0
    assert RELEASE_LINE.format("0.6.0") in out
    status, out, _ = _run(
        ["explain", str(script), LONG, "--config", str(v060), "--json", "--quiet"], capsys
    )
    story = json.loads(out)
    assert story["upstream_release"] == "0.6.0"
    assert story["entries"][0]["accepted"] is False
    assert story["entries"][0]["reject_reason"] == REJECTED


def _service_bag(tmp_path: Path) -> Path:
    """A rosbag2 MCAP bag holding one recorded ReportFault call of the long code."""
    times = [1_000_000_000 + n for n in range(4)]
    return bag(tmp_path, "bag", report_call(times, LONG), "mcap")


def test_follow_replays_the_chosen_release(
    tmp_path: Path, v060: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    recording = _service_bag(tmp_path)
    for name, configs in (("0.7.0", []), ("0.6.0", ["--config", str(v060)])):
        out = tmp_path / f"followed-{name}.json"
        status, _, _ = _run(["follow", str(recording), *configs, "--json", str(out)], capsys)
        assert status == 0
        report = json.loads(out.read_text())
        assert report["upstream_release"] == name
        assert [r["accepted"] for r in report["reports"]] == [name == "0.7.0"]


# -- the pytest plugin ------------------------------------------------------------------------


def test_the_plugin_replays_the_chosen_release(tmp_path: Path, script: Path, v060: Path) -> None:
    replayer = RecordingReplayer()
    newest = replayer(script)
    assert newest.upstream_release == "0.7.0"
    assert_confirmed(newest, LONG)
    oldest = replayer(script, v060)
    assert oldest.upstream_release == "0.6.0"
    assert_not_confirmed(oldest, LONG)
    golden = tmp_path / "golden.json"
    assert main(["analyze", str(script), "--json", str(golden), "--quiet"]) == 0
    with pytest.raises(AssertionError) as failed:
        assert_matches_golden(oldest, golden)
    assert "different ros2_medkit releases" in str(failed.value)


def test_the_plugin_refuses_an_unknown_release(script: Path, unknown: Path) -> None:
    with pytest.raises(ConfigError) as refused:
        RecordingReplayer()(script, unknown)
    assert "(0.6.0, 0.7.0)" in refused.value.render()


# -- an unknown release: one line, exit 2, in every command -----------------------------------


@pytest.mark.parametrize(
    "command", ["analyze", "check", "fleet", "sweep", "explain", "follow", "diff"]
)
def test_an_unknown_release_is_one_line_and_exit_2(
    command: str,
    tmp_path: Path,
    script: Path,
    unknown: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    budget = tmp_path / "budget.yaml"
    budget.write_text('version: 1\nrules:\n  - never_confirm: ["L*"]\n')
    config = ["--config", str(unknown)]
    argv = {
        "analyze": ["analyze", str(script), *config],
        "check": ["check", str(script), "--budget", str(budget), *config],
        "fleet": ["fleet", str(script.parent), "--out", str(tmp_path / "f"), *config],
        "sweep": [
            "sweep",
            str(script),
            "--vary",
            "fault_manager.confirmation_threshold=-1,-2",
            *config,
        ],
        "explain": ["explain", str(script), LONG, *config],
        "follow": ["follow", str(_service_bag(tmp_path)), *config],
        "diff": ["diff", str(script), str(script), *config],
    }[command]
    status, out, err = _run(argv, capsys)
    assert status == 2 and out == ""
    _unknown_line(err, unknown)


def test_an_unknown_release_in_vary_names_the_vary(
    script: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["sweep", str(script), "--vary", "medkit_replay.upstream_release=0.7.0,0.5.0"]
    status, out, err = _run(argv, capsys)
    assert status == 2 and out == ""
    assert err.count("\n") == 1
    assert "--vary medkit_replay.upstream_release=0.5.0" in err and "(0.6.0, 0.7.0)" in err


# -- diff: reports of two releases, reports made before the field -----------------------------


def _report(tmp_path: Path, script: Path, configs: list[str], name: str) -> dict[str, object]:
    out = tmp_path / name
    assert main(["analyze", str(script), *configs, "--json", str(out), "--quiet"]) == 0
    report: dict[str, object] = json.loads(out.read_text())
    return report


def test_diff_warns_once_when_the_releases_differ(
    tmp_path: Path, script: Path, v060: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    old = tmp_path / "old.json"
    new = tmp_path / "new.json"
    assert main(["analyze", str(script), "--config", str(v060), "--json", str(old), "--quiet"]) == 0
    assert main(["analyze", str(script), "--json", str(new), "--quiet"]) == 0
    status, out, _ = _run(["diff", str(old), str(new)], capsys)
    assert status == 1  # the fault is only in the 0.7.0 report
    warned = [line for line in out.splitlines() if "different ros2_medkit releases" in line]
    assert warned == [
        "warning: the reports model different ros2_medkit releases (baseline '0.6.0', current "
        "'0.7.0'): some differences may be the release's, not the robot's"
    ]
    status, out, _ = _run(["diff", str(new), str(new), "--json", "-", "--quiet"], capsys)
    assert status == 0 and "warnings" not in json.loads(out)
    status, out, _ = _run(["diff", str(old), str(new), "--json", "-", "--quiet"], capsys)
    assert json.loads(out)["warnings"] == warned


def test_diff_reads_a_report_made_before_the_release_was_named(
    tmp_path: Path, script: Path, v060: Path
) -> None:
    new = _report(tmp_path, script, [], "new.json")
    before = {key: value for key, value in new.items() if key != "upstream_release"}
    same = diff_reports(before, new)
    assert same.equal and same.warnings == ()
    older = _report(tmp_path, script, ["--config", str(v060)], "old.json")
    differs = diff_reports(before, older)
    assert not differs.equal and differs.warnings == ()
    assert "releases" not in render_diff(differs)
