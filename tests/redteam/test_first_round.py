"""Red team: the four first-round cases that had regressed, held again through the command line.

A FIFO listed as a storage file in metadata.yaml (refused, never opened blocking), an infinite
``auto_confirm_after_sec`` (upstream's behaviour, said with its file and line), and metadata.yaml
entries of the wrong type (each a warning naming metadata.yaml and the line).
"""

from __future__ import annotations

import json
import os
from typing import TYPE_CHECKING

import pytest

from tests.inputs.builders import diag, set_metadata, storage_file, write_bag
from tests.redteam.support import assert_one_line_error, run_limited

if TYPE_CHECKING:
    from pathlib import Path

SECOND = 1_000_000_000
TIMEOUT = 60
SCRIPT = (
    '{"t_ns": 1000000000, "op": "report", "fault_code": "MOTOR_A", "event_type": "FAILED", '
    '"severity": 2, "source_id": "/motor"}\n'
    '{"t_ns": 9000000000, "op": "report", "fault_code": "MOTOR_A", "event_type": "PASSED", '
    '"source_id": "/motor"}\n'
)


def analyze(tmp_path: Path, *argv: str | Path) -> dict[str, object]:
    """Run analyze; expect success; the JSON report."""
    report = tmp_path / "report.json"
    outcome = run_limited(["analyze", *argv, "--json", report, "--quiet"], timeout=TIMEOUT)
    assert outcome.status == 0, outcome.stderr[-2000:]
    assert "Traceback" not in outcome.stderr
    data: dict[str, object] = json.loads(report.read_text())
    return data


def warnings_of(report: dict[str, object]) -> list[str]:
    warnings = report["warnings"]
    assert isinstance(warnings, list)
    return [str(w) for w in warnings]


# --- a FIFO as a storage file -------------------------------------------------------------


def bag_with_storage_fifo(tmp_path: Path, storage: str, *, alone: bool) -> tuple[Path, Path]:
    """A bag whose metadata.yaml lists a FIFO as a storage file (beside its real one, or alone)."""
    bag = write_bag(tmp_path / "bag", [diag(k * SECOND) for k in (1, 2, 3)], storage=storage)  # type: ignore[arg-type]
    real = storage_file(bag)
    fifo = bag / f"pipe{real.suffix}"
    os.mkfifo(fifo)
    names = [fifo.name] if alone else [fifo.name, real.name]
    if alone:
        real.unlink()
    set_metadata(bag, relative_file_paths=names, files=[{"path": n} for n in names])
    return bag, fifo


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_fifo_among_the_storage_files_is_skipped_as_a_missing_one(
    tmp_path: Path, storage: str
) -> None:
    bag, fifo = bag_with_storage_fifo(tmp_path, storage, alone=False)
    report = analyze(tmp_path, bag)
    assert (
        f"{fifo}: cannot read: a FIFO, not a regular file; how much was lost is unknown"
        in warnings_of(report)
    )
    summary = report["summary"]
    assert isinstance(summary, dict)
    assert summary["messages_read"] == 3


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_bag_of_one_fifo_is_refused_in_one_line(tmp_path: Path, storage: str) -> None:
    bag, _ = bag_with_storage_fifo(tmp_path, storage, alone=True)
    outcome = run_limited(["analyze", bag, "--quiet"], timeout=TIMEOUT)
    assert_one_line_error(outcome, str(bag), "a FIFO, not a regular file")


# --- auto_confirm_after_sec: .inf -----------------------------------------------------------


def auto_confirms(tmp_path: Path, value: str) -> tuple[list[str], int]:
    """Analyze a fault left PREFAILED for 8 s under ``auto_confirm_after_sec: value``: the
    report's warnings and how many auto_confirm transitions it holds."""
    script = tmp_path / "run.jsonl"
    script.write_text(SCRIPT)
    config = tmp_path / f"params_{value.strip('.')}.yaml"
    config.write_text(
        "fault_manager:\n  ros__parameters:\n    confirmation_threshold: -3\n"
        f"    auto_confirm_after_sec: {value}\n"
    )
    report = analyze(tmp_path, script, "--config", config)
    transitions = report["transitions"]
    assert isinstance(transitions, list)
    return warnings_of(report), sum(t["cause"] == "auto_confirm" for t in transitions)


def test_an_infinite_auto_confirm_never_fires_and_is_said_with_its_file_and_line(
    tmp_path: Path,
) -> None:
    assert auto_confirms(tmp_path, "2.0") == ([], 1)  # the case can auto-confirm
    warnings, fired = auto_confirms(tmp_path, ".inf")
    assert fired == 0
    assert warnings == [
        f"{tmp_path / 'params_inf.yaml'}:4: fault_manager: auto_confirm_after_sec inf is beyond "
        "int64 nanoseconds (292 years): time-based confirmation can never fire (upstream "
        "accepts it and never auto-confirms); using 0.0 (off)"
    ]


# --- metadata.yaml entries of the wrong type --------------------------------------------------


def mcap_bag(tmp_path: Path) -> Path:
    return write_bag(tmp_path / "bag", [diag(k * SECOND) for k in (1, 2, 3)])


def line_of(path: Path, needle: str) -> int:
    """The (1-based) line of ``path`` holding ``needle`` first."""
    return next(n for n, line in enumerate(path.read_text().splitlines(), 1) if needle in line)


def test_a_starting_time_that_is_a_list_is_a_warning_naming_metadata_yaml(
    tmp_path: Path,
) -> None:
    bag = mcap_bag(tmp_path)
    set_metadata(bag, files=[{"path": "bag.mcap", "starting_time": [1]}])
    metadata = bag / "metadata.yaml"
    report = analyze(tmp_path, bag)
    assert (
        f"{metadata}:{line_of(metadata, '- path: bag.mcap')}: files: 1 entry with a "
        "starting_time that is not {nanoseconds_since_epoch: N} in int64 ('bag.mcap': a list); "
        "ignored (the file's own first message time is used)"
    ) in warnings_of(report)
    summary = report["summary"]
    assert isinstance(summary, dict)
    assert summary["messages_read"] == 3


def test_numbers_among_the_files_are_warnings_naming_metadata_yaml(tmp_path: Path) -> None:
    bag = mcap_bag(tmp_path)
    set_metadata(
        bag,
        relative_file_paths=["bag.mcap", 7, int("9" * 40)],
        files=[{"path": "bag.mcap"}, 1, {"path": 5}],
    )
    metadata = bag / "metadata.yaml"
    report = analyze(tmp_path, bag)
    warnings = warnings_of(report)
    assert (
        f"{metadata}:{line_of(metadata, '- 1')}: files: 2 entries without a file path (1, 5); "
        "ignored"
    ) in warnings
    assert (
        f"{metadata}:{line_of(metadata, '- 7')}: relative_file_paths: 2 entries not naming a "
        "file (7, a number past int64); ignored"
    ) in warnings
    summary = report["summary"]
    assert isinstance(summary, dict)
    assert summary["messages_read"] == 3


def test_a_metadata_yaml_naming_no_file_and_no_storage_file_is_refused(tmp_path: Path) -> None:
    bag = mcap_bag(tmp_path)
    storage_file(bag).unlink()
    set_metadata(bag, relative_file_paths=[1], files=[2])
    outcome = run_limited(["analyze", bag, "--quiet"], timeout=TIMEOUT)
    assert_one_line_error(outcome, str(bag), "metadata.yaml lists no storage file that exists")
