"""A sweep on the terminal: the variants ranked, best first, and the inputs that failed.

Labels and paths are shown literally (no rich markup, control characters escaped); away from a
terminal the summary is plain text at 80 columns (or ``COLUMNS``). No path, code or number is
ever split (outputs/summary_lines.py).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, TextIO

from rich.console import Group
from rich.text import Text

from medkit_replay.fleet.terminal import said
from medkit_replay.outputs.console import draw, literal_console
from medkit_replay.outputs.summary_lines import Cell, Flow, Rows, cell, piece
from medkit_replay.result import release_line
from medkit_replay.text import printable
from medkit_replay.tuning.ranking import RANKING, same_latency

if TYPE_CHECKING:
    from collections.abc import Sequence
    from pathlib import Path

    from rich.console import RenderableType

    from medkit_replay.tuning.metrics import RunRow
    from medkit_replay.tuning.ranking import VariantTotal

MAX_VARIANT_ROWS = 30
"""Variants listed on the terminal; variants.csv has all of them."""
MAX_ERROR_ROWS = 10


def _seconds(ns: int | None) -> str:
    return "" if ns is None else f"{ns / 1e9:,.2f}"


def summary_renderables(
    totals: Sequence[VariantTotal],
    inputs: int,
    failed: Sequence[RunRow],
    out_dir: Path | None,
    *,
    budget: bool,
    over_budget: Sequence[tuple[str, str, int]] = (),
) -> list[RenderableType]:
    """What the terminal summary shows, as rich renderables; ``over_budget``: (input, budget
    failures, variants) of the ways inputs failed the budget."""
    head = Text()
    head.append("sweep: ", style="bold")
    head.append(f"{len(totals):,} variant(s) x {inputs:,} input(s)")
    releases = list(dict.fromkeys(total.upstream_release for total in totals))
    parts: list[RenderableType] = [head, Text(release_line(releases), style="dim")]
    latency_note = same_latency(totals)
    names = ["conf", "flaps", "events", "muted", "near"]
    if latency_note is None:
        names.append("lat s")
    if budget:
        names.append("over")
    rows: list[list[Cell]] = []
    for total in totals[:MAX_VARIANT_ROWS]:
        row = [
            cell(str(total.rank)),
            cell(printable(total.variant)),
            cell(f"{total.faults_confirmed:,}"),
            cell(f"{total.flaps:,}"),
            cell(f"{total.events:,}"),
            cell(f"{total.muted_events:,}"),
            cell(f"{total.near_misses:,}"),
        ]
        if latency_note is None:
            row.append(cell(_seconds(total.latency_mean_ns)))
        if budget:
            over = total.budget_failed
            row.append(cell(f"{over:,}", "bold red" if over else ""))
        rows.append(row)
    heads = ["#", "variant", *names]
    right = frozenset(range(2, len(heads))) | {0}
    labels = [printable(total.label) for total in totals[:MAX_VARIANT_ROWS]]
    title = "variants, best first (each with its parameters below)"
    parts.append(Rows(heads, rows, right=right, title=title, wide=1, below=labels))
    legend = (
        "conf: faults confirmed (summed over inputs); flaps: confirm-heal cycles; events: "
        "FaultEvents published; muted: events muted by correlation; near: near misses"
        + ("; lat s: mean detection latency" if latency_note is None else f"; {latency_note}")
        + ("; over: inputs over budget" if budget else "")
        + f". Ranked by {RANKING}."
    )
    parts.append(Text(legend, style="dim"))
    if len(totals) > MAX_VARIANT_ROWS:
        more = len(totals) - MAX_VARIANT_ROWS
        parts.append(Text(f"... {more:,} more variants in variants.csv", style="dim"))
    if over_budget:
        parts.append(Text("over budget:", style="bold red"))
        for path, why, variants in over_budget[:MAX_ERROR_ROWS]:
            shown = f"{why} ({variants:,} variant{'' if variants == 1 else 's'})"
            parts.append(said(path, shown))
        if len(over_budget) > MAX_ERROR_ROWS:
            more = len(over_budget) - MAX_ERROR_ROWS
            parts.append(Text(f"  ... {more:,} more in runs.csv"))
    if failed:
        parts.append(Text("not replayed:", style="bold red"))
        for failure in failed[:MAX_ERROR_ROWS]:
            parts.append(said(failure.variant, str(failure.error)))
        if len(failed) > MAX_ERROR_ROWS:
            parts.append(Text(f"  ... {len(failed) - MAX_ERROR_ROWS:,} more in runs.csv"))
    if out_dir is not None:
        parts.append(Flow([piece("tables:"), piece(f" {printable(str(out_dir))}/", whole=True)]))
    return parts


def print_summary(stream: TextIO, parts: list[RenderableType]) -> None:
    """Draw the summary on ``stream``: rich on a terminal, plain text elsewhere (80 columns
    unless ``COLUMNS`` says otherwise)."""
    draw(literal_console(stream), Group(*parts), crop=False)
