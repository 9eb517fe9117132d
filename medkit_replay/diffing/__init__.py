"""What changed between two JSON reports: ``medkit-replay diff`` and the golden-report pytest
fixture both use this package. :mod:`~medkit_replay.diffing.reports` reads a report file from disk,
strictly and within bounds; :mod:`~medkit_replay.diffing.compare` compares two report dicts into a
:class:`ReportDiff` (pure: no file, no clock, no terminal), aligning each fault's transitions and
events with :mod:`~medkit_replay.diffing.align`; :mod:`~medkit_replay.diffing.render` draws the
diff for people with rich, and :meth:`ReportDiff.to_json` gives it as JSON.
"""

from __future__ import annotations

from medkit_replay.diffing.compare import DIFF_SCHEMA, KINDS, ReportDiff, diff_reports, tolerance_ns
from medkit_replay.diffing.render import diff_renderable, render_diff
from medkit_replay.diffing.reports import read_report

__all__ = [
    "DIFF_SCHEMA",
    "KINDS",
    "ReportDiff",
    "diff_renderable",
    "diff_reports",
    "read_report",
    "render_diff",
    "tolerance_ns",
]
