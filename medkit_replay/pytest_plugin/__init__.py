"""pytest plugin for regression tests of recorded missions (the ``pytest11`` entry point).

Fixtures:

- ``replay_recording(inputs, configs=())``: replays a recording (or several merged, or a JSON-lines
  script) with ROS 2 parameter files and returns the :class:`~medkit_replay.result.Result`;
  cached per (inputs, configs) for the whole session.
- ``golden(result, name=None, *, time_tolerance=0.0)``: compares the result with a stored JSON
  report, by default ``goldens/<test module>/<test name>.json`` beside the test file.

Assertion helpers (import them from this module): :func:`assert_confirmed`,
:func:`assert_not_confirmed`, :func:`assert_status`, :func:`assert_within_budget` and
:func:`assert_matches_golden`. Their failures show the fault's timeline (status changes and
FaultEvents) or the diff with the golden report.

Options: ``--update-golden`` rewrites golden reports that differ (or are missing) instead of
failing; ``--allow-empty-replay`` lets :func:`assert_within_budget` pass a replay in which nothing
reached the fault manager (as ``--allow-empty`` does for ``check``).

Loaded into every pytest session of an environment where medkit-replay is installed, so it does
nothing until one of its fixtures or helpers is used: no import of the replay, no output.

The replay's modules are imported once per process, also under pytester, whose in-process
sessions forget every module a session imported: each session gets the same module objects
back (see ``session._KEPT``). Imported a second time, numpy refuses to load ("cannot load module
more than once per process") and our classes would exist twice; that once turned every recorded
definition into "unusable" and the replay of the next session into an empty one.

pytest loads this package as the plugin: its hooks and fixtures, defined in the submodules
(``session``, ``replays``, ``goldens``; helpers in ``assertions`` and ``timeline``), are found
here as names of this module.
"""

from __future__ import annotations

from medkit_replay.pytest_plugin.assertions import (
    MAX_FAULTS_SHOWN,
    Window,
    assert_confirmed,
    assert_not_confirmed,
    assert_status,
    assert_within_budget,
)
from medkit_replay.pytest_plugin.goldens import (
    DIFF_WIDTH,
    Golden,
    assert_matches_golden,
    golden,
)
from medkit_replay.pytest_plugin.replays import PathLike, RecordingReplayer, replay_recording
from medkit_replay.pytest_plugin.session import (
    pytest_addoption,
    pytest_configure,
    pytest_terminal_summary,
    pytest_unconfigure,
)
from medkit_replay.pytest_plugin.timeline import (
    MAX_TIMELINE_ROWS,
    fault_timeline,
    recording_start_ns,
)

__all__ = [
    "DIFF_WIDTH",
    "MAX_FAULTS_SHOWN",
    "MAX_TIMELINE_ROWS",
    "Golden",
    "PathLike",
    "RecordingReplayer",
    "Window",
    "assert_confirmed",
    "assert_matches_golden",
    "assert_not_confirmed",
    "assert_status",
    "assert_within_budget",
    "fault_timeline",
    "golden",
    "pytest_addoption",
    "pytest_configure",
    "pytest_terminal_summary",
    "pytest_unconfigure",
    "recording_start_ns",
    "replay_recording",
]
