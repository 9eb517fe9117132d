"""Correlation rules learned from fleets with a known structure: the cascade and the burst are
recovered, nothing is proposed for an independent flapping code; the file loads as upstream's."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

from medkit_replay.cli import main
from medkit_replay.config.correlation_file import load_correlation, parse_correlation_config
from medkit_replay.engine.correlation import validate_config
from medkit_replay.tuning.rules_file import rules_yaml
from medkit_replay.tuning.suggest import rule_window, suggest
from sample_bags.make_tuning_fleet import FOLDER, write_fleet
from tests.fleet.fleet_support import report, write_script

ROOT = Path(__file__).resolve().parents[2]

MS = 1_000_000
SEC = 1_000_000_000


def synthetic_runs(count: int, seed: int = 7) -> list[list[tuple[int, str]]]:
    """Confirmations of ``count`` runs: ROOT drags A and B (90 %), X/Y/Z burst in any order
    (75 %), NOISE confirms at random times many times."""
    rng = random.Random(seed)
    runs = []
    for _ in range(count):
        events: list[tuple[int, str]] = []
        if rng.random() < 0.9:
            root = rng.randint(10, 500) * SEC
            events += [(root, "ROOT"), (root + rng.randint(100, 900) * MS, "A")]
            events.append((root + rng.randint(100, 900) * MS, "B"))
        if rng.random() < 0.75:
            burst = rng.randint(10, 500) * SEC
            events += [(burst + rng.randint(0, 300) * MS, code) for code in ("X", "Y", "Z")]
        events += [(rng.randint(0, 600) * SEC, "NOISE") for _ in range(15)]
        runs.append(sorted(events))
    return runs


def test_the_cascade_and_the_burst_are_recovered_and_the_noise_is_not() -> None:
    found = suggest(synthetic_runs(20))
    assert [(c.root, [s.code for s in c.symptoms]) for c in found.cascades] == [
        ("ROOT", ["A", "B"])
    ]
    assert [b.codes for b in found.bursts] == [("X", "Y", "Z")]
    assert all(s.confidence >= 0.8 for s in found.cascades[0].symptoms)
    assert found.cascades[0].window_ms >= 900


def test_too_little_support_proposes_nothing() -> None:
    found = suggest(synthetic_runs(2), min_support=3)
    assert found.cascades == () and found.bursts == ()
    text = rules_yaml(found)
    assert "rules: []" in text
    assert validate_config(parse_correlation_config(text)).errors == ()


def test_a_symptom_often_alone_is_not_a_symptom() -> None:
    runs = [[(1 * SEC, "ROOT"), (SEC + 300 * MS, "A")] for _ in range(4)]
    runs += [[(5 * SEC, "A")] for _ in range(4)]  # A alone as often: confidence 0.5
    assert suggest(runs).cascades == ()


def test_windows_round_up_with_a_margin() -> None:
    assert rule_window(0) == 100
    assert rule_window(829) == 1100
    assert rule_window(800) == 1000


def test_the_file_is_upstream_schema_and_our_loader_accepts_it(tmp_path: Path) -> None:
    text = rules_yaml(suggest(synthetic_runs(20)))
    config = parse_correlation_config(text)
    result = validate_config(config)
    assert result.errors == () and result.warnings == ()
    assert [r.id for r in config.rules] == ["cascade_root", "burst_x"]
    path = tmp_path / "rules.yaml"
    path.write_text(text)
    loaded = load_correlation(path)
    assert loaded.config is not None and loaded.warnings == ()
    assert "# support" in text or "support 1" in text


def test_the_generated_fleet_on_the_command_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    write_fleet(tmp_path)
    fleet = tmp_path / FOLDER
    out = tmp_path / "rules.yaml"
    argv = ["suggest-rules", str(fleet), "--config", str(fleet / "params.yaml")]
    status = main([*argv, "--out", str(out), "--validate", "--jobs", "1"])
    printed = capsys.readouterr().out
    assert status == 0
    text = out.read_text()
    config = parse_correlation_config(text)
    assert validate_config(config).errors == ()
    rules = {rule.id: rule for rule in config.rules}
    cascade = rules["cascade_motor_overheat"]
    assert cascade.root_cause_codes == ("MOTOR_OVERHEAT",)
    assert cascade.inline_symptom_codes == ("ODOM_DRIFT", "WHEEL_SLIP")
    burst = rules["burst_camera_stall"]
    assert config.patterns[burst.match_pattern_ids[0]] == (
        "CAMERA_STALL",
        "IMU_DRIFT",
        "LIDAR_TIMEOUT",
    )
    assert "WIFI_WEAK" not in text
    assert "support 9 run(s), confidence 1.00 (9/9)" in text
    assert "cascade: MOTOR_OVERHEAT -> ODOM_DRIFT, WHEEL_SLIP" in printed
    assert "0 fault(s) muted although their root never confirmed" in printed


def test_validate_names_a_mute_whose_root_never_confirmed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """With confirmation after 2 FAILED, a root reported once mutes its symptoms all the same
    (upstream correlates every FAILED report): --validate says so."""
    params = tmp_path / "params.yaml"
    params.write_text("fault_manager:\n  ros__parameters:\n    confirmation_threshold: -2\n")
    for index in range(4):
        lines = [report(10.0, "PUMP_FAIL"), report(10.1, "PUMP_FAIL")]
        lines += [report(10.3 + i * 0.1, "FLOW_LOW") for i in range(2)]
        write_script(tmp_path / "fleet" / f"run_{index}.jsonl", lines)
    write_script(
        tmp_path / "fleet" / "run_lone.jsonl",
        [report(10.0, "PUMP_FAIL"), *(report(10.3 + i * 0.1, "FLOW_LOW") for i in range(2))],
    )
    argv = ["suggest-rules", str(tmp_path / "fleet"), "--config", str(params), "--validate"]
    status = main([*argv, "--jobs", "1", "--out", str(tmp_path / "rules.yaml")])
    printed = capsys.readouterr().out
    assert status == 0
    assert "cascade: PUMP_FAIL -> FLOW_LOW" in printed
    assert "1 fault(s) muted although their root never confirmed, in 1 run(s)" in printed
    assert "run_lone.jsonl: FLOW_LOW muted by cascade_pump_fail" in printed


def test_the_bundled_fleet_is_what_its_generator_writes(tmp_path: Path) -> None:
    written = write_fleet(tmp_path)
    bundled = ROOT / "examples" / FOLDER
    for path in [*written, tmp_path / FOLDER / "params.yaml"]:
        assert (bundled / path.name).read_bytes() == path.read_bytes(), path.name
    assert sorted(p.name for p in bundled.iterdir()) == sorted(
        [p.name for p in written] + ["params.yaml"]
    )


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--window-ms", "0"], "Invalid value for '--window-ms'"),
        (["--min-support", "0"], "Invalid value for '--min-support'"),
        (["--config", "missing.yaml"], "missing.yaml: config file not found"),
    ],
)
def test_bad_usage_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str], message: str
) -> None:
    script = write_script(tmp_path / "run.jsonl", [report(1.0, "PUMP_FAIL")])
    assert main(["suggest-rules", str(script), *extra]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_no_recording_is_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "empty").mkdir()
    assert main(["suggest-rules", str(tmp_path / "empty")]) == 2
    assert "no recording found (rosbag2 folders, .mcap, .db3, .bag or .jsonl" in (
        capsys.readouterr().err
    )


def test_rules_go_to_standard_output_without_out(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    script = write_script(tmp_path / "run.jsonl", [report(1.0, "PUMP_FAIL")])
    assert main(["suggest-rules", str(script), "--jobs", "1"]) == 0
    captured = capsys.readouterr()
    assert captured.out.startswith("# Correlation rules proposed by medkit-replay")
    assert "rules: []" in captured.out
    assert captured.err.startswith("suggest-rules: 1 run(s) replayed; 0 hierarchical")
