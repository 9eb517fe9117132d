"""The fleet table and the cross-run statistics, as pandas DataFrames built from run summaries.

Pure: summaries in, tables out, in a fixed row and column order, so that the same runs always
give the same bytes. Times are seconds of bag time (floats), durations likewise.
"""

from __future__ import annotations

import statistics
from typing import TYPE_CHECKING

import pandas as pd

from medkit_replay.result import STATUSES

if TYPE_CHECKING:
    from collections.abc import Sequence

    from medkit_replay.fleet.run import RunSummary

NS_PER_S = 1e9

RUN_COLUMNS: dict[str, str] = {
    "path": "string",
    "kind": "string",
    "upstream_release": "string",
    "start_ns": "Int64",
    "span_s": "Float64",
    "messages": "Int64",
    "faults": "Int64",
    **{status.lower(): "Int64" for status in STATUSES},
    "top_codes": "object",
    "confirmed_codes": "object",
    "heals": "Int64",
    "warnings": "Int64",
    "budget": "string",
    "budget_failures": "object",
    "error": "string",
}
"""The fleet table's columns and their pandas types; ``object`` columns hold lists."""

CODE_COLUMNS: dict[str, str] = {
    "fault_code": "string",
    "runs_confirmed": "Int64",
    "share_of_runs": "Float64",
    "mean_first_confirmed_s": "Float64",
    "heals": "Int64",
    "mean_time_to_heal_s": "Float64",
    "median_time_to_heal_s": "Float64",
}
"""The per-code statistics' columns and their pandas types."""


def _seconds(ns: float | None) -> float | None:
    return None if ns is None else ns / NS_PER_S


def _run_record(run: RunSummary) -> dict[str, object]:
    statuses = dict(run.faults_by_status)
    replayed = run.ok
    return {
        "path": run.path,
        "kind": run.kind,
        "upstream_release": run.upstream_release,
        "start_ns": run.start_ns,
        "span_s": _seconds(run.span_ns),
        "messages": run.messages,
        "faults": sum(statuses.values()) if replayed else None,
        **{s.lower(): statuses.get(s, 0) if replayed else None for s in STATUSES},
        "top_codes": [{"fault_code": c, "failed_reports": n} for c, n in run.top_codes],
        "confirmed_codes": [code for code, _ in run.confirmed],
        "heals": len(run.heals) if replayed else None,
        "warnings": run.warnings if replayed else None,
        "budget": run.budget,
        "budget_failures": list(run.budget_failures),
        "error": run.error,
    }


def runs_table(runs: Sequence[RunSummary]) -> pd.DataFrame:
    """One row per run, in run order (see RUN_COLUMNS)."""
    records = [_run_record(run) for run in runs]
    frame = pd.DataFrame.from_records(records, columns=list(RUN_COLUMNS))
    return frame.astype(RUN_COLUMNS)


def codes_table(runs: Sequence[RunSummary]) -> pd.DataFrame:
    """Per fault code that was confirmed in at least one run: in how many runs it was, how
    soon into the run (mean of first confirmations), and how long it took to heal (every
    CONFIRMED→HEALED transition of every run). Most confirmed first, then by code."""
    replayed = [run for run in runs if run.ok]
    confirmed_in: dict[str, list[int]] = {}
    heal_ns: dict[str, list[int]] = {}
    for run in replayed:
        origin = run.start_ns or 0
        for code, t_ns in run.confirmed:
            confirmed_in.setdefault(code, []).append(t_ns - origin)
        for code, ns in run.heals:
            heal_ns.setdefault(code, []).append(ns)
    ranked = sorted(confirmed_in.items(), key=lambda item: (-len(item[1]), item[0]))
    records: list[dict[str, object]] = []
    for code, offsets in ranked:
        heals = heal_ns.get(code, [])
        records.append(
            {
                "fault_code": code,
                "runs_confirmed": len(offsets),
                "share_of_runs": len(offsets) / len(replayed),
                "mean_first_confirmed_s": _seconds(statistics.fmean(offsets)),
                "heals": len(heals),
                "mean_time_to_heal_s": _seconds(statistics.fmean(heals)) if heals else None,
                "median_time_to_heal_s": _seconds(statistics.median(heals)) if heals else None,
            }
        )
    frame = pd.DataFrame.from_records(records, columns=list(CODE_COLUMNS))
    return frame.astype(CODE_COLUMNS)


def overview(runs: Sequence[RunSummary]) -> dict[str, int]:
    """Fleet-wide counts: runs, replayed, failed, messages, runs with a confirmed fault, and
    runs per budget verdict when a budget was checked."""
    replayed = [run for run in runs if run.ok]
    counts = {
        "runs": len(runs),
        "replayed": len(replayed),
        "failed": len(runs) - len(replayed),
        "messages": sum(run.messages or 0 for run in replayed),
        "runs_with_confirmed": sum(1 for run in replayed if run.confirmed),
    }
    for verdict in sorted({run.budget for run in runs if run.budget is not None}):
        counts[f"budget_{verdict}"] = sum(1 for run in runs if run.budget == verdict)
    return counts
