"""The small things a new user trips on: ``-h``, output folders made, written files echoed, the
progress phase's name, ``--json``'s metavar, a fleet's warnings on the terminal."""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING

import click

from medkit_replay.cli import cli
from medkit_replay.fleet.run import KEPT_WARNINGS, WARNING_CHARS, RunSummary, run_one
from medkit_replay.fleet.terminal import MAX_WARNING_ROWS, render_summary
from medkit_replay.outputs.progress import PHASE_LABELS
from medkit_replay.tuning.page import trade_off_svg, y_axis
from medkit_replay.tuning.ranking import VariantTotal, same_latency
from tests.test_cli import run

if TYPE_CHECKING:
    import pytest

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "nav2_mission.jsonl"
TUNING = ROOT / "examples" / "tuning_fleet"
SERVICE_CALLS = ROOT / "sample_bags" / "service_calls.mcap"


def test_dash_h_is_help_on_the_group_and_every_command(capsys: pytest.CaptureFixture[str]) -> None:
    status, out, err = run(["-h"], capsys)
    assert status == 0 and err == "" and out.startswith("Usage: medkit-replay [OPTIONS]")
    assert isinstance(cli, click.Group)
    for name in sorted(cli.commands):
        status, out, err = run([name, "-h"], capsys)
        assert status == 0 and err == "", name
        assert out.startswith(f"Usage: medkit-replay {name} "), name
        assert "-h, --help" in out, name


def test_no_option_shows_text_as_its_metavar(capsys: pytest.CaptureFixture[str]) -> None:
    for name in sorted(cli.commands):
        _, out, _ = run([name, "--help"], capsys)
        assert " TEXT" not in out, name
    for name in ("analyze", "follow", "diff"):
        _, out, _ = run([name, "--help"], capsys)
        assert "--json FILE|-" in out, name


def test_analyze_makes_output_folders_and_says_each_file_it_wrote(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    html = tmp_path / "a" / "b" / "report.html"
    report = tmp_path / "j" / "report.json"
    mcap = tmp_path / "m" / "events.mcap"
    tables = tmp_path / "t"
    argv = ["analyze", str(EXAMPLE), "--html", str(html), "--json", str(report)]
    status, out, err = run([*argv, "--mcap", str(mcap), "--csv", str(tables)], capsys)
    assert status == 0 and "ESTOP_PRESSED" in out
    assert html.is_file() and report.is_file() and mcap.is_file() and tables.is_dir()
    assert err.splitlines() == [f"wrote {p}" for p in (report, tables, mcap, html)]
    # --quiet: nothing said; the files are still written (again, over the first ones)
    html.unlink()
    status, out, err = run([*argv, "--quiet"], capsys)
    assert status == 0 and out == "" and err == "" and html.is_file()


def test_json_on_standard_output_is_not_announced(capsys: pytest.CaptureFixture[str]) -> None:
    status, out, err = run(["analyze", str(EXAMPLE), "--json", "-"], capsys)
    assert status == 0 and out.startswith("{") and "wrote" not in err


def test_sweep_makes_the_page_folder_and_says_what_it_wrote(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    page = tmp_path / "new" / "sweep.html"
    out_dir = tmp_path / "tables"
    mission = TUNING / "mission_01.jsonl"
    vary = "fault_manager.healing_threshold=1,3"
    argv = ["sweep", str(mission), "--vary", vary, "--jobs", "1", "--html", str(page)]
    status, out, err = run([*argv, "--out", str(out_dir)], capsys)
    assert status == 0 and "variants, best first" in out
    assert page.is_file() and (out_dir / "variants.csv").is_file()
    assert [line for line in err.splitlines() if line.startswith("wrote ")] == [
        f"wrote {page}",
        f"wrote {out_dir}",
    ]
    status, out, err = run([*argv, "--quiet"], capsys)
    assert status == 0 and out == "" and "wrote" not in err


def test_suggest_rules_says_the_file_it_wrote(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rules = tmp_path / "rules.yaml"
    argv = ["suggest-rules", str(TUNING), "--jobs", "1", "--out", str(rules)]
    status, out, err = run(argv, capsys)
    assert status == 0 and rules.is_file() and "suggest-rules:" in out
    assert f"wrote {rules}" in err.splitlines()


def test_the_first_progress_phase_says_what_it_reads() -> None:
    # The pre-pass reads only recorded ReportFault calls (to withhold bridge duplicates).
    assert PHASE_LABELS["prescan"] == "finding recorded ReportFault calls"
    assert "service calls" not in PHASE_LABELS.values()


def test_a_run_keeps_its_first_warnings(tmp_path: Path) -> None:
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(SERVICE_CALLS.read_bytes()[:9000])  # ends inside a record, no footer
    run_summary = run_one(cut)
    assert run_summary.ok and run_summary.warnings >= 2
    assert 0 < len(run_summary.first_warnings) <= KEPT_WARNINGS
    assert all(len(w) <= WARNING_CHARS + 40 for w in run_summary.first_warnings)
    text = render_summary([run_summary])
    assert f"warnings: {run_summary.warnings}" in text
    assert "file ends inside a record" in " ".join(text.split())


def test_fleet_summary_lists_the_first_warnings_then_how_many_more() -> None:
    runs = [
        RunSummary(
            path=f"m{i:02}.mcap",
            kind="mcap",
            messages=1,
            warnings=4,
            first_warnings=tuple(f"damage {i}.{j}" for j in range(KEPT_WARNINGS)),
        )
        for i in range(6)
    ]
    runs.append(RunSummary(path="clean.mcap", kind="mcap", messages=1))
    text = render_summary(runs)
    lines = text.splitlines()
    shown = [line for line in lines if "damage " in line]
    assert len(shown) == MAX_WARNING_ROWS
    assert shown[0].strip() == "m00.mcap: damage 0.0"
    assert "warnings: 24" in text
    more = 24 - MAX_WARNING_ROWS
    assert any(line.strip().startswith(f"+{more} more (6 runs with warnings") for line in lines)
    assert "warnings:" not in render_summary(runs[-1:])


def _total(variant: str, latency: int | None, confirmed: int = 5, events: int = 9) -> VariantTotal:
    return VariantTotal(
        rank=int(variant[1:]),
        variant=variant,
        label="",
        upstream_release="0.7.0",
        runs=1,
        failed_runs=0,
        faults_confirmed=confirmed,
        latency_mean_ns=latency,
        flaps=0,
        confirmed_ns=0,
        events=events,
        muted_events=0,
        near_misses=0,
        muted_faults=0,
        budget_failed=0,
    )


def test_latency_is_a_column_only_where_it_differs() -> None:
    zero = same_latency([_total("v1", 0), _total("v2", 0)])
    assert zero is not None and "0.00 s in every variant" in zero and "first FAILED" in zero
    assert same_latency([_total("v1", 0), _total("v2", 2_000_000_000)]) is None
    assert same_latency([_total("v1", 0)]) is None  # one variant: its figure is the news
    none = same_latency([_total("v1", None), _total("v2", None)])
    assert none is not None and "no variant confirmed" in none


def test_a_sweep_whose_latency_differs_shows_it_per_variant(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Confirming later (a lower threshold) takes longer: the figure is measured, not 0.
    mission = TUNING / "mission_01.jsonl"
    page = tmp_path / "s.html"
    argv = ["sweep", str(mission), "--jobs", "1", "--html", str(page)]
    status, out, _ = run([*argv, "--vary", "fault_manager.confirmation_threshold=-1,-2"], capsys)
    assert status == 0 and "lat s" in out
    latencies = {line.split()[1]: line.split()[-1] for line in out.splitlines() if " v0" in line}
    assert latencies["v01"] == "0.00" and float(latencies["v02"]) > 0
    assert "mean latency (s)" in page.read_text()
    status, out, _ = run([*argv, "--vary", "fault_manager.healing_threshold=1,3"], capsys)
    assert status == 0 and "lat s" not in out and "0.00 s in every variant" in " ".join(out.split())
    text = page.read_text()
    assert "mean latency (s)" not in text and "0.00 s in every variant" in text


def test_the_trade_off_plot_never_has_a_single_y_value() -> None:
    same = [_total("v1", 0, events=10), _total("v2", 0, events=30)]
    assert y_axis(same) == "FaultEvents published"
    svg = trade_off_svg(same)
    assert "FaultEvents published &#8594;" in svg and ">10<" in svg and ">30<" in svg
    differ = [_total("v1", 0, confirmed=4), _total("v2", 0, confirmed=6)]
    assert y_axis(differ) == "faults confirmed"
    assert "faults confirmed &#8594;" in trade_off_svg(differ)


def test_fleet_page_and_summary_agree(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out_dir = tmp_path / "fleet"
    argv = ["fleet", str(ROOT / "sample_bags"), str(EXAMPLE), "--jobs", "1", "--out", str(out_dir)]
    status, out, _ = run(argv, capsys)
    assert status == 0
    page = (out_dir / "index.html").read_text()
    card = dict(re.findall(r'<div class="k">([^<]*)</div><div class="v">([^<]*)</div>', page))
    head = " ".join(out.split())
    assert (
        f"fleet: {card['runs']} recordings, {card['replayed']} replayed; "
        f"{card['messages']} messages read; {card['runs with confirmed']} with a confirmed fault"
    ) in head


def test_sweep_page_and_summary_agree(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    page = tmp_path / "sweep.html"
    argv = ["sweep", str(TUNING), "--config", str(TUNING / "params.yaml"), "--jobs", "1"]
    argv += ["--vary", "fault_manager.confirmation_threshold=-1,-2", "--html", str(page)]
    status, out, _ = run(argv, capsys)
    assert status == 0
    terminal = {
        cells[1]: cells[2:]
        for line in out.splitlines()
        if (cells := line.split())[1:2] == ["v01"] or cells[1:2] == ["v02"]
    }
    rows = re.findall(
        r"<tr>(.*?)</tr>", page.read_text().split('id="variants"')[1].split("</table>")[0]
    )
    shown = {}
    for row in rows:
        texts = re.findall(r"<td[^>]*>([^<]*)</td>", row)
        if not texts:
            continue  # the heading row
        # rank, variant, threshold, release, confirmed, flaps, events, muted, near, muted faults,
        # mean latency (s), ...
        shown[texts[1]] = [texts[4], texts[5], texts[6], texts[7], texts[8], texts[10]]
    assert set(shown) == {"v01", "v02"} and terminal == shown
