"""Budget verdicts on the terminal with rich: one line per rule, the offending faults below it.

Colour on a terminal, plain text (80 columns or ``COLUMNS``) in a file, a pipe or a CI log.
Recorded text goes into ``rich.text.Text`` objects after :func:`printable`: never parsed as
markup or emoji, never able to move the cursor.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, TextIO

from rich.console import Console
from rich.text import Text

from medkit_replay.model import read_in_part
from medkit_replay.outputs.summary_lines import Beside, Flow, flow, piece
from medkit_replay.result import release_line
from medkit_replay.text import WARNING_CAP, clip, printable

if TYPE_CHECKING:
    from collections.abc import Sequence

    from rich.console import RenderableType

    from medkit_replay.checks.evaluate import CheckRun, Verdict

PLAIN_WIDTH = 4096
"""Columns of plain output: wide enough that no verdict line wraps."""
MAX_OFFENDERS = 10
"""Offending faults listed per rule on the terminal; JUnit and the step summary list more."""


def _plural(count: int, word: str) -> str:
    return f"{count} {word}" + ("" if count == 1 else "s")


Row = tuple[str, str, list[Flow]]
"""A mark (PASS, FAIL, ERROR, !), its style, and the lines beside it."""


def _verdict_row(verdict: Verdict) -> Row:
    mark, style = ("PASS", "bold green") if verdict.passed else ("FAIL", "bold red")
    lines = [
        Flow(
            [
                piece(printable(verdict.rule.name) + ":", "bold", whole=True),
                piece(" " + printable(verdict.message)),
            ]
        )
    ]
    for offender in verdict.offenders[:MAX_OFFENDERS]:
        lines.append(
            Flow([piece("-", whole=True), piece(" " + printable(offender.text()), "red")], hang=2)
        )
    hidden = len(verdict.offenders) - MAX_OFFENDERS
    if hidden > 0:
        lines.append(Flow([piece(f"... and {hidden} more", "dim", whole=True)], indent=2))
    return (mark, style, lines)


def _marked(rows: list[Row]) -> Beside:
    """Each row's mark, styled and padded to the widest, then its lines beside it."""
    size = max((len(mark) for mark, _, _ in rows), default=0)
    leads = []
    for mark, style, lines in rows:
        lead = Text(f"{mark:<{size}} ")
        lead.stylize(style, 0, len(mark))
        leads.append((lead, lines))
    return Beside(leads)


def run_renderable(run: CheckRun) -> list[RenderableType]:
    """The verdicts of one run: a heading, a line per rule (or why the run was not checked:
    its recording could not be read, or nothing was replayed), the replay's warnings."""
    head = [
        piece("check", "bold"),
        piece(" "),
        piece(printable(run.label), "bold", whole=True),
        piece(" against "),
        piece(printable(run.budget.title) + ":", whole=True),
        piece(" "),
    ]
    rows: list[Row] = []
    failed = len(run.failures)
    if run.error is not None:
        why = "nothing was replayed" if run.empty else "the recording cannot be read"
        head.append(piece(f"not checked, {why}", "bold red"))
        rows.append(("ERROR", "bold red", [flow(printable(run.error), "red")]))
    elif failed:
        said = f"{failed} of {_plural(len(run.verdicts), 'rule')} failed"
        head.append(piece(said, "bold red"))
    else:
        head.append(piece(f"all {_plural(len(run.verdicts), 'rule')} passed", "bold green"))
    if run.damage:
        head.append(piece("; read only in part (--strict)", "bold red"))
    rows += [_verdict_row(verdict) for verdict in run.verdicts]
    rows += [("FAIL", "bold red", [flow(printable(line), "red")]) for line in run.damage]
    for warning in run.warnings:
        shown = printable(clip(warning, WARNING_CAP))
        rows.append(("!", "bold yellow", [flow(shown, "yellow")]))
    if not run.damage:
        for loss in run.losses:
            total = printable(read_in_part(loss))
            rows.append(("!", "bold yellow", [flow(total, "bold yellow")]))
    return [Flow(head), _marked(rows), Text("")]


def conclusion(runs: Sequence[CheckRun]) -> Text:
    """The last line: whether the budget held on every run (a run that could not be read, or
    that replayed nothing, never holds it)."""
    unreadable = [r for r in runs if r.error is not None and not r.empty]
    empty = [r for r in runs if r.empty]
    if unreadable or empty:
        said = [(len(unreadable), "could not be read")] if unreadable else []
        said += [(len(empty), "replayed nothing")] if empty else []
        (count, what), *more = said
        text = f"check failed: {count} of {_plural(len(runs), 'run')} {what}"
        text += "".join(f", {n} {other}" for n, other in more)
        over = [r for r in runs if r.error is None and not r.passed]
        if over:
            failures = sum(len(r.failures) for r in over)
            text += f"; {_plural(failures, 'rule verdict')} failed in {len(over)}"
        return Text(text, style="bold red")
    failed_runs = [r for r in runs if not r.passed]
    rules = len(runs[0].verdicts) if runs else 0
    if not failed_runs:
        return Text(
            f"budget holds: {_plural(rules, 'rule')} passed on {_plural(len(runs), 'run')}",
            style="bold green",
        )
    failures = sum(len(r.failures) for r in failed_runs)
    over = [r for r in failed_runs if r.failures]
    damaged = sum(1 for r in failed_runs if r.damage)
    strict = f"{damaged} of {_plural(len(runs), 'run')} read only in part (--strict)"
    if not over:
        return Text(f"check failed: {strict}", style="bold red")
    return Text(
        f"budget exceeded: {_plural(failures, 'rule verdict')} failed in "
        f"{len(over)} of {_plural(len(runs), 'run')}" + (f"; {strict}" if damaged else ""),
        style="bold red",
    )


def _console(stream: TextIO, width: int | None = None) -> Console:
    return Console(file=stream, width=width, markup=False, emoji=False, highlight=False)


def print_renderables(renderables: Sequence[RenderableType], stream: TextIO) -> None:
    """Draw on ``stream``: colour on a terminal; elsewhere plain text, one line per verdict and
    per offending fault however long (CI logs are searched, not read at 80 columns)."""
    console = _console(stream)
    if console.is_terminal:
        for renderable in renderables:
            console.print(renderable)
        return
    console = _console(stream, PLAIN_WIDTH)
    with console.capture() as capture:
        for renderable in renderables:
            console.print(renderable)
    stream.write("\n".join(line.rstrip(" ") for line in capture.get().split("\n")))


def print_release(release: str, stream: TextIO) -> None:
    """The check's first line: the ros2_medkit release the runs are replayed as."""
    print_renderables([Text(release_line([release]), style="dim")], stream)


def print_run(run: CheckRun, stream: TextIO) -> None:
    """The verdicts of one run (printed as soon as the run is checked)."""
    print_renderables(run_renderable(run), stream)


def print_conclusion(runs: Sequence[CheckRun], stream: TextIO) -> None:
    """The closing line over every run."""
    print_renderables([conclusion(runs)], stream)
