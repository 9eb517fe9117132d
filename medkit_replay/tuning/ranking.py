"""A sweep's figures summed over its inputs, per variant and per variant x code, and the ranking.

Pure: fed the rows as they arrive (memory grows with variants x codes, never with inputs).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Iterable, Mapping, Sequence

    from medkit_replay.tuning.grid import Variant
    from medkit_replay.tuning.metrics import CodeRow, RunRow

RANKING = (
    "fewest budget failures, then most faults confirmed, then fewest flaps, then fewest events "
    "published, then the shortest mean detection latency"
)
"""How variants are ranked (said under the terminal summary and on the page)."""


@dataclass(frozen=True, slots=True, kw_only=True)
class VariantTotal:
    """One variant over all inputs (a row of ``variants``).

    Attributes:
        rank: 1 for the best (see RANKING).
        upstream_release: the ros2_medkit release the variant models.
        runs, failed_runs: inputs replayed, and inputs that could not be.
        faults_confirmed: detections: codes confirmed at least once, summed over inputs.
        latency_mean_ns: mean detection latency over all detections (floor).
        budget_failed: inputs whose budget verdict was ``fail`` (0 without ``--budget``).
    """

    rank: int
    variant: str
    label: str
    upstream_release: str
    runs: int
    failed_runs: int
    faults_confirmed: int
    latency_mean_ns: int | None
    flaps: int
    confirmed_ns: int
    events: int
    muted_events: int
    near_misses: int
    muted_faults: int
    budget_failed: int


@dataclass(frozen=True, slots=True, kw_only=True)
class CodeTotal:
    """One fault code of one variant over all inputs (a row of ``codes``).

    Attributes:
        runs_reported: inputs where it was reported; ``runs_confirmed``: where it was CONFIRMED.
        latency_mean_ns: mean detection latency over the inputs it was confirmed in (floor).
    """

    variant: str
    fault_code: str
    runs_reported: int
    runs_confirmed: int
    latency_mean_ns: int | None
    flaps: int
    confirmed_ns: int
    events: int
    muted_events: int
    near_misses: int
    runs_muted: int


VARIANT_COLUMNS = tuple(f.name for f in fields(VariantTotal))
CODE_TOTAL_COLUMNS = tuple(f.name for f in fields(CodeTotal))

_SUMMED = ("faults_confirmed", "flaps", "confirmed_ns", "events", "muted_events", "near_misses",
           "muted_faults")  # fmt: skip
_CODE_SUMMED = ("flaps", "confirmed_ns", "events", "muted_events", "near_misses")


class Totals:
    """Running sums per variant and per variant x code."""

    def __init__(self, variants: Sequence[Variant], releases: Mapping[str, str]) -> None:
        self.variants = list(variants)
        self.releases = releases  # the release each variant models, by id
        self._runs: dict[str, dict[str, int]] = {
            v.id: dict.fromkeys((*_SUMMED, "runs", "failed", "budget", "lat_sum", "lat_n"), 0)
            for v in variants
        }
        self._codes: dict[tuple[str, str], dict[str, int]] = {}

    def add_run(self, row: RunRow) -> None:
        """Count one variant x input row."""
        sums = self._runs[row.variant]
        if row.error:
            sums["failed"] += 1
            return
        sums["runs"] += 1
        for name in _SUMMED:
            value = getattr(row, name)
            sums[name] += value or 0
        sums["budget"] += row.budget == "fail"

    def add_code(self, row: CodeRow) -> None:
        """Count one variant x input x code row."""
        key = (row.variant, row.fault_code)
        sums = self._codes.get(key)
        if sums is None:
            sums = self._codes[key] = dict.fromkeys(
                (*_CODE_SUMMED, "reported", "confirmed", "lat_sum", "muted"), 0
            )
        for name in _CODE_SUMMED:
            sums[name] += getattr(row, name)
        sums["reported"] += 1
        sums["confirmed"] += row.confirmations > 0
        sums["muted"] += row.muted
        if row.detection_latency_ns is not None:
            sums["lat_sum"] += row.detection_latency_ns
            run = self._runs[row.variant]
            run["lat_sum"] += row.detection_latency_ns
            run["lat_n"] += 1

    def variant_totals(self) -> list[VariantTotal]:
        """Every variant, best first."""
        unranked = []
        for variant in self.variants:
            sums = self._runs[variant.id]
            unranked.append(
                VariantTotal(
                    rank=0,
                    variant=variant.id,
                    label=variant.label,
                    upstream_release=self.releases[variant.id],
                    runs=sums["runs"],
                    failed_runs=sums["failed"],
                    latency_mean_ns=sums["lat_sum"] // sums["lat_n"] if sums["lat_n"] else None,
                    budget_failed=sums["budget"],
                    **{name: sums[name] for name in _SUMMED},
                )
            )
        ranked = sorted(unranked, key=_rank_key)
        return [_with_rank(total, rank) for rank, total in enumerate(ranked, 1)]

    def code_totals(self) -> Iterable[CodeTotal]:
        """Every variant x code, in grid order then code byte order."""
        order = {v.id: v.index for v in self.variants}
        for variant, code in sorted(self._codes, key=lambda k: (order[k[0]], k[1].encode())):
            sums = self._codes[(variant, code)]
            yield CodeTotal(
                variant=variant,
                fault_code=code,
                runs_reported=sums["reported"],
                runs_confirmed=sums["confirmed"],
                latency_mean_ns=sums["lat_sum"] // sums["confirmed"] if sums["confirmed"] else None,
                runs_muted=sums["muted"],
                **{name: sums[name] for name in _CODE_SUMMED},
            )


def _rank_key(total: VariantTotal) -> tuple[int, int, int, int, int, int]:
    latency = total.latency_mean_ns if total.latency_mean_ns is not None else 2**63
    index = int(total.variant[1:])
    return (total.budget_failed + total.failed_runs, -total.faults_confirmed, total.flaps,
            total.events, latency, index)  # fmt: skip


def _with_rank(total: VariantTotal, rank: int) -> VariantTotal:
    values = {f.name: getattr(total, f.name) for f in fields(VariantTotal)}
    values["rank"] = rank
    return VariantTotal(**values)


def same_latency(totals: Sequence[VariantTotal]) -> str | None:
    """Why the latency column is left out, when it would compare nothing: the same mean detection
    latency in every one of two or more variants (0 when each fault confirms on its first FAILED
    report: ``confirmation_threshold`` -1 or a CRITICAL report); None when it differs."""
    values = {total.latency_mean_ns for total in totals}
    if len(totals) < 2 or len(values) != 1:
        return None
    (value,) = values
    if value is None:
        return "no variant confirmed a fault, so there is no detection latency to compare"
    what = f"mean detection latency is {value / 1e9:,.2f} s in every variant"
    if value == 0:
        what += " (each fault confirmed on its first FAILED report)"
    return f"{what}: the same everywhere, so not a column"
