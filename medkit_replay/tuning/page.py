"""A sweep as one self-contained HTML page: the trade-off across variants (detections against
flaps, events as the marker's size) as inline SVG, the ranked variants, and each code over the grid.

No network, no clock, no script needed to read it (a small one sorts the tables); every text
is escaped, so labels and fault codes from recordings cannot inject markup.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from medkit_replay.outputs.atomic import write_text_atomic
from medkit_replay.outputs.html_page import cards, page_end, page_start, scrolling_table
from medkit_replay.outputs.html_tables import esc, short
from medkit_replay.result import release_line
from medkit_replay.tuning.ranking import RANKING, same_latency
from medkit_replay.version import __version__

if TYPE_CHECKING:
    from collections.abc import Sequence
    from pathlib import Path

    from medkit_replay.tuning.ranking import CodeTotal, VariantTotal
    from medkit_replay.tuning.sweep import Grid, Outcome

MAX_CODES = 200
"""Codes in the per-code view (most confirmations over the grid first); the tables have all."""
MAX_VARIANTS = 120
"""Variants in the per-code view and the plot (best ranked first); the tables have all."""
WIDTH, HEIGHT, PAD = 640, 360, 48

_EXTRA_STYLE = """
svg.trade-off { display: block; max-width: 100%; height: auto; border: 1px solid var(--line);
  border-radius: 8px; background: var(--panel); }
svg text { font: 11px system-ui, sans-serif; fill: var(--fg); }
svg .axis { stroke: #9aa3af; }
svg .dot { fill: var(--accent); fill-opacity: .55; stroke: #1f4aa8; }
svg .best { fill: #2b8a57; stroke: #17663d; }
td.heat { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
.note { max-width: 60em; }
"""


def _seconds(ns: int | None) -> str:
    return "" if ns is None else f"{ns / 1e9:,.2f}"


def _num(value: int | None, shown: str | None = None) -> str:
    if value is None:
        return '<td class="num" data-v=""></td>'
    return (
        f'<td class="num" data-v="{value}">{esc(shown if shown is not None else f"{value:,}")}</td>'
    )


def _scale(value: float, low: float, high: float, out_low: float, out_high: float) -> float:
    if high <= low:
        return (out_low + out_high) / 2
    return out_low + (value - low) * (out_high - out_low) / (high - low)


def y_axis(totals: Sequence[VariantTotal]) -> str:
    """What the plot's y axis shows: faults confirmed, or FaultEvents published when every
    variant confirmed as many (a single y value would hide how the variants differ)."""
    found = {t.faults_confirmed for t in totals[:MAX_VARIANTS]}
    return "FaultEvents published" if len(found) == 1 and len(totals) > 1 else "faults confirmed"


def _y(total: VariantTotal, axis: str) -> int:
    return total.events if axis == "FaultEvents published" else total.faults_confirmed


def trade_off_svg(totals: Sequence[VariantTotal]) -> str:
    """Detections (y; FaultEvents published when every variant detected as many, see
    :func:`y_axis`) against flaps (x), each variant a dot sized by the events it published."""
    shown = list(totals[:MAX_VARIANTS])
    if not shown:
        return "<p>No variant ran.</p>"
    axis = y_axis(shown)
    flaps = [t.flaps for t in shown]
    found = [_y(t, axis) for t in shown]
    events = [t.events for t in shown]
    most_events = max(*events, 1)
    parts = [
        f'<svg class="trade-off" xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" '
        f'height="{HEIGHT}" viewBox="0 0 {WIDTH} {HEIGHT}" role="img" '
        f'aria-label="{esc(axis)} against flaps">',
        f'<line class="axis" x1="{PAD}" y1="{HEIGHT - PAD}" x2="{WIDTH - PAD / 2}" '
        f'y2="{HEIGHT - PAD}"/>',
        f'<line class="axis" x1="{PAD}" y1="{PAD / 2}" x2="{PAD}" y2="{HEIGHT - PAD}"/>',
        f'<text x="{WIDTH / 2}" y="{HEIGHT - 12}" text-anchor="middle">&#8592; fewer flaps '
        "(confirm-heal cycles)</text>",
        f'<text x="14" y="{HEIGHT / 2}" text-anchor="middle" transform="rotate(-90 14 '
        f'{HEIGHT / 2})">{esc(axis)} &#8594;</text>',
    ]
    low_x, high_x, low_y, high_y = min(flaps), max(flaps), min(found), max(found)
    for value, label in ((low_x, "start"), (high_x, "end")):
        x = _scale(value, low_x, high_x, PAD + 20, WIDTH - PAD)
        parts.append(
            f'<text x="{x:.1f}" y="{HEIGHT - PAD + 14}" text-anchor="{label}">{value:,}</text>'
        )
    for value in (low_y, high_y):
        y = _scale(value, low_y, high_y, HEIGHT - PAD - 20, PAD)
        parts.append(f'<text x="{PAD - 4}" y="{y:.1f}" text-anchor="end">{value:,}</text>')
    labels: dict[tuple[int, int], list[str]] = {}
    for total in shown:
        labels.setdefault((total.flaps, _y(total, axis)), []).append(total.variant)
    for total in reversed(shown):  # the best drawn last, on top
        x = _scale(total.flaps, low_x, high_x, PAD + 20, WIDTH - PAD)
        y = _scale(_y(total, axis), low_y, high_y, HEIGHT - PAD - 20, PAD)
        radius = 4 + 14 * math.sqrt(total.events / most_events)
        css = "dot best" if total.rank == 1 else "dot"
        tip = (
            f"#{total.rank} {total.variant} {short(total.label)}: {total.faults_confirmed:,} "
            f"confirmed, {total.flaps:,} flaps, {total.events:,} events"
        )
        parts.append(
            f'<circle class="{css}" cx="{x:.1f}" cy="{y:.1f}" r="{radius:.1f}">'
            f"<title>{esc(tip)}</title></circle>"
        )
        same = labels[(total.flaps, _y(total, axis))]
        if same[0] == total.variant:  # one label per spot: the variants there, best first
            text = ", ".join(same[:4]) + (f" +{len(same) - 4}" if len(same) > 4 else "")
            # Right of the dot in the left half, left of it in the right half: inside the frame.
            left = x > WIDTH / 2
            at = x - radius - 3 if left else x + radius + 3
            anchor = "end" if left else "start"
            parts.append(
                f'<text x="{at:.1f}" y="{y + 4:.1f}" text-anchor="{anchor}">{esc(text)}</text>'
            )
    parts.append("</svg>")
    return "\n".join(parts)


def _variants_table(grid: Grid, totals: Sequence[VariantTotal]) -> str:
    keys = [v.key for v in grid.varies]
    latency = same_latency(totals) is None  # a column only when it differs between variants
    heads = ["rank", "variant", *keys, "ros2_medkit", "confirmed", "flaps", "events",
             "muted events", "near misses", "muted faults",
             *(["mean latency (s)"] if latency else []),
             "time confirmed (s)", "inputs", "failed", "over budget"]  # fmt: skip
    settings = {v.id: [s.text for s in v.settings] for v in grid.variants}
    rows = []
    for t in totals:
        cells = [_num(t.rank), f"<td>{esc(t.variant)}</td>"]
        cells += [f"<td>{esc(short(text))}</td>" for text in settings[t.variant]]
        cells.append(f"<td>{esc(t.upstream_release)}</td>")
        cells += [_num(t.faults_confirmed), _num(t.flaps), _num(t.events), _num(t.muted_events),
                  _num(t.near_misses), _num(t.muted_faults)]  # fmt: skip
        if latency:
            cells.append(_num(t.latency_mean_ns, _seconds(t.latency_mean_ns)))
        cells += [_num(t.confirmed_ns, _seconds(t.confirmed_ns)), _num(t.runs),
                  _num(t.failed_runs), _num(t.budget_failed)]  # fmt: skip
        rows.append("<tr>" + "".join(cells) + "</tr>")
    numeric = frozenset(heads) - {"variant", *keys, "ros2_medkit"}
    return scrolling_table("variants", heads, rows, numeric)


def _code_grid(totals: Sequence[VariantTotal], codes: Sequence[CodeTotal]) -> str:
    """Codes down, variants (best first) across: runs confirmed, mean latency and flaps."""
    order = [t.variant for t in totals[:MAX_VARIANTS]]
    cells: dict[tuple[str, str], CodeTotal] = {(c.fault_code, c.variant): c for c in codes}
    weight: dict[str, int] = {}
    for total in codes:
        weight[total.fault_code] = weight.get(total.fault_code, 0) + total.runs_confirmed
    ranked = sorted(weight, key=lambda c: (-weight[c], c.encode("utf-8")))[:MAX_CODES]
    most_flaps = max((total.flaps for total in codes), default=0) or 1
    rows = []
    for code in ranked:
        row = [f"<td>{esc(short(code))}</td>"]
        for variant in order:
            found = cells.get((code, variant))
            if found is None:
                row.append('<td class="heat" data-v=""></td>')
                continue
            total = found
            shade = 255 - round(90 * total.flaps / most_flaps)
            tip = (
                f"{short(code)} in {variant}: confirmed in {total.runs_confirmed:,} of "
                f"{total.runs_reported:,} input(s), mean latency "
                f"{_seconds(total.latency_mean_ns) or '-'} s, {total.flaps:,} flaps, "
                f"{total.events:,} events, {total.muted_events:,} muted"
            )
            latency = _seconds(total.latency_mean_ns) or "-"
            row.append(
                f'<td class="heat" data-v="{total.runs_confirmed}" title="{esc(tip)}" '
                f'style="background: rgb(255,{shade},{shade})">{total.runs_confirmed:,} / '
                f"{esc(latency)} / {total.flaps:,}</td>"
            )
        rows.append("<tr>" + "".join(row) + "</tr>")
    more = len(weight) - len(ranked)
    note = f"<p class=note>{more:,} more codes in codes.csv.</p>" if more > 0 else ""
    return scrolling_table("codes", ["fault code", *order], rows, frozenset(order)) + note


def render_page(grid: Grid, outcome: Outcome, inputs: int) -> str:
    """The sweep as one self-contained HTML page."""
    totals = outcome.variants
    facts = {
        "variants": len(totals),
        "inputs": inputs,
        "rows (variant x input)": len(totals) * inputs,
        "failed rows": len(outcome.failed),
    }
    varied = "".join(
        f"<li><code>{esc(v.key)}</code> = {esc(', '.join(short(t) for t in v.texts))}</li>"
        for v in grid.varies
    )
    axis = y_axis(totals)
    if axis == "faults confirmed":
        up = "up is more faults confirmed (summed over the inputs)"
    else:
        found = totals[0].faults_confirmed
        up = (
            f"every variant confirmed {found:,} faults (summed over the inputs), so up is more "
            "FaultEvents published"
        )
    latency = same_latency(totals)
    latency_note = f"<p class=note>The {esc(latency)}.</p>\n" if latency is not None else ""
    sub = (
        f"medkit-replay {esc(__version__)} · {esc(release_line(grid.release_names))} · click a "
        "column heading to sort"
    )
    return (
        page_start("medkit-replay sweep", sub, _EXTRA_STYLE)
        + cards(facts)
        + f"<h2>Grid</h2>\n<ul>{varied}</ul>\n"
        "<h2>Trade-off across variants</h2>\n"
        f"<p class=note>Each dot is a variant: {esc(up)}, left is fewer flaps (confirm-heal "
        "cycles), a smaller dot published fewer FaultEvents. The best ranked is green; hover a "
        "dot for its figures.</p>\n"
        f"{trade_off_svg(totals)}\n"
        "<h2>Variants, best first</h2>\n"
        f"<p class=note>Ranked by {esc(RANKING)}.</p>\n{latency_note}"
        f"{_variants_table(grid, totals)}\n"
        "<h2>Each code over the grid</h2>\n"
        "<p class=note>Per cell: inputs it was confirmed in / mean detection latency (s) / "
        "flaps; redder is more flaps. Variants best first; codes most often confirmed "
        "first.</p>\n"
        f"{_code_grid(totals, outcome.codes)}\n" + page_end()
    )


def write_page(path: Path, grid: Grid, outcome: Outcome, inputs: int) -> None:
    """Write the page atomically."""
    write_text_atomic(path, render_page(grid, outcome, inputs))
