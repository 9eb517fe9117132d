"""Snapshot storage at 0.6.0 (bdcc4ed0's fault_storage.cpp and sqlite_fault_storage.cpp) beside
0.7.0, over the same captures and clears of a generated recording.

0.6.0 stores a capture row by row and refuses rows once a fault holds ``max_per_fault`` (the
first ones are kept), deletes a fault's snapshots on every clear, and keeps no compact freeze
frame. Ported from bdcc4ed0: InMemorySnapshotLimitTest.RejectsWhenFull and
SqliteFaultStorageTest.SnapshotLimitRejectsNewWhenFull (limit 2, three snapshots: the first two
kept), InMemorySnapshotLimitTest.UnlimitedWhenZero, and
SqliteFaultStorageTest.ClearFaultDeletesAssociatedSnapshots.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

from medkit_replay.evidence.frames import freeze_frames
from medkit_replay.evidence.plan import Plan, Step
from medkit_replay.evidence.rules import SnapshotConfig
from medkit_replay.evidence.source import EvidenceSource
from tests.evidence.robot import at, write_robot
from tests.evidence.test_frames import capture, frames

if TYPE_CHECKING:
    from pathlib import Path

OLD = SnapshotConfig(freeze_frame_row=False, snapshot_sets=False)
"""SnapshotConfig() as 0.6.0 reads it (retain_on_clear is not a parameter there)."""


def captures_of(*topic_counts: int) -> list[Step]:
    """One capture of fault A per count, a second apart, each of that many topics."""
    topics = ("/odom", "/tf")
    steps = []
    for index, count in enumerate(topic_counts, 1):
        planned = capture(index, 4 + index, topics[:count])
        steps.append(Step(planned.t_ns, "A", planned))
    return steps


def test_the_limit_keeps_the_first_rows_at_060(tmp_path: Path) -> None:
    steps = captures_of(1, 1, 1)  # RejectsWhenFull: three snapshots, limit 2
    assert frames(tmp_path / "old", steps, replace(OLD, max_per_fault=2)) == [
        (1, True, False, 1),
        (2, True, False, 1),
        (3, False, False, 1),
    ]
    assert frames(tmp_path / "new", steps, SnapshotConfig(max_per_fault=2)) == [
        (1, False, False, 1),
        (2, True, False, 1),
        (3, True, True, 1),
    ]


def test_a_capture_straddling_the_limit_is_held_in_part_at_060(tmp_path: Path) -> None:
    steps = captures_of(1, 2)  # three rows in all, limit 2: the second capture's first row fits
    assert frames(tmp_path / "old", steps, replace(OLD, max_per_fault=2)) == [
        (1, True, False, 1),
        (2, True, False, 2),
    ]
    # 0.7.0 stores the second capture whole and evicts the first (df421024)
    assert frames(tmp_path / "new", steps, SnapshotConfig(max_per_fault=2)) == [
        (1, False, False, 1),
        (2, True, True, 2),
    ]


def test_no_limit_when_zero(tmp_path: Path) -> None:
    steps = captures_of(*[1] * 12)  # UnlimitedWhenZero, at both
    assert all(r for _, r, _, _ in frames(tmp_path, steps, replace(OLD, max_per_fault=0)))


def test_a_clear_deletes_the_snapshots_and_060_keeps_no_freeze_frame(tmp_path: Path) -> None:
    steps = [*captures_of(2), Step(at(8), "A")]  # ClearFaultDeletesAssociatedSnapshots
    assert frames(tmp_path / "old", steps, OLD) == [(1, False, False, 2)]
    assert frames(tmp_path / "new", steps, SnapshotConfig()) == [(1, False, True, 2)]
    # retain_on_clear (0.7.0 only) keeps them
    kept = SnapshotConfig(retain_on_clear=True)
    assert frames(tmp_path / "kept", steps, kept) == [(1, True, True, 2)]


def test_the_capture_held_in_part_is_named(tmp_path: Path) -> None:
    steps = captures_of(1, 2)
    plan = Plan(captures=[s.capture for s in steps if s.capture is not None], steps=steps)
    source = EvidenceSource([write_robot(tmp_path).bag])
    cut: list[int] = []
    try:
        freeze_frames(plan, replace(OLD, max_per_fault=2), source, cut)
        assert cut == [2]
        whole: list[int] = []
        freeze_frames(plan, SnapshotConfig(max_per_fault=2), source, whole)
        assert whole == []  # 0.7.0 never stores a capture in part
    finally:
        source.close()
