"""A fleet's report files: CSV and JSON tables and a self-contained HTML page.

Every file is a function of the run summaries only (no clock, no host name, no absolute path
that was not given), so the same fleet always gives the same bytes. Text that comes from a
recording or a path is escaped for HTML. Each file is written to a temporary file and renamed
into place; a run the tables cannot hold becomes a failed row instead of costing the whole
report.
"""

from __future__ import annotations

import html
import io
import json
import math
from dataclasses import replace
from typing import TYPE_CHECKING

import pandas as pd

from medkit_replay.fleet.stats import codes_table, overview, runs_table
from medkit_replay.outputs.atomic import write_bytes_atomic
from medkit_replay.outputs.csv_safety import write_frame
from medkit_replay.outputs.html_page import cards, page_end, page_start, scrolling_table
from medkit_replay.text import clip, one_line, xml_text
from medkit_replay.version import __version__

if TYPE_CHECKING:
    from collections.abc import Sequence
    from pathlib import Path

    from medkit_replay.fleet.run import RunSummary

FILES = ("runs.csv", "runs.json", "codes.csv", "codes.json", "index.html")
"""What ``write_report`` writes into its folder."""
NUMERIC = frozenset(
    {"span (s)", "messages", "confirmed", "healed", "cleared", "prefailed", "prepassed",
     "runs confirmed", "share of runs", "mean first confirmed (s)", "heals",
     "mean time to heal (s)", "median time to heal (s)"}
)  # fmt: skip
"""Headings of columns of numbers (aligned right)."""
MAX_CELL_CHARS = 2000
"""Characters of a text cell in index.html; longer text is cut, saying how much."""


def _csv_frame(frame: pd.DataFrame) -> pd.DataFrame:
    """The table with its list columns joined into text (``A:3; B:1``) for CSV."""
    flat = frame.copy()
    if "top_codes" in flat:
        flat["top_codes"] = [
            "; ".join(f"{item['fault_code']}:{item['failed_reports']}" for item in items)
            for items in frame["top_codes"]
        ]
    for column in ("confirmed_codes", "budget_failures"):
        if column in flat:
            flat[column] = ["; ".join(items) for items in frame[column]]
    return flat


def to_csv(frame: pd.DataFrame) -> str:
    """A fleet table as CSV text (list columns joined, missing values empty, text cells a
    spreadsheet would run as formulas neutralised: see outputs/csv_safety.py)."""
    buffer = io.StringIO()
    write_frame(_csv_frame(frame), buffer)
    return buffer.getvalue()


def to_json(frame: pd.DataFrame) -> str:
    """A fleet table as a JSON array of records (lists stay lists, missing values null)."""
    records = json.loads(frame.to_json(orient="records", double_precision=10))
    return json.dumps(records, indent=2, ensure_ascii=False) + "\n"


def _texts(runs: Sequence[RunSummary]) -> dict[str, str]:
    runs_frame = runs_table(runs)
    codes_frame = codes_table(runs)
    return {
        "runs.csv": to_csv(runs_frame),
        "runs.json": to_json(runs_frame),
        "codes.csv": to_csv(codes_frame),
        "codes.json": to_json(codes_frame),
        "index.html": render_html(runs, runs_frame, codes_frame),
    }


def _text(value: str) -> str:
    """Text every writer can encode: a lone surrogate (a file name that is not UTF-8) becomes
    its escape, ``\\udcff``; any other text stays as it is."""
    return value.encode("utf-8", "backslashreplace").decode("utf-8")


def _encodable(run: RunSummary) -> RunSummary:
    """The run with every text it holds made encodable (itself when it already is)."""
    return replace(
        run,
        path=_text(run.path),
        top_codes=tuple((_text(code), n) for code, n in run.top_codes),
        confirmed=tuple((_text(code), t) for code, t in run.confirmed),
        heals=tuple((_text(code), ns) for code, ns in run.heals),
        budget_failures=tuple(_text(name) for name in run.budget_failures),
        error=None if run.error is None else _text(run.error),
    )


def _untabulated(run: RunSummary, error: Exception) -> RunSummary:
    from medkit_replay.fleet.run import RunSummary  # noqa: PLC0415  # no cycle at import

    problem = one_line(error)
    what = f"{type(error).__name__}: {problem}" if problem else type(error).__name__
    return RunSummary(path=run.path, kind=run.kind, error=f"{run.path}: cannot be reported: {what}")


def tabulated(runs: Sequence[RunSummary]) -> tuple[list[RunSummary], dict[str, str]]:
    """The report files' texts; a run they cannot hold (whatever the reason) is replaced by a
    failed row saying why, so one run never costs the report of the others."""
    kept = [_encodable(run) for run in runs]
    try:
        return kept, _texts(kept)
    except Exception:  # find the runs at fault, one at a time
        for index, run in enumerate(kept):
            try:
                _texts([run])
            except Exception as err:  # any of them: that run's failure
                kept[index] = _untabulated(run, err)
    return kept, _texts(kept)


def write_texts(texts: dict[str, str], out_dir: Path) -> list[Path]:
    """Write the report files (:func:`tabulated`'s texts) into ``out_dir``, each through a
    temporary file renamed into place.

    Returns:
        The files written, in FILES order.

    Raises:
        OSError: the folder cannot be created or a file cannot be written.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    for name in FILES:
        path = out_dir / name
        # A lone surrogate (a file name that is not UTF-8) is written as its escape.
        write_bytes_atomic(path, texts[name].encode("utf-8", "backslashreplace"))
        written.append(path)
    return written


def write_report(runs: Sequence[RunSummary], out_dir: Path) -> list[Path]:
    """Write the fleet table, the code statistics and the HTML page into ``out_dir`` (a run the
    tables cannot hold as a failed row, see :func:`tabulated`).

    Returns:
        The files written, in FILES order.

    Raises:
        OSError: the folder cannot be created or a file cannot be written.
    """
    return write_texts(tabulated(runs)[1], out_dir)


# --- HTML -------------------------------------------------------------------------------------


def is_missing(value: object) -> bool:
    """Whether a table cell holds no value (None, pandas' NA, NaN)."""
    if value is None or value is pd.NA:
        return True
    return isinstance(value, float) and math.isnan(value)


def _number_cell(value: object, digits: int | None = None) -> str:
    if is_missing(value):
        return '<td class="num" data-v=""></td>'
    if digits is not None and isinstance(value, float):
        shown = f"{value:,.{digits}f}"
    elif isinstance(value, int):
        shown = f"{value:,}"
    else:
        shown = str(value)
    return f'<td class="num" data-v="{html.escape(str(value))}">{html.escape(shown)}</td>'


def _text_cell(value: object, css: str = "") -> str:
    # runs.json keeps the whole text
    text = "" if is_missing(value) else clip(xml_text(str(value)), MAX_CELL_CHARS)
    attr = f' class="{html.escape(css)}"' if css else ""
    return f"<td{attr}>{html.escape(text)}</td>"


def _runs_rows(frame: pd.DataFrame) -> list[str]:
    rows: list[str] = []
    for record in frame.to_dict(orient="records"):
        error = record["error"]
        budget = record["budget"]
        top = "; ".join(f"{t['fault_code']}:{t['failed_reports']}" for t in record["top_codes"])
        cells = [
            _text_cell(record["path"]),
            _text_cell(record["kind"]),
            _text_cell(record["upstream_release"]),
            _number_cell(record["span_s"], 3),
            _number_cell(record["messages"]),
            _number_cell(record["confirmed"]),
            _number_cell(record["healed"]),
            _number_cell(record["cleared"]),
            _number_cell(record["prefailed"]),
            _number_cell(record["prepassed"]),
            _text_cell(top),
            _text_cell(budget, "" if is_missing(budget) else str(budget)),
            _text_cell("; ".join(record["budget_failures"])),
            _text_cell(error),
        ]
        css = ' class="failed"' if not is_missing(error) else ""
        rows.append(f"<tr{css}>" + "".join(cells) + "</tr>")
    return rows


def _codes_rows(frame: pd.DataFrame) -> list[str]:
    rows: list[str] = []
    for record in frame.to_dict(orient="records"):
        cells = [
            _text_cell(record["fault_code"]),
            _number_cell(record["runs_confirmed"]),
            _number_cell(record["share_of_runs"], 3),
            _number_cell(record["mean_first_confirmed_s"], 3),
            _number_cell(record["heals"]),
            _number_cell(record["mean_time_to_heal_s"], 3),
            _number_cell(record["median_time_to_heal_s"], 3),
        ]
        rows.append("<tr>" + "".join(cells) + "</tr>")
    return rows


def render_html(
    runs: Sequence[RunSummary], runs_frame: pd.DataFrame, codes_frame: pd.DataFrame
) -> str:
    """The fleet as one self-contained HTML page (inline style and script, nothing fetched)."""
    counts = overview(runs)
    runs_html = scrolling_table(
        "runs",
        [
            "path",
            "kind",
            "ros2_medkit",
            "span (s)",
            "messages",
            "confirmed",
            "healed",
            "cleared",
            "prefailed",
            "prepassed",
            "top codes",
            "budget",
            "rules failed",
            "error",
        ],
        _runs_rows(runs_frame),
        NUMERIC,
    )
    codes_html = scrolling_table(
        "codes",
        [
            "fault code",
            "runs confirmed",
            "share of runs",
            "mean first confirmed (s)",
            "heals",
            "mean time to heal (s)",
            "median time to heal (s)",
        ],
        _codes_rows(codes_frame),
        NUMERIC,
    )
    return (
        page_start(
            "medkit-replay fleet report",
            f"medkit-replay {html.escape(__version__)} · click a column heading to sort",
        )
        + cards({key.replace("_", " "): value for key, value in counts.items()})
        + "<h2>Codes confirmed across runs</h2>\n"
        + codes_html
        + "\n<h2>Runs</h2>\n"
        + runs_html
        + "\n"
        + page_end()
    )
