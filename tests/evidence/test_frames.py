"""Freeze-frame storage over captures and clears (test_snapshot_capture.cpp's
EmptyRecaptureKeepsRetainedFreezeFrame, the snapshot cap and retention of test_fault_manager.cpp),
on a generated recording, and captures of muted faults (muting does not prevent a capture)."""

from __future__ import annotations

from pathlib import Path

from medkit_replay import replay
from medkit_replay.evidence.frames import freeze_frames
from medkit_replay.evidence.plan import Plan, PlannedCapture, Step
from medkit_replay.evidence.rules import SnapshotConfig
from medkit_replay.evidence.source import EvidenceSource
from tests.evidence.robot import at, write_robot

ROOT = Path(__file__).resolve().parents[2]


def capture(
    capture_id: int, seconds: float, topics: tuple[str, ...], code: str = "A"
) -> PlannedCapture:
    return PlannedCapture(
        code, capture_id, at(seconds), topics, background=False, entity_scoped=False
    )


def frames(
    tmp_path: Path, steps: list[Step], config: SnapshotConfig
) -> list[tuple[int, bool, bool, int]]:
    robot = write_robot(tmp_path)
    plan = Plan(captures=[s.capture for s in steps if s.capture is not None], steps=steps)
    source = EvidenceSource([robot.bag])
    try:
        found = freeze_frames(plan, config, source)
    finally:
        source.close()
    return [(c.capture_id, c.retained, c.freeze_frame, len(c.topics)) for c in found]


def test_an_empty_recapture_keeps_the_retained_freeze_frame(tmp_path: Path) -> None:
    first = capture(1, 10, ("/odom",))
    silent = capture(2, 29.99, ("/odom",))  # nothing is published after it
    steps = [Step(first.t_ns, "A", first), Step(silent.t_ns, "A", silent)]
    assert frames(tmp_path, steps, SnapshotConfig()) == [(1, True, True, 1), (2, False, False, 0)]


def test_a_first_capture_that_samples_nothing_is_the_freeze_frame(tmp_path: Path) -> None:
    silent = capture(1, 29.99, ("/odom",))
    assert frames(tmp_path, [Step(silent.t_ns, "A", silent)], SnapshotConfig()) == [
        (1, False, True, 0)
    ]


def test_clears_and_the_cap_are_per_fault(tmp_path: Path) -> None:
    a1, b1, a2 = (
        capture(1, 5, ("/odom", "/tf")),
        capture(2, 6, ("/odom",), "B"),
        capture(3, 7, ("/odom", "/tf")),
    )
    steps = [Step(a1.t_ns, "A", a1), Step(b1.t_ns, "B", b1), Step(a2.t_ns, "A", a2)]
    # cap 2: A's second set evicts its first; B's set stays
    assert frames(tmp_path, steps, SnapshotConfig(max_per_fault=2)) == [
        (1, False, False, 2),
        (2, True, True, 1),
        (3, True, True, 2),
    ]
    # clearing A leaves B's snapshots alone; the freeze frames survive the clear
    cleared = [*steps, Step(at(8), "A")]
    assert frames(tmp_path / "c", cleared, SnapshotConfig()) == [
        (1, False, False, 2),
        (2, True, True, 1),
        (3, False, True, 2),
    ]


def test_muted_faults_are_captured_too() -> None:
    result = replay(
        [ROOT / "examples/nav2_mission.jsonl"],
        [ROOT / "rules/nav2/fault_manager.yaml", ROOT / "examples/evidence/capture.yaml"],
    )
    muted = {m.fault_code for m in result.muted_faults}
    confirmed_by_report = {
        t.fault_code
        for t in result.transitions
        if t.to_status == "CONFIRMED" and t.cause == "report"
    }
    captured = {c.fault_code for c in result.snapshots}
    assert muted & confirmed_by_report
    assert muted & confirmed_by_report <= captured
