"""Timeline lanes for the HTML report: status bands, markers and counter traces per fault.

Reads only the Result, one pass over each record list; every list it keeps is bounded, and the
bounding is deterministic (fixed caps, time bins over the recording's span, first-come order).
Recorded text in tooltips and in the page's data is cut at TEXT_CAP characters and made visible.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from medkit_replay.model import CLEAR_ROWS, EVENT_ROWS, NS_PER_SEC, REPORT_ROWS, TRANSITION_ROWS
from medkit_replay.outputs.record_rows import Row, row_batches
from medkit_replay.result import STATUSES
from medkit_replay.text import clip, seconds, severity_name, xml_text

if TYPE_CHECKING:
    from collections.abc import Callable

    from medkit_replay.model import FaultSnapshot, NearMiss
    from medkit_replay.result import Result
    from medkit_replay.rows import RecordRows

ROW_CAP = 1000  # timeline rows; beyond it the most serious faults are kept
BAND_CAP = 200  # status periods per fault drawn exactly; beyond it, BAND_BINS time bins
BAND_BINS = 400
MARKER_CAP = 200  # markers of one kind per fault drawn exactly; beyond it, one per bin
MARKER_BINS = 200
TRACE_CAP = 1000  # counter-trace points per fault; beyond it, min, max and changes per bin
TRACE_BINS = 500
NEAR_CAP = 200  # near misses listed per fault
TEXT_CAP = 200  # characters of one recorded text in a tooltip or the page's data
LIST_CAP = 20  # items of one recorded list (sources, clusters, codes) shown

# Most serious first: binned bands show the worst status of their interval.
STATUS_RANK = {"CLEARED": 0, "HEALED": 1, "PREPASSED": 2, "PREFAILED": 3, "CONFIRMED": 4}
RANK_STATUS = {rank: status for status, rank in STATUS_RANK.items()}
STATUS_INDEX: dict[str, int] = {status: index for index, status in enumerate(STATUSES)}
MARKER_ORDER = {"fault_confirmed": 0, "fault_updated": 1, "fault_cleared": 2, "clear": 3}

# t_s, counter, confirmation threshold, healing threshold, PASSED (0/1), status index
TracePoint = tuple[float, int, int, int, int, int]
_RawPoint = tuple[int, int, int, int, int, int]  # the same with t_ns, while being collected


def shown(value: str | None, limit: int = TEXT_CAP) -> str | None:
    """Recorded text for the page: cut at ``limit`` characters, controls made visible."""
    return None if value is None else xml_text(clip(value, limit))


def shown_list(values: tuple[str, ...]) -> list[str | None]:
    """The first LIST_CAP items of a recorded list, each ``shown``, then ``+N more``."""
    items = [shown(value) for value in values[:LIST_CAP]]
    if len(values) > LIST_CAP:
        items.append(f"+{len(values) - LIST_CAP:,} more")
    return items


@dataclass(frozen=True, slots=True)
class Span:
    """The recording's bag-time span; the timeline's x axis runs over it (start inclusive)."""

    start_ns: int
    end_ns: int

    @classmethod
    def of(cls, result: Result) -> Span:
        """The recording's span (``Result.span``, as the terminal and ``explain`` count from);
        at least 1 ms, so positions are always defined."""
        start, end = result.span()
        if start is None or end is None:
            start = end = 0
        return cls(start, max(end, start + NS_PER_SEC // 1000))

    @property
    def duration_ns(self) -> int:
        """End minus start (positive)."""
        return self.end_ns - self.start_ns

    def seconds(self, t_ns: int) -> float:
        """Seconds since the start, to the microsecond."""
        return round((t_ns - self.start_ns) / NS_PER_SEC, 6)

    def label(self, t_ns: int) -> str:
        """Seconds since the start as text, to the millisecond."""
        return f"{seconds(t_ns - self.start_ns)} s"

    def percent(self, t_ns: int) -> float:
        """Position in the span in percent, clamped to [0, 100]."""
        frac = (t_ns - self.start_ns) / self.duration_ns
        return min(max(frac, 0.0), 1.0) * 100.0

    def bin(self, t_ns: int, bins: int) -> int:
        """The time bin of an instant, 0 .. bins-1 (integer arithmetic: exact)."""
        index = (t_ns - self.start_ns) * bins // self.duration_ns
        return min(max(index, 0), bins - 1)

    def bin_start(self, index: int, bins: int) -> int:
        """The first instant of a time bin."""
        return self.start_ns + self.duration_ns * index // bins


@dataclass(frozen=True, slots=True)
class Band:
    """One status period of one fault, [start_ns, end_ns)."""

    start_ns: int
    end_ns: int
    status: str
    tip: str


@dataclass(frozen=True, slots=True)
class Marker:
    """An event or a ClearFault request on a fault's row."""

    t_ns: int
    kind: str
    tip: str


@dataclass(slots=True)
class _Bands:
    span: Span
    exact: list[Band] = field(default_factory=list)
    bins: list[int] | None = None
    count: int = 0

    def add(self, band: Band) -> None:
        self.count += 1
        if self.bins is None:
            self.exact.append(band)
            if len(self.exact) <= BAND_CAP:
                return
            self.bins = [-1] * BAND_BINS
            for kept in self.exact:
                self._fill(kept)
            self.exact = []
            return
        self._fill(band)

    def _fill(self, band: Band) -> None:
        assert self.bins is not None
        rank = STATUS_RANK.get(band.status, 0)
        last = self.span.bin(max(band.end_ns - 1, band.start_ns), BAND_BINS)
        for index in range(self.span.bin(band.start_ns, BAND_BINS), last + 1):
            self.bins[index] = max(self.bins[index], rank)

    def result(self) -> list[Band]:
        if self.bins is None:
            return self.exact
        bands: list[Band] = []
        index = 0
        while index < BAND_BINS:
            rank = self.bins[index]
            end = index
            while end + 1 < BAND_BINS and self.bins[end + 1] == rank:
                end += 1
            if rank >= 0:
                start_ns = self.span.bin_start(index, BAND_BINS)
                end_ns = self.span.bin_start(end + 1, BAND_BINS)
                status = RANK_STATUS[rank]
                when = f"{self.span.label(start_ns)} \u2013 {self.span.label(end_ns)}"
                tip = (
                    f"{status} at worst, {when}\n"
                    f"downsampled: {self.count} status periods in this fault"
                )
                bands.append(Band(start_ns, end_ns, status, tip))
            index = end + 1
        return bands


# A marker before its tooltip is written: (t_ns, kind, the record's row); tips are made only for
# the markers drawn.
_PendingMarker = tuple[int, str, Row]


@dataclass(slots=True)
class _Markers:
    """Each kind of marker is drawn exactly up to MARKER_CAP of that kind; a denser kind (the
    ``fault_updated`` of every PASSED on a confirmed fault) is drawn once per time bin it
    appears in. So no kind of marker ever vanishes from a stretch of the timeline, and the rare
    ones (confirmed, cleared, ClearFault) are each drawn where they happened."""

    span: Span
    exact: list[_PendingMarker] = field(default_factory=list)  # in the order added
    binned: dict[tuple[int, int], tuple[_PendingMarker, int]] = field(default_factory=dict)
    per_kind: Counter[str] = field(default_factory=Counter)
    count: int = 0

    def add(self, t_ns: int, kind: str, row: Row) -> None:
        self.count += 1
        self.per_kind[kind] += 1
        if self.per_kind[kind] <= MARKER_CAP:
            self.exact.append((t_ns, kind, row))
        key = (self.span.bin(t_ns, MARKER_BINS), MARKER_ORDER.get(kind, 9))
        first, seen = self.binned.get(key, ((t_ns, kind, row), 0))
        self.binned[key] = (first, seen + 1)

    def result(self, tip: Callable[[_PendingMarker], str]) -> list[Marker]:
        dense = {kind for kind, count in self.per_kind.items() if count > MARKER_CAP}
        markers = [
            Marker(item[0], item[1], tip(item)) for item in self.exact if item[1] not in dense
        ]
        if not dense:
            return markers
        for (_, _), (first, seen) in sorted(self.binned.items()):
            if first[1] in dense:
                extra = f"\n(+{seen - 1} more of this kind nearby: downsampled)" if seen > 1 else ""
                markers.append(Marker(first[0], first[1], tip(first) + extra))
        return sorted(markers, key=lambda m: (m.t_ns, MARKER_ORDER.get(m.kind, 9)))


@dataclass(slots=True)
class _Trace:
    """The counter trace: every point up to TRACE_CAP; beyond, per time bin the lowest and the
    highest counter, and every point where the status changed (up to TRACE_CAP of them; beyond,
    the first point of each status a bin changes to), so no status change is drawn away."""

    span: Span
    exact: list[_RawPoint] = field(default_factory=list)
    binned: dict[int, tuple[tuple[int, _RawPoint], tuple[int, _RawPoint]]] = field(
        default_factory=dict
    )
    changes: list[tuple[int, _RawPoint]] = field(default_factory=list)
    binned_changes: dict[tuple[int, int], tuple[int, _RawPoint]] = field(default_factory=dict)
    last_status: int | None = None
    count: int = 0

    def add(self, point: _RawPoint, key: int) -> None:
        """One point, in time bin ``key`` of TRACE_BINS (``Span.bin``, worked out by the caller
        with the arithmetic inlined: this runs once per report)."""
        self.count += 1
        if self.count <= TRACE_CAP:
            self.exact.append(point)
        item = (self.count, point)
        low, high = self.binned.get(key, (item, item))
        if point[1] < low[1][1] or point[1] > high[1][1] or low is item:
            self.binned[key] = (
                item if point[1] < low[1][1] else low,
                item if point[1] > high[1][1] else high,
            )
        if point[5] != self.last_status:
            self.last_status = point[5]
            if len(self.changes) < TRACE_CAP:
                self.changes.append(item)
            self.binned_changes.setdefault((key, point[5]), item)

    def result(self) -> list[TracePoint]:
        if self.count <= TRACE_CAP:
            kept = self.exact
        else:
            numbered = {item for pair in self.binned.values() for item in pair}
            if len(self.changes) < TRACE_CAP:
                numbered.update(self.changes)
            else:
                numbered.update(self.binned_changes.values())
            kept = [point for _, point in sorted(numbered)]
        seconds = self.span.seconds
        return [(seconds(p[0]), p[1], p[2], p[3], p[4], p[5]) for p in kept]


@dataclass(slots=True)
class Lane:
    """One fault's row: final state, bands, markers, counter trace and near misses."""

    fault: FaultSnapshot
    bands: list[Band]
    band_periods: int
    markers: list[Marker]
    marker_count: int
    trace: list[TracePoint]
    trace_count: int
    near: list[NearMiss]
    near_count: int


def _kept_codes(faults: tuple[FaultSnapshot, ...]) -> set[str]:
    if len(faults) <= ROW_CAP:
        return {f.fault_code for f in faults}
    ranked = sorted(faults, key=lambda f: (-STATUS_RANK.get(f.status, 0), -f.severity))
    return {f.fault_code for f in ranked[:ROW_CAP]}


def _band_tip(span: Span, start: int, end: int, status: str, cause: str, source: str | None) -> str:
    origin = f" from {clip(source, TEXT_CAP)}" if source else ""
    return f"{status}  {span.label(start)} \u2013 {span.label(end)}\nentered by {cause}{origin}"


def build_lanes(result: Result, span: Span) -> list[Lane]:
    """The timeline rows, in fault-code order (at most ROW_CAP, the most serious kept).

    Reads the record lists as rows (a spool's as they are stored): a long recording's records
    are never rebuilt one by one just to be counted into bins.
    """
    kept = _kept_codes(result.faults)
    bands = {code: _Bands(span) for code in kept}
    markers = {code: _Markers(span) for code in kept}
    traces = {code: _Trace(span) for code in kept}
    open_bands: dict[str, tuple[int, str, str, str | None]] = {}
    t_at, code_at, to_at, cause_at, source_at = _columns(
        TRANSITION_ROWS, "t_ns", "fault_code", "to_status", "cause", "source_id"
    )
    for batch in row_batches(result.transitions, TRANSITION_ROWS):
        for row in batch:
            code = row[code_at]
            if code not in kept:
                continue
            t_ns = row[t_at]
            previous = open_bands.get(code)
            if previous is not None:
                start, status, cause, source = previous
                tip = _band_tip(span, start, t_ns, status, cause, source)
                bands[code].add(Band(start, t_ns, status, tip))
            open_bands[code] = (
                t_ns,
                row[to_at],
                row[cause_at],
                row[source_at],
            )
    for code, (start, status, cause, source) in sorted(open_bands.items()):
        end = max(span.end_ns, start)
        bands[code].add(
            Band(start, end, status, _band_tip(span, start, end, status, cause, source))
        )
    t_at, kind_at, code_at = _columns(EVENT_ROWS, "t_ns", "event_type", "fault_code")
    for batch in row_batches(result.events, EVENT_ROWS):
        for row in batch:
            code = row[code_at]
            if code in kept:
                markers[code].add(row[t_at], row[kind_at], row)
    t_at, code_at = _columns(CLEAR_ROWS, "t_ns", "fault_code")
    for batch in row_batches(result.clears, CLEAR_ROWS):
        for row in batch:
            code = row[code_at]
            if code in kept:
                markers[code].add(row[t_at], "clear", row)
    _traces(result, span, traces)
    near: dict[str, list[NearMiss]] = {}
    near_count: dict[str, int] = {}
    for miss in result.near_misses:
        if miss.fault_code in kept:
            near_count[miss.fault_code] = near_count.get(miss.fault_code, 0) + 1
            listed = near.setdefault(miss.fault_code, [])
            if len(listed) < NEAR_CAP:
                listed.append(miss)
    marker_tip = _marker_tip(span)
    return [
        Lane(
            fault=fault,
            bands=bands[fault.fault_code].result(),
            band_periods=bands[fault.fault_code].count,
            markers=markers[fault.fault_code].result(marker_tip),
            marker_count=markers[fault.fault_code].count,
            trace=traces[fault.fault_code].result(),
            trace_count=traces[fault.fault_code].count,
            near=near.get(fault.fault_code, []),
            near_count=near_count.get(fault.fault_code, 0),
        )
        for fault in result.faults
        if fault.fault_code in kept
    ]


def _columns(rows: RecordRows[Any], *names: str) -> tuple[int, ...]:
    return tuple(rows.names.index(name) for name in names)


def _traces(result: Result, span: Span, traces: dict[str, _Trace]) -> None:
    """Each accepted report's counter, thresholds and resulting status, into its fault's trace."""
    t_at, code_at, accepted_at, counter_at, conf_at, heal_at, event_at, status_at = _columns(
        REPORT_ROWS,
        "t_ns",
        "fault_code",
        "accepted",
        "debounce_counter",
        "confirmation_threshold",
        "healing_threshold",
        "event_type",
        "status",
    )
    status_index = STATUS_INDEX.get
    start, duration, last_bin = span.start_ns, span.duration_ns, TRACE_BINS - 1
    for batch in row_batches(result.reports, REPORT_ROWS):
        for row in batch:
            trace = traces.get(row[code_at])
            if trace is None or not row[accepted_at]:
                continue
            counter, conf, heal = row[counter_at], row[conf_at], row[heal_at]
            if counter is None or conf is None or heal is None:
                continue
            t_ns = row[t_at]
            key = (t_ns - start) * TRACE_BINS // duration  # Span.bin, inlined
            key = 0 if key < 0 else last_bin if key > last_bin else key
            passed = 1 if row[event_at] == "PASSED" else 0
            point = (t_ns, counter, conf, heal, passed, status_index(row[status_at], -1))
            trace.add(point, key)


def _marker_tip(span: Span) -> Callable[[_PendingMarker], str]:
    """The tooltip of a drawn marker, from its event's or ClearFault's row."""
    ev_status, ev_severity, ev_occurrences, ev_auto = _columns(
        EVENT_ROWS, "status", "severity", "occurrence_count", "auto_cleared_codes"
    )
    cl_success, cl_message = _columns(CLEAR_ROWS, "success", "message")

    def tip(marker: _PendingMarker) -> str:
        t_ns, kind, row = marker
        if kind == "clear":
            verdict = "succeeded" if row[cl_success] else "failed"
            message = clip(row[cl_message], TEXT_CAP)
            return f"ClearFault at {span.label(t_ns)}: {verdict}\n{message}".rstrip()
        auto = ", ".join(map(str, shown_list(row[ev_auto])))
        return (
            f"{kind} at {span.label(t_ns)}\nstatus {row[ev_status]}, "
            f"severity {severity_name(row[ev_severity])}, "
            f"occurrences {row[ev_occurrences]}" + (f"\nauto-cleared: {auto}" if auto else "")
        )

    return tip


def page_data(lanes: list[Lane], span: Span) -> dict[str, object]:
    """What the page's script reads: the span, and per row its final state, trace, near misses."""
    return {
        "duration_s": span.seconds(span.end_ns),
        "start_ns": str(span.start_ns),
        "statuses": list(STATUSES),
        "lanes": [
            {
                "code": lane.fault.fault_code,
                "status": lane.fault.status,
                "severity": severity_name(lane.fault.severity),
                "description": shown(lane.fault.description),
                "sources": shown_list(lane.fault.reporting_sources),
                "occurrences": lane.fault.occurrence_count,
                "first_s": span.seconds(lane.fault.first_occurred_ns),
                "last_s": span.seconds(lane.fault.last_occurred_ns),
                "last_passed_s": span.seconds(lane.fault.last_passed_ns)
                if lane.fault.last_passed_ns
                else None,
                "muted_by": shown(lane.fault.root_cause_code) if lane.fault.muted else None,
                "clusters": shown_list(lane.fault.cluster_ids),
                "trace": [list(p) for p in lane.trace],
                "trace_count": lane.trace_count,
                "near": [
                    [
                        span.seconds(n.t_ns),
                        n.debounce_counter,
                        n.confirmation_threshold,
                        severity_name(n.severity),
                        shown(n.source_id),
                        n.resulting_status,
                    ]
                    for n in lane.near
                ],
                "near_count": lane.near_count,
            }
            for lane in lanes
        ],
    }
