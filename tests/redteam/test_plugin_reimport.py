"""Red team, pytest plugin: replays in consecutive pytester sessions of one process, which forget
every module a session imported, give the same non-empty results.

The cause of the empty replay once seen: the second session imported numpy again, numpy refused
("cannot load module more than once per process"), the reader took that for an unusable
recorded definition and every message was dropped. The plugin now hands each session the
modules an earlier one imported. Run in a child ``pytest`` so that nothing of the replay is
imported before the first session, as in a user's fresh test process.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
MISSION = ROOT / "sample_bags" / "nav2_mission_mcap"
CONFIGS = [ROOT / "rules" / "nav2" / "fault_manager.yaml", ROOT / "rules" / "nav2" / "bridges.yaml"]
BUDGET = ROOT / "rules" / "budgets" / "nav2_mission_pass.yaml"

INNER = f"""
import json
from pathlib import Path

from medkit_replay.pytest_plugin import assert_matches_golden, assert_within_budget

MISSION = Path({str(MISSION)!r})
CONFIGS = [Path({str(CONFIGS[0])!r}), Path({str(CONFIGS[1])!r})]


def test_the_mission(replay_recording, tmp_path):
    result = replay_recording(MISSION, CONFIGS)
    summary = [
        result.summary.messages_read,
        len(result.events),
        len(result.transitions),
        sorted(f.fault_code for f in result.faults),
        list(result.warnings),
    ]
    print("SUMMARY " + json.dumps(summary))
    assert_within_budget(result, {str(BUDGET)!r})
    golden = Path("golden.json").absolute()
    assert_matches_golden(result, golden, update=not golden.exists())
"""

OUTER = f"""
pytest_plugins = ["pytester"]

INNER = {INNER!r}


def test_three_sessions(pytester):
    pytester.makepyfile(test_inner=INNER)
    for _ in range(3):
        outcome = pytester.runpytest("-s", "-p", "no:cacheprovider")
        for line in outcome.stdout.lines:
            if "SUMMARY " in line:
                print(line[line.index("SUMMARY "):])
        outcome.assert_outcomes(passed=1)
"""


def test_replays_in_consecutive_pytester_sessions_are_equal(tmp_path: Path) -> None:
    (tmp_path / "test_outer.py").write_text(textwrap.dedent(OUTER), encoding="utf-8")
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-s", "-p", "no:cacheprovider", "test_outer.py"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    summaries = [
        json.loads(line.removeprefix("SUMMARY "))
        for line in done.stdout.splitlines()
        if line.startswith("SUMMARY ")
    ]
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr[-2000:]
    assert len(summaries) == 3
    messages, events, transitions, faults, warnings = summaries[0]
    assert messages > 600 and events > 0 and transitions > 0 and faults
    assert warnings == []
    assert summaries[1] == summaries[0] and summaries[2] == summaries[0]
