"""A bar counting finished runs on standard error (a fleet's recordings, a sweep's jobs).

Shown only on a terminal and gone once the runs end; imports rich only.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol, TextIO

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from medkit_replay.outputs.console import bar_terminal

if TYPE_CHECKING:
    from types import TracebackType
    from typing import Self


class Finished(Protocol):
    """What the bar reads of a finished run."""

    @property
    def ok(self) -> bool:
        """The run succeeded."""


class FleetProgress:
    """A bar counting finished runs, on standard error; a context manager, and the
    ``on_done`` callback of the executors."""

    def __init__(self, stream: TextIO, total: int) -> None:
        console = Console(file=stream, highlight=False, emoji=False, markup=False)
        self._progress = Progress(
            TextColumn("{task.description}"),
            BarColumn(bar_width=30),
            MofNCompleteColumn(),
            TextColumn("{task.fields[failed]}"),
            TimeElapsedColumn(),
            TimeRemainingColumn(),
            console=console,
            transient=True,
            redirect_stdout=False,
            redirect_stderr=False,
            refresh_per_second=8,
        )
        self._task = self._progress.add_task("replaying", total=total, failed="")
        self._failed = 0

    def __enter__(self) -> Self:
        self._progress.start()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self._progress.stop()

    def __call__(self, index: int, run: Finished) -> None:
        """One more run finished."""
        self._failed += 0 if run.ok else 1
        failed = f"{self._failed} failed" if self._failed else ""
        self._progress.update(self._task, advance=1, failed=failed)


def fleet_progress(stream: TextIO, total: int, *, quiet: bool = False) -> FleetProgress | None:
    """A progress bar on ``stream``, or None under ``--quiet`` or when it is not a terminal."""
    return FleetProgress(stream, total) if bar_terminal(stream, quiet=quiet) else None
