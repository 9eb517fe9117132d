"""What a sweep measures of one variant on one input, taken from the manager's records as they
are made (no records are kept): per code and in total.

Pure: fed the engine's report, event and transition rows (``FaultManager.set_row_sinks``).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Callable

    from medkit_replay.engine.manager import FaultManager, Row


@dataclass(frozen=True, slots=True, kw_only=True)
class CodeRow:
    """One fault code of one variant on one input (a row of ``run_codes``).

    Attributes:
        first_failed_ns: bag time of its first accepted FAILED report.
        detection_latency_ns: from that report to its first CONFIRMED (None: never confirmed).
        confirmations: times it entered CONFIRMED.
        flaps: CONFIRMED → HEALED transitions (confirm→heal cycles).
        confirmed_ns: bag time spent CONFIRMED, up to the end of the recording.
        events: FaultEvents published for it (what the live manager would have sent).
        muted_events: FaultEvents correlation withheld for it (muted).
        near_misses: FAILED reports after which it stayed unconfirmed.
        muted: muted as a symptom at the end.
        status: final status (empty when never stored).
    """

    variant: str
    input: str
    fault_code: str
    first_failed_ns: int | None
    detection_latency_ns: int | None
    confirmations: int
    flaps: int
    confirmed_ns: int
    events: int
    muted_events: int
    near_misses: int
    muted: bool
    status: str


CODE_COLUMNS = tuple(f.name for f in fields(CodeRow))


class Tally:
    """Running counts for one manager, fed its rows; :meth:`codes` reads them out at the end."""

    def __init__(self) -> None:
        self.first_failed: dict[str, int] = {}
        self.first_confirmed: dict[str, int] = {}
        self.confirmed_since: dict[str, int] = {}
        self.confirmed_ns: dict[str, int] = {}
        self.confirmations: dict[str, int] = {}
        self.flaps: dict[str, int] = {}
        self.events: dict[str, int] = {}
        self.muted_events: dict[str, int] = {}

    def sinks(self) -> tuple[Callable[[Row], None], Callable[[Row], None], Callable[[Row], None]]:
        """The report, event and transition row sinks (hot: one call per report)."""
        first_failed, muted_events, events = self.first_failed, self.muted_events, self.events

        def report(row: Row) -> None:
            # (t_ns, origin, topic, code, event, severity, description, source, accepted,
            #  reason, status, counter, confirmation, healing, withheld)
            code = row[3]
            if code not in first_failed and row[8] and row[4] == "FAILED":
                first_failed[code] = row[0]  # type: ignore[index,assignment]
            if row[14] is not None:
                muted_events[code] = muted_events.get(code, 0) + 1  # type: ignore[index,call-overload]

        def event(row: Row) -> None:
            code = row[2]
            events[code] = events.get(code, 0) + 1  # type: ignore[index,call-overload]

        return report, event, self._transition

    def _transition(self, row: Row) -> None:
        t_ns, code, before, after = row[0], row[1], row[2], row[3]
        assert isinstance(t_ns, int) and isinstance(code, str)
        if after == "CONFIRMED" and before != "CONFIRMED":
            self.first_confirmed.setdefault(code, t_ns)
            self.confirmed_since[code] = t_ns
            self.confirmations[code] = self.confirmations.get(code, 0) + 1
        elif before == "CONFIRMED" and after != "CONFIRMED":
            since = self.confirmed_since.pop(code, t_ns)
            self.confirmed_ns[code] = self.confirmed_ns.get(code, 0) + t_ns - since
            if after == "HEALED":
                self.flaps[code] = self.flaps.get(code, 0) + 1

    def codes(
        self, manager: FaultManager, end_ns: int | None, variant: str, input_label: str
    ) -> list[CodeRow]:
        """One row per code reported, stored or counted, in byte order."""
        storage = manager.storage
        correlation = manager.correlation
        known = (
            set(self.first_failed)
            | set(storage.faults)
            | set(self.events)
            | set(self.first_confirmed)
            | set(storage.near_misses)
        )
        rows = []
        for code in sorted(known, key=lambda c: c.encode("utf-8")):
            confirmed_ns = self.confirmed_ns.get(code, 0)
            since = self.confirmed_since.get(code)
            if since is not None and end_ns is not None:
                confirmed_ns += end_ns - since
            first_failed = self.first_failed.get(code)
            first_confirmed = self.first_confirmed.get(code)
            latency = (
                first_confirmed - first_failed
                if first_confirmed is not None and first_failed is not None
                else None
            )
            fault = storage.faults.get(code)
            rows.append(
                CodeRow(
                    variant=variant,
                    input=input_label,
                    fault_code=code,
                    first_failed_ns=first_failed,
                    detection_latency_ns=latency,
                    confirmations=self.confirmations.get(code, 0),
                    flaps=self.flaps.get(code, 0),
                    confirmed_ns=confirmed_ns,
                    events=self.events.get(code, 0),
                    muted_events=self.muted_events.get(code, 0),
                    near_misses=len(storage.near_misses.get(code, ())),
                    muted=correlation is not None and correlation.muted_entry(code) is not None,
                    status=fault.status if fault is not None else "",
                )
            )
        return rows


@dataclass(frozen=True, slots=True, kw_only=True)
class RunRow:
    """One variant on one input (a row of ``runs``): its codes' figures summed up.

    Attributes:
        faults_confirmed: codes CONFIRMED at least once (detections).
        latency_mean_ns, latency_max_ns: detection latency over those codes (floor of the mean).
        muted_faults: faults muted as symptoms at the end.
        budget: ``pass`` or ``fail`` with ``--budget``, else empty; ``budget_failures`` the rules
            that did not hold, ``;``-separated.
        input_warnings: what reading the input warned about (damage, refused messages): the
            figures cover what could be read.
        upstream_release: the ros2_medkit release the variant models (empty when the input
            could not be replayed).
        error: why the input could not be replayed (the figures are then empty).
    """

    variant: str
    input: str
    upstream_release: str = ""
    messages: int | None = None
    reports: int | None = None
    faults: int | None = None
    faults_confirmed: int | None = None
    latency_mean_ns: int | None = None
    latency_max_ns: int | None = None
    flaps: int | None = None
    confirmed_ns: int | None = None
    events: int | None = None
    events_confirmed: int | None = None
    events_updated: int | None = None
    events_cleared: int | None = None
    muted_events: int | None = None
    near_misses: int | None = None
    muted_faults: int | None = None
    budget: str = ""
    budget_failures: str = ""
    input_warnings: int | None = None
    error: str = ""


RUN_COLUMNS = tuple(f.name for f in fields(RunRow))


def run_row(
    manager: FaultManager,
    codes: list[CodeRow],
    messages: int,
    variant: str,
    input_label: str,
    input_warnings: int = 0,
) -> RunRow:
    """The run's row from its code rows and the manager's running totals."""
    latencies = [c.detection_latency_ns for c in codes if c.detection_latency_ns is not None]
    counts = manager.output.event_counts
    correlation = manager.correlation
    return RunRow(
        variant=variant,
        input=input_label,
        upstream_release=manager.config.release.name,
        messages=messages,
        reports=manager.output.reports_accepted,
        faults=len(manager.storage.faults),
        faults_confirmed=sum(1 for c in codes if c.confirmations),
        latency_mean_ns=sum(latencies) // len(latencies) if latencies else None,
        latency_max_ns=max(latencies, default=None),
        flaps=sum(c.flaps for c in codes),
        confirmed_ns=sum(c.confirmed_ns for c in codes),
        events=sum(counts.values()),
        events_confirmed=counts.get("fault_confirmed", 0),
        events_updated=counts.get("fault_updated", 0),
        events_cleared=counts.get("fault_cleared", 0),
        muted_events=sum(c.muted_events for c in codes),
        near_misses=sum(c.near_misses for c in codes),
        muted_faults=len(correlation.muted_faults()) if correlation is not None else 0,
        input_warnings=input_warnings,
    )
