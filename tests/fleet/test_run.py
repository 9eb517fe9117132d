"""The per-run function and the process executor: summaries, errors, order, budgets."""

from __future__ import annotations

import pickle
from pathlib import Path

import pytest

from medkit_replay.checks import parse_budget
from medkit_replay.config.referenced import config_files
from medkit_replay.errors import ConfigError
from medkit_replay.fleet import run as fleet_run
from medkit_replay.fleet.run import RunSummary, run_one, summarize
from medkit_replay.fleet.workers import default_jobs, run_all
from medkit_replay.pipeline import replay
from medkit_replay.result import STATUSES
from tests.fleet.fleet_support import BRINGUP, NAV2, SAMPLES, SEC, episode, write_script

BAG = SAMPLES / "nav2_mission_mcap"


def test_run_one_summarizes_what_analyze_replays() -> None:
    result = replay([BAG], [NAV2])
    run = run_one(BAG, [NAV2])
    assert run == summarize(str(BAG), "rosbag2", result)
    assert run.ok and run.error is None
    assert run.kind == "rosbag2"
    assert run.messages == result.summary.messages_read == 626
    assert dict(run.faults_by_status) == result.summary.faults_by_status
    assert [s for s, _ in run.faults_by_status] == list(STATUSES)
    assert run.span_ns is not None and 150 * SEC < run.span_ns < 151 * SEC
    assert run.warnings == len(result.warnings)
    assert len(run.top_codes) == fleet_run.TOP_CODES
    counts = [n for _, n in run.top_codes]
    assert counts == sorted(counts, reverse=True)
    confirmed = dict(run.confirmed)
    assert "MOTOR_LEFT_OVERHEAT" in confirmed
    first = min(t.t_ns for t in result.transitions if t.to_status == "CONFIRMED")
    assert run.confirmed[0][1] == first
    heals = dict(run.heals)
    assert heals["MOTOR_LEFT_OVERHEAT"] == pytest.approx(24 * SEC, abs=0.01 * SEC)


def test_summary_is_small_and_picklable() -> None:
    run = run_one(BAG, [NAV2])
    assert pickle.loads(pickle.dumps(run)) == run
    assert len(pickle.dumps(run)) < 4096


def test_heal_durations_per_confirmation(tmp_path: Path) -> None:
    script = write_script(
        tmp_path / "a.jsonl",
        [line for _, line in episode("A", 1.0, 4.0) + episode("B", 6.0, None)],
    )
    run = run_one(script, [BRINGUP])
    assert run.confirmed == (("A", 1 * SEC), ("B", 6 * SEC))
    assert run.heals == (("A", 4 * SEC),)
    assert dict(run.faults_by_status)["HEALED"] == 1
    assert dict(run.faults_by_status)["CONFIRMED"] == 1
    assert run.top_codes == (("A", 1), ("B", 1))
    assert (run.start_ns, run.end_ns) == (1 * SEC, 6 * SEC)


@pytest.mark.parametrize(
    ("name", "content", "error"),
    [
        ("garbage.mcap", b"not a bag", "garbage.mcap: not an MCAP file"),
        ("garbage.db3", b"not a bag", "garbage.db3: "),
        ("bad.jsonl", b"{not json\n", "bad.jsonl:1: "),
        ("notes.txt", b"x", "notes.txt: unsupported input"),
    ],
)
def test_failed_recording_is_reported_not_raised(
    tmp_path: Path, name: str, content: bytes, error: str
) -> None:
    path = tmp_path / name
    path.write_bytes(content)
    run = run_one(path)
    assert not run.ok
    assert run.error is not None and run.error.startswith(str(tmp_path / error))
    assert "\n" not in run.error
    assert run.messages is None and run.faults_by_status == ()


def test_missing_recording_is_reported(tmp_path: Path) -> None:
    run = run_one(tmp_path / "gone.jsonl")
    assert run.error == f"{tmp_path / 'gone.jsonl'}: input not found"


def test_any_exception_is_reported_on_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def explode(*_: object, **__: object) -> None:
        raise RuntimeError("boom\non two lines")

    monkeypatch.setattr(fleet_run, "replay", explode)
    run = run_one(tmp_path / "x.jsonl")
    assert run.error == f"{tmp_path / 'x.jsonl'}: RuntimeError: boom on two lines"


def test_label_names_the_run_and_its_error(tmp_path: Path) -> None:
    path = tmp_path / "garbage.mcap"
    path.write_bytes(b"x")
    run = run_one(path.absolute(), label="fleet/garbage.mcap")
    assert run.path == "fleet/garbage.mcap"
    assert run.error is not None and run.error.startswith("fleet/garbage.mcap: ")


def test_budget_verdict_and_failed_rules(tmp_path: Path) -> None:
    budget = parse_budget(
        "version: 1\nrules:\n"
        "  - name: no motor faults\n    never_confirm: ['MOTOR_*']\n"
        "  - name: wifi may confirm\n    never_confirm: ['NOTHING_*']\n",
        "budget.yaml",
    )
    over = run_one(BAG, [NAV2], budget)
    assert over.budget == "fail"
    assert over.budget_failures == ("no motor faults",)
    script = write_script(tmp_path / "a.jsonl", [line for _, line in episode("A", 1.0, 4.0)])
    within = run_one(script, [BRINGUP], budget)
    assert (within.budget, within.budget_failures) == ("pass", ())
    assert run_one(script, [BRINGUP]).budget is None


def test_run_all_keeps_input_order_whatever_finishes_first(tmp_path: Path) -> None:
    scripts = [
        write_script(tmp_path / f"s{i}.jsonl", [line for _, line in episode("A", 1.0, 4.0)])
        for i in range(4)
    ]
    broken = tmp_path / "broken.mcap"
    broken.write_bytes(b"x")
    paths = [BAG, *scripts, broken, SAMPLES / "nav2_mission_sqlite3"]
    seen: list[int] = []
    runs = run_all(paths, [NAV2], jobs=2, on_done=lambda index, _: seen.append(index))
    assert [r.path for r in runs] == [str(p) for p in paths]
    assert sorted(seen) == list(range(len(paths)))
    assert runs == run_all(paths, [NAV2], jobs=1)
    assert [r.ok for r in runs] == [True, True, True, True, True, False, True]


def test_run_all_with_more_jobs_than_recordings(tmp_path: Path) -> None:
    script = write_script(tmp_path / "a.jsonl", [line for _, line in episode("A", 1.0, 4.0)])
    assert run_all([script], jobs=8) == [run_one(script)]
    assert run_all([], jobs=2) == []


def test_check_configs_refuses_a_bad_config_once(tmp_path: Path) -> None:
    config_files([NAV2, BRINGUP])
    with pytest.raises(ConfigError, match="not found"):
        config_files([tmp_path / "missing.yaml"])
    bad = tmp_path / "bad.yaml"
    bad.write_text("fault_manager:\n  ros__parameters:\n    auto_confirm_after_sec: 10\n")
    with pytest.raises(ConfigError, match="auto_confirm_after_sec"):
        config_files([bad])


def test_default_jobs_is_at_least_one() -> None:
    assert default_jobs() >= 1


def test_failed_summary_of_a_lost_worker() -> None:
    run = fleet_run.failed_run(Path("x.mcap"), RuntimeError("worker\nlost"))
    assert run == RunSummary(path="x.mcap", kind="mcap", error="x.mcap: RuntimeError: worker lost")


def test_a_row_error_is_one_line_naming_the_input_as_given_and_bounded() -> None:
    path = "/abs/missions/run_7.mcap"
    said = fleet_run.row_error(f"{path}: bad\n  chunk\tat 42", path, "missions/run_7.mcap")
    assert said == "missions/run_7.mcap: bad chunk at 42"
    config = "config.yaml:3: an unknown key"
    assert fleet_run.row_error(config, path, "run_7") == config
    assert fleet_run.row_error(config, path, "run_7", named_first=True) == f"run_7: {config}"
    long = fleet_run.row_error("x" * 10_000, path, None)
    assert len(long) == fleet_run.MAX_ERROR_CHARS and long.endswith("…")
