"""Red team, fleet: a killed worker, a run that takes too long, a FIFO, out-of-range times and
unsafe outputs each cost only their own run; the report is still written, whole.

Each fleet runs in a child process under rlimits (``run_limited``): a worker the kernel kills
for its CPU time is a real death, not a simulated one.
"""

from __future__ import annotations

import csv
import json
import os
import sqlite3
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.fleet.report import FILES
from tests.fleet.fleet_support import BRINGUP, episode, write_script
from tests.inputs.builders import diag, storage_file, write_bag
from tests.redteam.support import assert_one_line_error, run_limited, tree_listing

if TYPE_CHECKING:
    from tests.redteam.support import Outcome

SEC = 1_000_000_000
NEVER_MOTOR = "version: 1\nrules:\n  - name: no motor faults\n    never_confirm: ['MOTOR_*']\n"
"""A budget every small run below keeps (their codes are A, B and C)."""


def small_runs(folder: Path, count: int = 3) -> list[Path]:
    """Scripts that replay in a blink, each with one fault confirmed and healed."""
    return [
        write_script(folder / f"run_{n}.jsonl", [line for _, line in episode("ABC"[n], 1.0, 4.0)])
        for n in range(count)
    ]


def slow_script(path: Path, lines: int) -> Path:
    """A valid script that takes the replay about a second of CPU per 80,000 lines."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", encoding="utf-8") as stream:
        for n in range(lines):
            event = "PASSED" if n % 3 == 0 else "FAILED"
            stream.write(
                f'{{"t_ns": {SEC + n * 1000}, "op": "report", "fault_code": "C{n % 5000}", '
                f'"event_type": "{event}", "severity": 2, "source_id": "/x"}}\n'
            )
    return path


def rows(out_dir: Path) -> dict[str, dict[str, str]]:
    """runs.csv by the recording's file name."""
    with (out_dir / "runs.csv").open(newline="", encoding="utf-8") as stream:
        return {Path(row["path"]).name: row for row in csv.DictReader(stream)}


def assert_others_replayed(table: dict[str, dict[str, str]], names: list[str]) -> None:
    for name in names:
        assert table[name]["error"] == "", table[name]
        assert table[name]["confirmed"] == "0" and table[name]["healed"] == "1", table[name]


def assert_clean(outcome: Outcome) -> None:
    assert "Traceback" not in outcome.stderr, outcome.stderr[-2000:]
    assert "internal error" not in outcome.stderr, outcome.stderr[-2000:]
    assert "BrokenProcessPool" not in outcome.stdout + outcome.stderr


def test_a_worker_killed_by_the_kernel_costs_only_its_run(tmp_path: Path) -> None:
    """The CPU limit (inherited by the workers) kills the worker replaying the long script, once
    and again when it is run a second time; the other runs keep their real results."""
    fleet = tmp_path / "fleet"
    quick = small_runs(fleet)
    slow = slow_script(fleet / "long.jsonl", 600_000)  # some 7 s of CPU, past the 3 s limit
    budget = tmp_path / "budget.yaml"
    budget.write_text(NEVER_MOTOR, encoding="utf-8")
    out_dir = tmp_path / "report"
    outcome = run_limited(
        ["fleet", fleet, "--config", BRINGUP, "--jobs", "2", "--budget", budget, "--out", out_dir],
        cpu_seconds=3,
        timeout=600,
    )
    assert_clean(outcome)
    assert outcome.status == 1, outcome.stderr[-2000:]  # with --budget, a dead run fails the gate
    table = rows(out_dir)
    assert table["long.jsonl"]["error"].startswith(f"{slow}: worker died: killed by SIG")
    assert "also when run again" in table["long.jsonl"]["error"]
    assert_others_replayed(table, [p.name for p in quick])
    assert all(table[p.name]["budget"] == "pass" for p in quick)
    assert sorted(p.name for p in out_dir.iterdir()) == sorted(FILES)


def test_a_run_past_the_timeout_is_killed_and_the_rest_complete(tmp_path: Path) -> None:
    fleet = tmp_path / "fleet"
    quick = small_runs(fleet)
    slow = slow_script(fleet / "long.jsonl", 200_000)
    for jobs in ("1", "2"):
        out_dir = tmp_path / f"report_{jobs}"
        options: list[str | Path] = [
            "--jobs",
            jobs,
            "--timeout",
            "0.2",
            "--quiet",
            "--out",
            out_dir,
        ]
        outcome = run_limited(["fleet", fleet, "--config", BRINGUP, *options], timeout=300)
        assert_clean(outcome)
        assert outcome.status == 0, outcome.stderr[-2000:]  # no --budget: reported, exit 0
        table = rows(out_dir)
        assert table["long.jsonl"]["error"] == f"{slow}: timed out after 0.2 s"
        assert_others_replayed(table, [p.name for p in quick])


def test_the_timeout_fails_the_budget_gate(tmp_path: Path) -> None:
    fleet = tmp_path / "fleet"
    small_runs(fleet, 1)
    slow_script(fleet / "long.jsonl", 200_000)
    budget = tmp_path / "budget.yaml"
    budget.write_text(NEVER_MOTOR, encoding="utf-8")
    options: list[str | Path] = [
        "--timeout",
        "0.2",
        "--budget",
        budget,
        "--out",
        tmp_path / "report",
    ]
    outcome = run_limited(["fleet", fleet, "--config", BRINGUP, *options], timeout=300)
    assert_clean(outcome)
    assert outcome.status == 1
    table = rows(tmp_path / "report")
    assert table["long.jsonl"]["error"].endswith("timed out after 0.2 s")
    assert table["run_0.jsonl"]["budget"] == "pass"


def test_bad_timeouts_are_usage_errors(tmp_path: Path) -> None:
    small_runs(tmp_path / "fleet", 1)
    for value in ("0", "-1", "nan", "inf", "1e300", "soon"):
        outcome = run_limited(
            ["fleet", tmp_path / "fleet", "--timeout", value, "--out", tmp_path / "r"], timeout=120
        )
        assert_one_line_error(outcome, "--timeout")
        assert not (tmp_path / "r").exists()


def test_fifos_and_devices_named_like_recordings_do_not_block(tmp_path: Path) -> None:
    fleet = tmp_path / "fleet"
    quick = small_runs(fleet)
    os.mkfifo(fleet / "pipe.mcap")
    os.mkfifo(fleet / "pipe.jsonl")
    (fleet / "zero.db3").symlink_to("/dev/zero")
    out_dir = tmp_path / "report"
    # No --timeout: a FIFO must be refused, not waited for (the harness's timeout is the guard).
    outcome = run_limited(["fleet", fleet, "--config", BRINGUP, "--out", out_dir], timeout=120)
    assert_clean(outcome)
    assert outcome.status == 0
    table = rows(out_dir)
    assert table["pipe.mcap"]["error"] == f"{fleet / 'pipe.mcap'}: a FIFO, not a regular file"
    assert table["pipe.jsonl"]["error"].endswith("a FIFO, not a regular file")
    assert table["zero.db3"]["error"].endswith("a character device, not a regular file")
    assert_others_replayed(table, [p.name for p in quick])


def test_a_fifo_inside_a_bag_is_bounded_by_the_timeout(tmp_path: Path) -> None:
    """Whether or not the bag reader refuses it, the fleet ends and reports the bag as failed."""
    fleet = tmp_path / "fleet"
    quick = small_runs(fleet)
    bag = write_bag(fleet / "bag", [diag(n * SEC, level=2) for n in range(1, 4)])
    data = storage_file(bag)
    data.unlink()
    os.mkfifo(data)
    out_dir = tmp_path / "report"
    outcome = run_limited(
        ["fleet", fleet, "--config", BRINGUP, "--timeout", "10", "--out", out_dir], timeout=240
    )
    assert_clean(outcome)
    assert outcome.status == 0
    table = rows(out_dir)
    assert table["bag"]["error"].startswith(str(bag)), table["bag"]
    assert_others_replayed(table, [p.name for p in quick])


def test_out_of_range_times_are_that_runs_failure(tmp_path: Path) -> None:
    """A script time past 2^63 ns and a db3 with TEXT timestamps: failed rows, one line each,
    naming the recording; the report of the others is written."""
    fleet = tmp_path / "fleet"
    quick = small_runs(fleet)
    write_script(
        fleet / "far.jsonl",
        [
            json.dumps(
                {"t_ns": 2**63 + 5, "op": "report", "fault_code": "A", "event_type": "FAILED"}
            )
        ],
    )
    write_script(
        fleet / "before.jsonl",
        [json.dumps({"t_ns": -(2**63) - 1, "op": "report", "fault_code": "A"})],
    )
    bag = write_bag(
        fleet / "text_times", [diag(n * SEC, level=2) for n in range(1, 4)], storage="sqlite3"
    )
    with sqlite3.connect(storage_file(bag)) as db:
        db.execute("UPDATE messages SET timestamp = 'abc'")
    budget = tmp_path / "budget.yaml"
    budget.write_text(NEVER_MOTOR, encoding="utf-8")
    cases: list[tuple[list[str | Path], int]] = [([], 0), (["--budget", budget], 1)]
    for argv, status in cases:
        out_dir = tmp_path / f"report_{status}"
        # The timeout only bounds a hang this test must catch (it once was one).
        options: list[str | Path] = ["--timeout", "60", "--out", out_dir, *argv]
        outcome = run_limited(["fleet", fleet, "--config", BRINGUP, *options], timeout=300)
        assert_clean(outcome)
        assert outcome.status == status, outcome.stderr[-2000:]
        table = rows(out_dir)
        for name in ("far.jsonl", "before.jsonl"):
            error = table[name]["error"]
            assert error.startswith(str(fleet / name)) and "\n" not in error, error
        # However the reader takes TEXT timestamps, the bag has its row and names itself.
        error = table["text_times"]["error"]
        assert error == "" or error.startswith(str(bag)), error
        assert "timed out" not in error and "worker died" not in error, error
        assert_others_replayed(table, [p.name for p in quick])
        assert json.loads((out_dir / "runs.json").read_text(encoding="utf-8"))


def test_the_report_may_not_land_in_an_input_or_over_a_config(tmp_path: Path) -> None:
    fleet = tmp_path / "fleet"
    small_runs(fleet)
    budget = tmp_path / "budget.yaml"
    budget.write_text(NEVER_MOTOR, encoding="utf-8")
    config = tmp_path / "params.yaml"
    config.write_bytes(BRINGUP.read_bytes())
    before = tree_listing(tmp_path)
    cases = [
        (fleet, "is the input"),
        (fleet / "report", "is inside the input"),
        (budget, str(budget)),
        (config, str(config)),
    ]
    for out_dir, needle in cases:
        outcome = run_limited(
            ["fleet", fleet, "--config", config, "--budget", budget, "--out", out_dir],
            timeout=120,
        )
        assert_one_line_error(outcome, "--out", needle)
        assert tree_listing(tmp_path) == before


def test_spreadsheet_formulas_are_neutralised_in_the_csv(tmp_path: Path) -> None:
    """A folder and a fault code that a spreadsheet would run as formulas stay text."""
    fleet = tmp_path / "=HYPERLINK(1)"
    write_script(fleet / "a.jsonl", [line for _, line in episode("-SUM", 1.0, 4.0)])
    out_dir = tmp_path / "report"
    outcome = run_limited(
        ["fleet", fleet.name, "--config", BRINGUP, "--out", out_dir, "--quiet"],
        cwd=tmp_path,
        timeout=120,
    )
    assert outcome.status == 0, outcome.stderr
    for name in ("runs.csv", "codes.csv"):
        with (out_dir / name).open(newline="", encoding="utf-8") as stream:
            for row in csv.reader(stream):
                for cell in row:
                    assert not cell.startswith(("=", "+", "-", "@", "\t", "\r")), (name, cell)
    # JSON keeps the text as it is.
    runs = json.loads((out_dir / "runs.json").read_text(encoding="utf-8"))
    assert runs[0]["path"] == "=HYPERLINK(1)/a.jsonl"


def test_a_report_that_cannot_be_written_leaves_no_partial_file(tmp_path: Path) -> None:
    """Past the file-size limit the fleet stops with one line; every file of the earlier report
    is whole (old or new), and no temporary file is left behind."""
    fleet = tmp_path / "fleet"
    small_runs(fleet, 1)
    out_dir = tmp_path / "report"
    first = run_limited(["fleet", fleet, "--config", BRINGUP, "--out", out_dir], timeout=120)
    assert first.status == 0
    old = {name: (out_dir / name).read_bytes() for name in FILES}
    for n in range(3, 60):
        write_script(fleet / f"more_{n}.jsonl", [line for _, line in episode("B", 1.0, 4.0)])
    limit = len(old["index.html"]) + 4096  # the new page, with 60 rows, is larger than this
    outcome = run_limited(
        ["fleet", fleet, "--config", BRINGUP, "--out", out_dir],
        file_size=limit,
        timeout=300,
    )
    assert_one_line_error(outcome, "cannot write the fleet report")
    assert sorted(p.name for p in out_dir.iterdir()) == sorted(FILES)  # no .partial file
    assert (out_dir / "index.html").read_bytes() == old["index.html"]
    for name in FILES:
        text = (out_dir / name).read_text(encoding="utf-8")
        assert text == old[name].decode("utf-8") or text.endswith("\n"), name


def test_names_that_are_not_utf8_or_reorder_text_are_reported(tmp_path: Path) -> None:
    """A recording named with bytes that are not UTF-8 and a right-to-left override: the fleet
    ends normally, the name is an escape in every file, and the page shows no raw bidi control.
    """
    fleet = tmp_path / "fleet"
    quick = small_runs(fleet)
    odd = os.fsencode(fleet) + b"/bad\xff\xfe\xe2\x80\xae.jsonl"
    with open(odd, "wb") as stream:  # noqa: PTH123  # a bytes path: pathlib would decode it
        stream.write(quick[0].read_bytes())
    out_dir = tmp_path / "report"
    outcome = run_limited(["fleet", fleet, "--config", BRINGUP, "--out", out_dir], timeout=120)
    assert_clean(outcome)
    assert outcome.status == 0, outcome.stderr[-2000:]
    table = rows(out_dir)
    (name,) = [n for n in table if n.startswith("bad")]
    assert name == "bad\\udcff\\udcfe\u202e.jsonl"
    assert table[name]["error"] == "" and table[name]["confirmed"] == "0"
    page = (out_dir / "index.html").read_text(encoding="utf-8")
    assert "\u202e" not in page and "bad\\udcff\\udcfe\\u202e.jsonl" in page
    assert "\u202e" not in outcome.stdout
    runs = json.loads((out_dir / "runs.json").read_text(encoding="utf-8"))
    assert any(run["path"].endswith("bad\\udcff\\udcfe\u202e.jsonl") for run in runs)
