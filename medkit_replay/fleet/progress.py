"""A bar counting finished runs on standard error (a fleet's recordings, a sweep's jobs).

Shown only on a terminal and gone once the runs end; imports rich and the replay's bar only.
"""

from __future__ import annotations

from typing import Protocol, TextIO

from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from medkit_replay.outputs.console import bar_terminal
from medkit_replay.outputs.progress import TransientBar


class Finished(Protocol):
    """What the bar reads of a finished run."""

    @property
    def ok(self) -> bool:
        """The run succeeded."""


class FleetProgress(TransientBar):
    """A bar counting finished runs, on standard error; a context manager, and the
    ``on_done`` callback of the executors."""

    def __init__(self, stream: TextIO, total: int) -> None:
        super().__init__(
            stream,
            TextColumn("{task.description}"),
            BarColumn(bar_width=30),
            MofNCompleteColumn(),
            TextColumn("{task.fields[failed]}"),
            TimeElapsedColumn(),
            TimeRemainingColumn(),
            markup=False,
        )
        self._task = self._progress.add_task("replaying", total=total, failed="")
        self._failed = 0

    def __call__(self, index: int, run: Finished) -> None:
        """One more run finished."""
        self._failed += 0 if run.ok else 1
        failed = f"{self._failed} failed" if self._failed else ""
        self._progress.update(self._task, advance=1, failed=failed)


def fleet_progress(stream: TextIO, total: int, *, quiet: bool = False) -> FleetProgress | None:
    """A progress bar on ``stream``, or None under ``--quiet`` or when it is not a terminal."""
    return FleetProgress(stream, total) if bar_terminal(stream, quiet=quiet) else None
