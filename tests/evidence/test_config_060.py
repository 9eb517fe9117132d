"""The capture settings at 0.6.0 (bdcc4ed0) beside 0.7.0, from the same parameter file: the
parameters 0.6.0 does not declare are not read, and the black box's format defaults to sqlite3.

Upstream at bdcc4ed0: fault_manager_node.cpp's create_snapshot_config (no entity_default, no
retain_on_clear, no max_bags_per_fault, ``format`` default "sqlite3"; default_topics kept as
given), RosbagConfig's ``format{"sqlite3"}`` in snapshot_capture.hpp.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.config.params import load_parameters
from medkit_replay.config.snapshots import snapshot_config
from medkit_replay.releases import release_named

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.evidence.rules import SnapshotConfig

EVERY_NEW_PARAMETER = """\
fault_manager:
  ros__parameters:
    snapshots:
      entity_default: true
      retain_on_clear: true
      rosbag:
        enabled: true
        max_bags_per_fault: 5
"""


def both(tmp_path: Path, text: str) -> dict[str, SnapshotConfig]:
    path = tmp_path / "params.yaml"
    path.write_text(text)
    node = load_parameters([path]).node("fault_manager")
    return {name: snapshot_config(node, release_named(name))[0] for name in ("0.6.0", "0.7.0")}


def test_parameters_060_does_not_declare_are_not_read(tmp_path: Path) -> None:
    old, new = both(tmp_path, EVERY_NEW_PARAMETER).values()
    assert (new.entity_default, new.retain_on_clear, new.rosbag.max_bags_per_fault) == (
        True,
        True,
        5,
    )
    assert (old.entity_default, old.retain_on_clear, old.rosbag.max_bags_per_fault) == (
        False,
        False,
        1,
    )
    assert not old.rosbag.keeps_history  # one recording per fault, whatever the file says


def test_the_black_box_format_defaults_to_sqlite3_at_060(tmp_path: Path) -> None:
    enabled = "fault_manager:\n  ros__parameters:\n    snapshots.rosbag.enabled: true\n"
    unset = both(tmp_path, enabled)
    assert {name: c.rosbag.format for name, c in unset.items()} == {
        "0.6.0": "sqlite3",
        "0.7.0": "mcap",
    }
    chosen = both(tmp_path, enabled + "    snapshots.rosbag.format: mcap\n")
    assert {c.rosbag.format for c in chosen.values()} == {"mcap"}


def test_an_empty_default_topic_is_kept_at_060(tmp_path: Path) -> None:
    # a702f94f dropped '' (launch files' "no defaults") so it cannot shadow entity_default.
    (tmp_path / "snap.yaml").write_text("default_topics: [/d]\n")
    configs = both(
        tmp_path,
        "fault_manager:\n  ros__parameters:\n    snapshots:\n      config_file: snap.yaml\n"
        "      default_topics: ['']\n",
    )
    assert configs["0.7.0"].default_topics == ("/d",)  # the file's list applies
    assert configs["0.6.0"].default_topics == ("",)  # set, so the file's list does not


def test_060_keeps_no_freeze_frame_and_the_first_snapshots(tmp_path: Path) -> None:
    old, new = both(tmp_path, "fault_manager:\n  ros__parameters: {}\n").values()
    assert (new.freeze_frame_row, new.snapshot_sets) == (True, True)
    assert (old.freeze_frame_row, old.snapshot_sets) == (False, False)
    assert (old.rosbag.post_roll_sharing, old.rosbag.post_roll_only) == (False, False)
    assert not old.rosbag.cleanup_in_post_roll
