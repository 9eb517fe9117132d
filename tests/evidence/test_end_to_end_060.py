"""--evidence on the same generated robot recording with ``upstream_release`` 0.6.0 and 0.7.0 and
no ``snapshots.rosbag.format``: 0.6.0 writes its recordings in sqlite3 (node@bdcc4ed0 declares
"sqlite3" as the default; 054a41a5, #610, made it mcap) and keeps no compact freeze frame."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Any

import pytest

from medkit_replay.cli import main
from tests.evidence.robot import CONFIG, write_config, write_robot

if TYPE_CHECKING:
    from pathlib import Path


def analyze(root: Path, release: str) -> tuple[dict[str, Any], Path]:
    robot = write_robot(root)
    config = write_config(root)
    config.write_text(
        CONFIG.replace("        format: {fmt}\n", "").format()
        + f'medkit_replay:\n  ros__parameters:\n    upstream_release: "{release}"\n'
    )
    out, evidence = root / "report.json", root / "evidence"
    argv = [str(robot.bag), str(robot.script), "--config", str(config), "--graph", str(robot.graph)]
    argv += ["--evidence", str(evidence), "--json", str(out), "--quiet"]
    assert main(["analyze", *argv]) == 0
    return json.loads(out.read_text()), evidence


@pytest.mark.parametrize(("release", "suffix"), [("0.6.0", ".db3"), ("0.7.0", ".mcap")])
def test_the_default_bag_format_follows_the_release(
    tmp_path: Path, release: str, suffix: str
) -> None:
    report, evidence = analyze(tmp_path, release)
    written = [r for r in report["recordings"] if r["path"] is not None]
    assert written
    for recording in written:
        files = [p.suffix for p in (evidence / recording["path"]).iterdir()]
        other = ".mcap" if suffix == ".db3" else ".db3"
        assert suffix in files and other not in files
    freeze_frames = [s["freeze_frame"] for s in report["snapshots"]]
    assert any(freeze_frames) == (release == "0.7.0")
