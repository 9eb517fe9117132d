"""A progress bar on standard error while a replay reads a long recording (rich.progress).

Fed by ``replay(progress=...)``; shown only on a terminal, and gone (transient) once the replay
ends, so that nothing of it is left in logs, pipes or the summary that follows.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, TextIO

from rich.console import Console
from rich.progress import (
    BarColumn,
    Progress,
    ProgressColumn,
    TaskID,
    TaskProgressColumn,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.text import Text

if TYPE_CHECKING:
    from typing import Self

    from rich.progress import Task

    from medkit_replay.model import Phase, Progress as ReplayProgress

PHASE_LABELS: dict[str, str] = {
    "prescan": "finding recorded ReportFault calls",
    "replay": "replaying",
}
"""What each pass of the replay is called on the bar."""


class _BagTimeColumn(ProgressColumn):
    """Bag time read so far, and of how much when the recording's span is known."""

    def render(self, task: Task) -> Text:
        done, total = task.completed, task.total
        digits = 0 if max(done, total or 0) >= 100 else 1
        text = f"{done:,.{digits}f}" + (f"/{total:,.{digits}f}" if total is not None else "")
        return Text(f"{text} s", style="progress.download", no_wrap=True)


class _MessagesColumn(ProgressColumn):
    """Messages read so far (of the topics the replay reads)."""

    def render(self, task: Task) -> Text:
        messages = task.fields.get("messages", 0)
        return Text(f"{messages:,} msgs", style="progress.data.speed", no_wrap=True)


class _TimeColumn(ProgressColumn):
    """Time remaining when the span is known, else time elapsed."""

    def __init__(self) -> None:
        super().__init__()
        self._remaining = TimeRemainingColumn()
        self._elapsed = TimeElapsedColumn()

    def render(self, task: Task) -> Text:
        if task.total is None:
            return self._elapsed.render(task)
        eta = self._remaining.render(task)
        return Text.assemble(("ETA ", "progress.remaining"), eta)


class TransientBar:
    """A rich progress display on ``stream`` that is gone once it stops; a context manager.

    The one setup of the replay's bar and a fleet's or sweep's bar: ``columns`` say what it
    shows (``markup``: whether rich markup in the stream's text is read).
    """

    def __init__(self, stream: TextIO, *columns: ProgressColumn, markup: bool = True) -> None:
        console = Console(file=stream, highlight=False, emoji=False, markup=markup)
        self._progress = Progress(
            *columns,
            console=console,
            transient=True,
            redirect_stdout=False,
            redirect_stderr=False,
            refresh_per_second=8,
        )

    def __enter__(self) -> Self:
        self._progress.start()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self._progress.stop()


class ProgressBar(TransientBar):
    """A callable for ``replay(progress=...)`` drawing one bar per pass; a context manager.

    The bar advances with bag time when the recording declares its span up front (indexed
    MCAP, ``.db3``), with an ETA; otherwise it counts messages and time elapsed.
    """

    def __init__(self, stream: TextIO) -> None:
        super().__init__(
            stream,
            TextColumn("{task.description}"),
            BarColumn(bar_width=24),
            TaskProgressColumn(),
            _BagTimeColumn(),
            _MessagesColumn(),
            _TimeColumn(),
        )
        self._passes: dict[Phase, _Pass] = {}

    def __call__(self, update: ReplayProgress) -> None:
        """Show one report of the replay's progress."""
        state = self._passes.get(update.phase)
        if state is None:
            total = None
            if update.start_ns is not None and update.end_ns is not None:
                total = max(update.end_ns - update.start_ns, 0) / 1e9
            label = PHASE_LABELS.get(update.phase, update.phase)
            task = self._progress.add_task(label, total=total, messages=0)
            state = _Pass(task, update.start_ns, total)
            self._passes[update.phase] = state
        if state.origin_ns is None:
            state.origin_ns = update.t_ns  # no span: bag time since this pass's first message
        completed = 0.0
        if update.t_ns is not None and state.origin_ns is not None:
            completed = max(update.t_ns - state.origin_ns, 0) / 1e9
        if update.done and state.total is not None:
            completed = state.total
        self._progress.update(
            state.task,
            completed=completed,
            messages=update.messages,
            visible=not (update.done and update.phase == "prescan"),
        )


@dataclass(slots=True)
class _Pass:
    """The bar of one pass over the recording."""

    task: TaskID
    origin_ns: int | None
    total: float | None
