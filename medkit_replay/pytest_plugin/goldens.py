"""Golden reports: the ``golden`` fixture and ``assert_matches_golden``, with ``--update-golden``.

A result is compared with a stored JSON report as ``medkit-replay diff`` compares; a missing or
differing golden is written instead when an update is asked for.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from medkit_replay.pytest_plugin.session import (
    golden_size_limit,
    keeping_modules,
    note_updated,
    update_requested,
)

if TYPE_CHECKING:
    from medkit_replay.pytest_plugin.replays import PathLike
    from medkit_replay.result import Result

DIFF_WIDTH = 100
"""Columns the golden-report diff is laid out for in a failure message."""


class Golden:
    """Compares results with golden reports kept beside a test file."""

    def __init__(self, directory: Path, default_name: str) -> None:
        self.directory = directory
        self.default_name = default_name

    def path(self, name: PathLike | None = None) -> Path:
        """Where a golden report lives: ``name`` relative to the goldens folder, or the test's
        default (``<test module>/<test name>.json``)."""
        return self.directory / (name if name is not None else self.default_name)

    def __call__(
        self, result: Result, name: PathLike | None = None, *, time_tolerance: float = 0.0
    ) -> None:
        """Assert that ``result`` matches the golden report (see :func:`assert_matches_golden`)."""
        __tracebackhide__ = True
        assert_matches_golden(result, self.path(name), time_tolerance=time_tolerance)


@pytest.fixture
def golden(request: pytest.FixtureRequest) -> Golden:
    """``golden(result, name=None, *, time_tolerance=0.0)``: compare with a golden report."""
    test_file = request.path
    name = re.sub(r"[^A-Za-z0-9_.-]+", "_", request.node.name).strip("_") or "golden"
    return Golden(test_file.parent / "goldens", f"{test_file.stem}/{name}.json")


def assert_matches_golden(
    result: Result,
    path: PathLike,
    *,
    time_tolerance: float = 0.0,
    update: bool | None = None,
) -> None:
    """Assert that the result's report matches the golden JSON report at ``path`` (compared as
    ``medkit-replay diff`` compares, events and transitions within ``time_tolerance`` seconds).

    With ``update`` (by default: pytest's ``--update-golden``), a missing or differing golden is
    written from the result instead, and the assertion passes. The failure message is the diff.
    """
    __tracebackhide__ = True
    golden_path = Path(path)
    if update is None:
        update = update_requested()
    if not golden_path.exists():
        if update:
            _write_golden(result, golden_path)
            return
        raise AssertionError(
            f"golden report {golden_path} does not exist\n"
            "  run pytest with --update-golden to write it from this run"
        )
    with keeping_modules():
        from medkit_replay.diffing import diff_reports, read_report, render_diff, tolerance_ns  # noqa: PLC0415  # only when used
        from medkit_replay.outputs.json_report import to_report  # noqa: PLC0415

        diff = diff_reports(
            read_report(golden_path, golden_size_limit()),
            to_report(result),
            time_tolerance_ns=tolerance_ns(time_tolerance),
            baseline_name=str(golden_path),
            current_name="this run",
        )
        shown = None if diff.equal else render_diff(diff, DIFF_WIDTH)
    if shown is None:
        return
    if update:
        _write_golden(result, golden_path)
        return
    raise AssertionError(
        "the run differs from its golden report\n"
        + shown
        + "\nrun pytest with --update-golden to accept this run as the new golden report"
    )


def _write_golden(result: Result, path: Path) -> None:
    """Write a golden report whole (a temporary file renamed into place), compressed when its
    name ends in ``.gz`` or ``.zst``."""
    with keeping_modules():
        from medkit_replay.outputs.report_file import write_report  # noqa: PLC0415

        path.parent.mkdir(parents=True, exist_ok=True)
        write_report(result, path)
    note_updated(path)
