"""A fleet on the terminal: the summary printed after the runs and the progress bar meanwhile.

Text that comes from a recording or a path is shown literally (no rich markup, control
characters escaped); away from a terminal the summary is plain text at 80 columns (or
``COLUMNS``). No path, code or number is ever split (outputs/summary_lines.py).
"""

from __future__ import annotations

from itertools import islice
from typing import TYPE_CHECKING, TextIO

from rich.console import Group
from rich.padding import Padding
from rich.text import Text

from medkit_replay.fleet.progress import FleetProgress, fleet_progress
from medkit_replay.fleet.report import FILES, is_missing
from medkit_replay.fleet.stats import codes_table, overview
from medkit_replay.outputs.console import draw, literal_console, plain_text
from medkit_replay.outputs.summary_lines import Cell, Flow, Rows, cell, piece
from medkit_replay.releases import DEFAULT_RELEASE
from medkit_replay.result import release_line
from medkit_replay.text import printable

if TYPE_CHECKING:
    from collections.abc import Sequence
    from pathlib import Path

    from rich.console import RenderableType

    from medkit_replay.fleet.run import RunSummary

__all__ = ["FleetProgress", "fleet_progress", "print_summary", "render_summary"]

MAX_RUN_ROWS = 40
"""Runs listed on the terminal; the files have all of them."""
MAX_CODE_ROWS = 20
"""Codes listed on the terminal."""
MAX_ERROR_ROWS = 20
"""Failed recordings listed on the terminal."""
MAX_WARNING_ROWS = 10
"""Warnings listed on the terminal (the first ones of the runs in order); runs.csv counts all."""


def _seconds(value: float | None) -> str:
    return "" if value is None or is_missing(value) else f"{value:,.1f}"


def _plural(count: int, word: str) -> str:
    return f"{count:,} {word}" + ("" if count == 1 else "s")


def _indented(text: Text) -> Padding:
    return Padding(text, (0, 0, 0, 2))


def said(name: str, text: str) -> Flow:
    """``name: text`` under two spaces, the name whole, the text broken only at spaces."""
    pieces = [piece(printable(name) + ":", whole=True), piece(" " + printable(text))]
    return Flow(pieces, indent=2, hang=4)


def summary_renderables(
    runs: Sequence[RunSummary], out_dir: Path | None, release: str = DEFAULT_RELEASE
) -> list[RenderableType]:
    """What the terminal summary shows, as rich renderables; ``release``: the ros2_medkit
    release every run is replayed as."""
    counts = overview(runs)
    head = Text()
    head.append("fleet: ", style="bold")
    head.append(f"{_plural(counts['runs'], 'recording')}, {counts['replayed']:,} replayed")
    if counts["failed"]:
        head.append(f", {counts['failed']:,} failed", style="bold red")
    head.append(
        f"; {_plural(counts['messages'], 'message')} read; "
        f"{counts['runs_with_confirmed']:,} with a confirmed fault"
    )
    parts: list[RenderableType] = [head, Text(release_line([release]), style="dim")]
    verdicts = {k.removeprefix("budget_"): v for k, v in counts.items() if k.startswith("budget_")}
    if verdicts:
        line = Text("budget: ", style="bold")
        for index, (verdict, number) in enumerate(verdicts.items()):
            line.append(", " if index else "")
            line.append(f"{number:,} {verdict}", style="bold red" if verdict == "fail" else "")
        parts.append(line)

    heads = ["path", "span s", "msgs", "conf", "heal", "clear"] + (["budget"] if verdicts else [])
    rows: list[list[Cell]] = []
    for run in runs[:MAX_RUN_ROWS]:
        statuses = dict(run.faults_by_status)
        span = run.span_ns
        row = [
            cell(printable(str(run.path)), "" if run.ok else "red"),
            cell(_seconds(span / 1e9 if span is not None else None)),
            cell(f"{run.messages:,}" if run.messages is not None else ""),
            *(
                cell(f"{statuses.get(s, 0):,}" if run.ok else "")
                for s in ("CONFIRMED", "HEALED", "CLEARED")
            ),
        ]
        if verdicts:
            row.append(cell(run.budget or "", "bold red" if run.budget == "fail" else ""))
        rows.append(row)
    title = "runs (faults CONFIRMED, HEALED, CLEARED at the end)"
    parts.append(Rows(heads, rows, right=frozenset(range(1, 6)), title=title))
    if len(runs) > MAX_RUN_ROWS:
        parts.append(Text(f"... {len(runs) - MAX_RUN_ROWS:,} more runs in runs.csv", style="dim"))

    codes = codes_table(runs)
    if len(codes):
        code_rows = [
            [
                cell(printable(str(record["fault_code"]))),
                cell(f"{record['runs_confirmed']:,}"),
                cell(f"{record['share_of_runs']:.0%}"),
                cell(f"{record['heals']:,}"),
                cell(_seconds(record["mean_time_to_heal_s"])),
                cell(_seconds(record["median_time_to_heal_s"])),
            ]
            for record in codes.head(MAX_CODE_ROWS).to_dict(orient="records")
        ]
        code_heads = ["fault code", "runs", "share", "heals", "mean heal", "median heal"]
        title = "codes confirmed across runs"
        parts.append(Rows(code_heads, code_rows, right=frozenset(range(1, 6)), title=title))
        if len(codes) > MAX_CODE_ROWS:
            more = len(codes) - MAX_CODE_ROWS
            parts.append(Text(f"... {more:,} more codes in codes.csv", style="dim"))

    over = [run for run in runs if run.budget == "fail"]
    if over:
        parts.append(Text("over budget:", style="bold red"))
        for run in over[:MAX_ERROR_ROWS]:
            rules = "; ".join(run.budget_failures)
            parts.append(said(str(run.path), rules))
        if len(over) > MAX_ERROR_ROWS:
            more = len(over) - MAX_ERROR_ROWS
            parts.append(_indented(Text(f"... {more:,} more in runs.csv", style="dim")))
    parts.extend(_warnings(runs))
    failed = [run for run in runs if not run.ok]
    if failed:
        parts.append(Text("not replayed:", style="bold red"))
        for run in failed[:MAX_ERROR_ROWS]:
            error = run.error or ""
            shown = error.removeprefix(run.path).removeprefix(":").strip()
            parts.append(said(str(run.path), shown))
        if len(failed) > MAX_ERROR_ROWS:
            more = len(failed) - MAX_ERROR_ROWS
            parts.append(_indented(Text(f"... {more:,} more in runs.csv", style="dim")))
    if out_dir is not None:
        report = [piece("report:"), piece(f" {printable(str(out_dir))}/", whole=True)]
        parts.append(Flow([*report, piece(f" ({', '.join(FILES)})")]))
    return parts


def _warnings(runs: Sequence[RunSummary]) -> list[RenderableType]:
    """The runs' warnings, the first MAX_WARNING_ROWS of them, then how many more."""
    total = sum(run.warnings for run in runs)
    if not total:
        return []
    parts: list[RenderableType] = [Text(f"warnings: {total:,}", style="bold yellow")]
    first = ((run.path, warning) for run in runs for warning in run.first_warnings)
    shown = 0
    for path, warning in islice(first, MAX_WARNING_ROWS):
        text = warning.removeprefix(path).removeprefix(":").strip()
        parts.append(said(str(path), text))
        shown += 1
    if total > shown:
        within = sum(1 for run in runs if run.warnings)
        parts.append(
            _indented(
                Text(
                    f"+{total - shown:,} more ({within:,} runs with warnings: runs.csv counts "
                    "them; analyze a run to read all of its own)",
                    style="dim",
                )
            )
        )
    return parts


def render_summary(
    runs: Sequence[RunSummary],
    out_dir: Path | None = None,
    release: str = DEFAULT_RELEASE,
    width: int = 80,
) -> str:
    """The terminal summary as plain text at ``width`` columns (what a file or a pipe
    receives: 80, or ``COLUMNS``)."""
    return plain_text(Group(*summary_renderables(runs, out_dir, release)), width, crop=False)


def print_summary(
    runs: Sequence[RunSummary],
    stream: TextIO,
    out_dir: Path | None = None,
    release: str = DEFAULT_RELEASE,
) -> None:
    """Draw the summary on ``stream``: rich on a terminal, plain 80-column text elsewhere."""
    console = literal_console(stream)
    draw(console, Group(*summary_renderables(runs, out_dir, release)), crop=False)
