"""A sweep as one self-contained HTML page: the trade-off across variants (detections against
flaps, events as the marker's size) as inline SVG, the ranked variants, and each code over the grid.

No network, no clock, no script needed to read it (a small one sorts the tables); every text
is escaped, so labels and fault codes from recordings cannot inject markup.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from medkit_replay.fleet.report import PAGE_STYLE, SORT_SCRIPT
from medkit_replay.outputs.atomic import write_text_atomic
from medkit_replay.outputs.html_tables import esc, short
from medkit_replay.result import release_line
from medkit_replay.tuning.ranking import RANKING
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
svg { border: 1px solid #ccc; background: #fff; }
svg text { font: 11px system-ui, sans-serif; fill: #222; }
svg .axis { stroke: #888; } svg .dot { fill: #3465a4; fill-opacity: .55; stroke: #1d3b6a; }
svg .best { fill: #1b7f3b; }
td.heat { text-align: right; font-variant-numeric: tabular-nums; }
.note { color: #555; max-width: 60em; }
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


def trade_off_svg(totals: Sequence[VariantTotal]) -> str:
    """Detections (y) against flaps (x), each variant a dot sized by the events it published."""
    shown = list(totals[:MAX_VARIANTS])
    if not shown:
        return "<p>No variant ran.</p>"
    flaps = [t.flaps for t in shown]
    found = [t.faults_confirmed for t in shown]
    events = [t.events for t in shown]
    most_events = max(*events, 1)
    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" '
        f'viewBox="0 0 {WIDTH} {HEIGHT}" role="img" aria-label="detections against flaps">',
        f'<line class="axis" x1="{PAD}" y1="{HEIGHT - PAD}" x2="{WIDTH - PAD / 2}" '
        f'y2="{HEIGHT - PAD}"/>',
        f'<line class="axis" x1="{PAD}" y1="{PAD / 2}" x2="{PAD}" y2="{HEIGHT - PAD}"/>',
        f'<text x="{WIDTH / 2}" y="{HEIGHT - 12}" text-anchor="middle">&#8592; fewer flaps '
        "(confirm-heal cycles)</text>",
        f'<text x="14" y="{HEIGHT / 2}" text-anchor="middle" transform="rotate(-90 14 '
        f'{HEIGHT / 2})">faults confirmed &#8594;</text>',
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
        labels.setdefault((total.flaps, total.faults_confirmed), []).append(total.variant)
    for total in reversed(shown):  # the best drawn last, on top
        x = _scale(total.flaps, low_x, high_x, PAD + 20, WIDTH - PAD)
        y = _scale(total.faults_confirmed, low_y, high_y, HEIGHT - PAD - 20, PAD)
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
        same = labels[(total.flaps, total.faults_confirmed)]
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
    heads = ["rank", "variant", *keys, "ros2_medkit", "confirmed", "flaps", "events",
             "muted events", "near misses", "muted faults", "mean latency (s)",
             "time confirmed (s)", "inputs", "failed", "over budget"]  # fmt: skip
    settings = {v.id: [s.text for s in v.settings] for v in grid.variants}
    rows = []
    for t in totals:
        cells = [_num(t.rank), f"<td>{esc(t.variant)}</td>"]
        cells += [f"<td>{esc(short(text))}</td>" for text in settings[t.variant]]
        cells.append(f"<td>{esc(t.upstream_release)}</td>")
        cells += [_num(t.faults_confirmed), _num(t.flaps), _num(t.events), _num(t.muted_events),
                  _num(t.near_misses), _num(t.muted_faults),
                  _num(t.latency_mean_ns, _seconds(t.latency_mean_ns)),
                  _num(t.confirmed_ns, _seconds(t.confirmed_ns)), _num(t.runs),
                  _num(t.failed_runs), _num(t.budget_failed)]  # fmt: skip
        rows.append("<tr>" + "".join(cells) + "</tr>")
    head = "".join(f"<th>{esc(h)}</th>" for h in heads)
    return (
        f'<table id="variants" class="sortable"><thead><tr>{head}</tr></thead>'
        f"<tbody>{''.join(rows)}</tbody></table>"
    )


def _code_grid(totals: Sequence[VariantTotal], codes: Sequence[CodeTotal]) -> str:
    """Codes down, variants (best first) across: runs confirmed, mean latency and flaps."""
    order = [t.variant for t in totals[:MAX_VARIANTS]]
    cells: dict[tuple[str, str], CodeTotal] = {(c.fault_code, c.variant): c for c in codes}
    weight: dict[str, int] = {}
    for total in codes:
        weight[total.fault_code] = weight.get(total.fault_code, 0) + total.runs_confirmed
    ranked = sorted(weight, key=lambda c: (-weight[c], c.encode("utf-8")))[:MAX_CODES]
    most_flaps = max((total.flaps for total in codes), default=0) or 1
    head = "<th>fault code</th>" + "".join(f"<th>{esc(v)}</th>" for v in order)
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
    return (
        f'<table id="codes" class="sortable"><thead><tr>{head}</tr></thead>'
        f"<tbody>{''.join(rows)}</tbody></table>{note}"
    )


def render_page(grid: Grid, outcome: Outcome, inputs: int) -> str:
    """The sweep as one self-contained HTML page."""
    totals = outcome.variants
    facts = {
        "variants": len(totals),
        "inputs": inputs,
        "rows (variant x input)": len(totals) * inputs,
        "failed rows": len(outcome.failed),
    }
    dl = "".join(f"<dt>{esc(k)}</dt><dd>{v:,}</dd>" for k, v in facts.items())
    varied = "".join(
        f"<li><code>{esc(v.key)}</code> = {esc(', '.join(short(t) for t in v.texts))}</li>"
        for v in grid.varies
    )
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        "<title>medkit-replay sweep</title>\n"
        f"<style>{PAGE_STYLE}{_EXTRA_STYLE}</style>\n</head>\n<body>\n"
        "<h1>medkit-replay sweep</h1>\n"
        f"<p>medkit-replay {esc(__version__)}; click a column heading to sort.</p>\n"
        f"<p>{esc(release_line(grid.release_names))}</p>\n"
        f"<dl>{dl}</dl>\n<h2>Grid</h2>\n<ul>{varied}</ul>\n"
        "<h2>Trade-off across variants</h2>\n"
        "<p class=note>Each dot is a variant: up is more faults confirmed (summed over the "
        "inputs), left is fewer flaps (confirm-heal cycles), a smaller dot published fewer "
        "FaultEvents. The best ranked is green; hover a dot for its figures.</p>\n"
        f"{trade_off_svg(totals)}\n"
        "<h2>Variants, best first</h2>\n"
        f"<p class=note>Ranked by {esc(RANKING)}.</p>\n"
        f"{_variants_table(grid, totals)}\n"
        "<h2>Each code over the grid</h2>\n"
        "<p class=note>Per cell: inputs it was confirmed in / mean detection latency (s) / "
        "flaps; redder is more flaps. Variants best first; codes most often confirmed "
        "first.</p>\n"
        f"{_code_grid(totals, outcome.codes)}\n"
        f"<script>{SORT_SCRIPT}</script>\n</body>\n</html>\n"
    )


def write_page(path: Path, grid: Grid, outcome: Outcome, inputs: int) -> None:
    """Write the page atomically."""
    write_text_atomic(path, render_page(grid, outcome, inputs))
