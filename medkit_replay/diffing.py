"""Compares two JSON reports (schema ``medkit-replay/report/v1``): what changed between runs.

Pure: reads two report dicts (as ``json.load`` or ``to_report`` gives them) and returns a
:class:`ReportDiff`; renders it as rich text or JSON. No file, no clock, no terminal.

What counts as a difference:

- a fault in one report and not in the other (``fault_added``, ``fault_removed``; its events and
  transitions are not listed again), or a fault whose ``status``, ``severity``,
  ``occurrence_count``, ``reporting_sources``, ``muted``, ``root_cause_code`` or ``cluster_ids``
  changed (``fault_changed``, one per field);
- per fault code, the transitions (keyed on ``from_status``, ``to_status``, ``cause``) and the
  FaultEvents (keyed on ``event_type``) of both reports are aligned in order as a text diff aligns
  lines; an aligned pair more than the tolerance apart in bag time is ``*_shifted``, an unaligned
  baseline item ``*_missing``, an unaligned current item ``*_extra``;
- an active cluster in one report and not in the other (``cluster_added``, ``cluster_removed``), or
  whose rule, representative or members changed (``cluster_changed``).

Descriptions, input paths, tool versions, warnings, requests and summaries are not compared.
"""

from __future__ import annotations

import io
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from difflib import SequenceMatcher
from typing import TYPE_CHECKING, Literal

from rich import box
from rich.console import Console, Group
from rich.padding import Padding
from rich.table import Table
from rich.text import Text

from medkit_replay.errors import InputError
from medkit_replay.outputs.json_report import SCHEMA

if TYPE_CHECKING:
    from rich.console import RenderableType

    _KeyFunction = Callable[[Mapping[str, object]], tuple[object, ...]]

DIFF_SCHEMA = "medkit-replay/diff/v1"
"""Schema of the JSON a diff is written as (:meth:`ReportDiff.to_json`)."""

Kind = Literal[
    "fault_added",
    "fault_removed",
    "fault_changed",
    "transition_shifted",
    "transition_missing",
    "transition_extra",
    "event_shifted",
    "event_missing",
    "event_extra",
    "cluster_added",
    "cluster_removed",
    "cluster_changed",
]
KINDS: tuple[Kind, ...] = (
    "fault_added",
    "fault_removed",
    "fault_changed",
    "transition_shifted",
    "transition_missing",
    "transition_extra",
    "event_shifted",
    "event_missing",
    "event_extra",
    "cluster_added",
    "cluster_removed",
    "cluster_changed",
)
FAULT_FIELDS = (
    "status",
    "severity",
    "occurrence_count",
    "reporting_sources",
    "muted",
    "root_cause_code",
    "cluster_ids",
)
"""The fault fields compared, in the order differences are listed."""
CLUSTER_FIELDS = (
    "rule_id",
    "representative_code",
    "representative_severity",
    "fault_codes",
    "count",
)
NS_PER_SEC = 1_000_000_000
MAX_ROWS = 500
"""Most differences drawn in the human output; the JSON has all of them."""
MAX_WHAT = 34

JsonObject = dict[str, object]
_INT64_MIN = -(1 << 63)
_INT64_MAX = (1 << 63) - 1


def tolerance_ns(seconds: float) -> int:
    """A ``--time-tolerance`` in seconds as integer nanoseconds (negative values refused)."""
    if not math.isfinite(seconds) or seconds < 0:
        raise InputError(f"time tolerance must be a number of seconds >= 0, not {seconds}")
    if not math.isfinite(seconds * NS_PER_SEC):
        raise InputError(f"time tolerance {seconds} s is too large to count in nanoseconds")
    return round(seconds * NS_PER_SEC)


@dataclass(frozen=True, slots=True)
class Difference:
    """One difference between the baseline and the current report.

    ``subject`` is a fault code, or a cluster id for the ``cluster_*`` kinds; ``detail`` holds
    the kind's own fields, exactly as the JSON output writes them.
    """

    kind: Kind
    subject: str
    detail: Mapping[str, object]

    @property
    def subject_key(self) -> str:
        """``cluster_id`` or ``fault_code``: the JSON name of ``subject``."""
        return "cluster_id" if self.kind.startswith("cluster_") else "fault_code"

    def to_json(self) -> JsonObject:
        """The difference as the JSON output lists it."""
        return {"kind": self.kind, self.subject_key: self.subject, **self.detail}


@dataclass(frozen=True, slots=True)
class ReportDiff:
    """Every difference between two reports, faults first (by code), then clusters."""

    baseline_name: str
    current_name: str
    time_tolerance_ns: int
    differences: tuple[Difference, ...]
    origin_ns: int | None = None
    """Start of the baseline recording: the human output shows times as offsets from it."""

    @property
    def equal(self) -> bool:
        """No difference at all."""
        return not self.differences

    def counts(self) -> dict[str, int]:
        """Differences per kind, every kind listed."""
        counts: dict[str, int] = dict.fromkeys(KINDS, 0)
        for difference in self.differences:
            counts[difference.kind] += 1
        return counts

    def to_json(self) -> JsonObject:
        """The diff as a JSON-ready dict (schema :data:`DIFF_SCHEMA`)."""
        return {
            "schema": DIFF_SCHEMA,
            "baseline": self.baseline_name,
            "current": self.current_name,
            "time_tolerance_ns": self.time_tolerance_ns,
            "equal": self.equal,
            "counts": self.counts(),
            "differences": [d.to_json() for d in self.differences],
        }


# --- reading the reports ---------------------------------------------------------------------


class _Report:
    """The parts of one report a diff reads, checked as they are read."""

    def __init__(self, report: object, name: str) -> None:
        self.name = name
        if not isinstance(report, Mapping):
            raise InputError("not a medkit-replay report (not a JSON object)", path=name)
        schema = report.get("schema")
        if schema != SCHEMA:
            raise InputError(
                f"not a medkit-replay report: schema is {_short(schema)}, expected {SCHEMA!r}",
                path=name,
            )
        self.faults = self._objects(report, "faults", ("fault_code",), ("fault_code",))
        self.events = self._objects(
            report, "events", ("t_ns", "event_type", "fault"), ("event_type",)
        )
        self.transitions = self._objects(
            report,
            "transitions",
            ("t_ns", "fault_code", "to_status"),
            ("fault_code", "to_status"),
            ("from_status", "cause"),
        )
        self.clusters = self._objects(report, "clusters", ("cluster_id",), ("cluster_id",))
        for event in self.events:
            fault = event["fault"]
            if not isinstance(fault, Mapping) or not isinstance(fault.get("fault_code"), str):
                raise InputError("malformed report: an event without fault.fault_code", path=name)
        self.fault_by_code = {str(f["fault_code"]): f for f in self.faults}
        self.events_by_code: dict[str, list[Mapping[str, object]]] = {}
        for event in self.events:
            self.events_by_code.setdefault(_event_code(event), []).append(event)
        self.transitions_by_code: dict[str, list[Mapping[str, object]]] = {}
        for transition in self.transitions:
            code = str(transition["fault_code"])
            self.transitions_by_code.setdefault(code, []).append(transition)
        self.cluster_by_id = {str(c["cluster_id"]): c for c in self.clusters}
        self.origin_ns = _origin(report)

    def _objects(
        self,
        report: Mapping[str, object],
        key: str,
        required: tuple[str, ...],
        texts: tuple[str, ...] = (),
        optional_texts: tuple[str, ...] = (),
    ) -> list[Mapping[str, object]]:
        items = report.get(key)
        if not isinstance(items, list):
            raise InputError(f"malformed report: {key!r} is not a list", path=self.name)
        checked: list[Mapping[str, object]] = []
        for number, item in enumerate(items):
            if not isinstance(item, Mapping) or any(k not in item for k in required):
                raise InputError(
                    f"malformed report: {key}[{number}] lacks one of {', '.join(required)}",
                    path=self.name,
                )
            if "t_ns" in item and not _is_int(item["t_ns"]):
                raise InputError(
                    f"malformed report: {key}[{number}].t_ns is not an integer", path=self.name
                )
            if "t_ns" in item and not _is_time(item["t_ns"]):
                raise InputError(
                    f"malformed report: {key}[{number}].t_ns is outside int64 nanoseconds",
                    path=self.name,
                )
            for name in texts + optional_texts:
                value = item.get(name)
                if not isinstance(value, str) and (value is not None or name in texts):
                    raise InputError(
                        f"malformed report: {key}[{number}].{name} is not a string",
                        path=self.name,
                    )
            checked.append(item)
        return checked

    def events_of(self, code: str) -> list[Mapping[str, object]]:
        return self.events_by_code.get(code, [])

    def transitions_of(self, code: str) -> list[Mapping[str, object]]:
        return self.transitions_by_code.get(code, [])


def _is_int(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _short(value: object) -> str:
    """A value for a one-line message: never the whole of a long one."""
    text = (
        ascii(value) if isinstance(value, str | int | float | bool | None) else type(value).__name__
    )
    return text if len(text) <= 80 else f"{text[:77]}..."


def _is_time(value: object) -> bool:
    """An int64 bag time, as every time in a report is."""
    return _is_int(value) and _INT64_MIN <= value <= _INT64_MAX  # type: ignore[operator]


def _event_code(event: Mapping[str, object]) -> str:
    fault = event["fault"]
    assert isinstance(fault, Mapping)
    return str(fault["fault_code"])


def _origin(report: Mapping[str, object]) -> int | None:
    """The recording's first log time: its inputs' starts, else the first message read."""
    starts: list[int] = []
    inputs = report.get("inputs")
    if isinstance(inputs, list):
        starts += [
            i["start_ns"] for i in inputs if isinstance(i, Mapping) and _is_time(i.get("start_ns"))
        ]
    summary = report.get("summary")
    start = summary.get("start_ns") if isinstance(summary, Mapping) else None
    if isinstance(start, int) and _is_time(start):
        starts.append(start)
    return min(starts, default=None)


# --- comparing -------------------------------------------------------------------------------


def _byte_order(codes: set[str]) -> list[str]:
    return sorted(codes, key=lambda c: c.encode("utf-8", "surrogatepass"))


def diff_reports(
    baseline: object,
    current: object,
    *,
    time_tolerance_ns: int = 0,
    baseline_name: str = "baseline",
    current_name: str = "current",
) -> ReportDiff:
    """Compare two reports (dicts of schema ``medkit-replay/report/v1``).

    Args:
        baseline: the reference report.
        current: the report compared with it.
        time_tolerance_ns: bag-time shifts up to this much are not differences.
        baseline_name: how the baseline is named in errors and output (its path, say).
        current_name: likewise for the current report.

    Raises:
        InputError: a report is not a medkit-replay report or lacks what a diff reads.
    """
    if time_tolerance_ns < 0:
        raise InputError(f"time tolerance must be >= 0 ns, not {time_tolerance_ns}")
    old = _Report(baseline, baseline_name)
    new = _Report(current, current_name)
    differences: list[Difference] = []
    codes = set(old.fault_by_code) | set(new.fault_by_code)
    codes |= set(old.transitions_by_code) | set(new.transitions_by_code)
    codes |= set(old.events_by_code) | set(new.events_by_code)
    for code in _byte_order(codes):
        differences += _fault_differences(code, old, new, time_tolerance_ns)
    for cluster_id in _byte_order(set(old.cluster_by_id) | set(new.cluster_by_id)):
        differences += _cluster_differences(cluster_id, old, new)
    return ReportDiff(
        baseline_name=baseline_name,
        current_name=current_name,
        time_tolerance_ns=time_tolerance_ns,
        differences=tuple(differences),
        origin_ns=old.origin_ns if old.origin_ns is not None else new.origin_ns,
    )


def _fault_differences(code: str, old: _Report, new: _Report, tolerance: int) -> list[Difference]:
    before, after = old.fault_by_code.get(code), new.fault_by_code.get(code)
    if before is not None and after is None:
        return [Difference("fault_removed", code, {"baseline": dict(before)})]
    if before is None and after is not None:
        return [Difference("fault_added", code, {"current": dict(after)})]
    found: list[Difference] = []
    if before is not None and after is not None:
        found += [
            Difference(
                "fault_changed",
                code,
                {"field": name, "baseline": before.get(name), "current": after.get(name)},
            )
            for name in FAULT_FIELDS
            if before.get(name) != after.get(name)
        ]
    found += _align(
        code,
        "transition",
        old.transitions_of(code),
        new.transitions_of(code),
        _transition_key,
        tolerance,
    )
    found += _align(code, "event", old.events_of(code), new.events_of(code), _event_key, tolerance)
    return found


def _transition_key(transition: Mapping[str, object]) -> tuple[object, ...]:
    return (transition.get("from_status"), transition["to_status"], transition.get("cause"))


def _event_key(event: Mapping[str, object]) -> tuple[object, ...]:
    return (event["event_type"],)


def _key_detail(what: Literal["transition", "event"], key: tuple[object, ...]) -> JsonObject:
    if what == "event":
        return {"event_type": key[0]}
    return {"from_status": key[0], "to_status": key[1], "cause": key[2]}


def _align(
    code: str,
    what: Literal["transition", "event"],
    before: Sequence[Mapping[str, object]],
    after: Sequence[Mapping[str, object]],
    key: _KeyFunction,
    tolerance: int,
) -> list[Difference]:
    """Align two sequences of one fault's items on their keys, as a line diff does.

    First the items equal in key and bag time are aligned (the same item, surely); then, in
    each gap between those, the remaining items are aligned on their keys alone.
    """
    old_keys = [key(item) for item in before]
    new_keys = [key(item) for item in after]
    old_times = [_time(item) for item in before]
    new_times = [_time(item) for item in after]
    found: list[Difference] = []

    def add(kind: Kind, k: tuple[object, ...], old_t: int | None, new_t: int | None) -> None:
        detail = _key_detail(what, k)
        shift = new_t - old_t if old_t is not None and new_t is not None else None
        detail |= {"baseline_t_ns": old_t, "current_t_ns": new_t, "shift_ns": shift}
        found.append(Difference(kind, code, detail))

    exact = SequenceMatcher(
        None,
        list(zip(old_keys, old_times, strict=True)),
        list(zip(new_keys, new_times, strict=True)),
        autojunk=False,
    )
    for tag, a1, a2, b1, b2 in exact.get_opcodes():
        if tag == "equal":
            continue
        old_gap = [(old_keys[i], old_times[i]) for i in range(a1, a2)]
        new_gap = [(new_keys[j], new_times[j]) for j in range(b1, b2)]
        for i, j in _gap_pairs(old_gap, new_gap):
            if i is None:
                if j is not None:
                    add(_kind(what, "extra"), new_gap[j][0], None, new_gap[j][1])
            elif j is None:
                add(_kind(what, "missing"), old_gap[i][0], old_gap[i][1], None)
            elif abs(new_gap[j][1] - old_gap[i][1]) > tolerance:
                add(_kind(what, "shifted"), old_gap[i][0], old_gap[i][1], new_gap[j][1])
    # Listed in bag-time order of the baseline (missing, shifted) or current (extra) item.
    found.sort(key=_difference_time)
    return found


_Item = tuple[tuple[object, ...], int]
"""An item's key and bag time."""
_Pairs = list[tuple[int | None, int | None]]
"""An alignment: (i, j) aligned, (i, None) only in the baseline, (None, j) only in the current."""
MAX_CELLS = 40_000
"""Largest (baseline x current) table an exact alignment fills; larger gaps are aligned by runs
of equal keys first."""
MAX_RUN_CELLS = 200_000
"""Largest table aligning two runs of one key by least total shift; beyond, pairs in order."""


def _gap_pairs(before: Sequence[_Item], after: Sequence[_Item]) -> _Pairs:
    """Align the items of a gap: as many pairs of equal keys as possible and, among those
    alignments, the one with the least total time shift.

    Large gaps (two unrelated recordings, say) are aligned by runs of equal keys (``fault_updated``
    x 500), then item by item inside aligned runs; the largest, key occurrence by occurrence.
    """
    n, m = len(before), len(after)
    if n * m <= MAX_CELLS:
        return _exact_pairs(before, after)
    old_runs, new_runs = _runs(before), _runs(after)
    if len(old_runs) * len(new_runs) > MAX_CELLS:
        return _occurrence_pairs(before, after)
    run_pairs = _exact_pairs(
        [(key, length) for key, _, length in old_runs],
        [(key, length) for key, _, length in new_runs],
        weight=min,
        cost=lambda a, b: abs(a - b),
    )
    pairs: _Pairs = []
    for i, j in run_pairs:
        if i is None:
            if j is not None:
                _, first, length = new_runs[j]
                pairs += [(None, k) for k in range(first, first + length)]
        elif j is None:
            _, first, length = old_runs[i]
            pairs += [(k, None) for k in range(first, first + length)]
        else:
            _, old_first, old_length = old_runs[i]
            _, new_first, new_length = new_runs[j]
            old_times = [t for _, t in before[old_first : old_first + old_length]]
            new_times = [t for _, t in after[new_first : new_first + new_length]]
            pairs += [
                (None if a is None else old_first + a, None if b is None else new_first + b)
                for a, b in _run_pairs(old_times, new_times)
            ]
    return pairs


def _exact_pairs(
    before: Sequence[_Item],
    after: Sequence[_Item],
    *,
    weight: Callable[[int, int], int] = lambda a, b: 1,
    cost: Callable[[int, int], int] = lambda a, b: abs(b - a),
) -> _Pairs:
    """The alignment of greatest total ``weight`` (1 per pair of equal keys), and among those
    the least total ``cost`` (the time shift); each item's int is passed to both."""
    n, m = len(before), len(after)
    # best[i][j]: (weight, -cost) of the best alignment of before[i:] and after[j:]
    best = [[(0, 0)] * (m + 1) for _ in range(n + 1)]

    def paired(i: int, j: int) -> tuple[int, int]:
        gained, spent = best[i + 1][j + 1]
        a, b = before[i][1], after[j][1]
        return gained + weight(a, b), spent - cost(a, b)

    for i in range(n - 1, -1, -1):
        row, below = best[i], best[i + 1]
        for j in range(m - 1, -1, -1):
            choice = max(below[j], row[j + 1])
            if before[i][0] == after[j][0]:
                choice = max(choice, paired(i, j))
            row[j] = choice
    pairs: _Pairs = []
    i = j = 0
    while i < n and j < m:
        if before[i][0] == after[j][0] and best[i][j] == paired(i, j):
            pairs.append((i, j))
            i, j = i + 1, j + 1
        elif best[i][j] == best[i + 1][j]:
            pairs.append((i, None))
            i += 1
        else:
            pairs.append((None, j))
            j += 1
    pairs += [(k, None) for k in range(i, n)]
    pairs += [(None, k) for k in range(j, m)]
    return pairs


def _runs(items: Sequence[_Item]) -> list[tuple[tuple[object, ...], int, int]]:
    """Runs of equal keys: (key, first index, length)."""
    runs: list[tuple[tuple[object, ...], int, int]] = []
    for index, (key, _) in enumerate(items):
        if runs and runs[-1][0] == key:
            runs[-1] = (key, runs[-1][1], runs[-1][2] + 1)
        else:
            runs.append((key, index, 1))
    return runs


def _run_pairs(before: Sequence[int], after: Sequence[int]) -> _Pairs:
    """Align two runs of one key (their times): every item of the shorter run paired, in
    order, with the least total shift; the longer run's others unpaired."""
    if len(before) > len(after):
        return [(j, i) for i, j in _run_pairs(after, before)]
    short, extra = len(before), len(after) - len(before)
    if extra == 0 or short * (extra + 1) > MAX_RUN_CELLS:
        return [*zip(range(short), range(short), strict=True)] + [
            (None, k) for k in range(short, len(after))
        ]
    # cost[i][k]: least shift pairing before[:i] within after[:i + k] (k of those unpaired)
    inf = float("inf")
    cost = [[inf] * (extra + 1) for _ in range(short + 1)]
    cost[0] = [0.0] * (extra + 1)
    for i in range(1, short + 1):
        for k in range(extra + 1):
            take = cost[i - 1][k] + abs(after[i - 1 + k] - before[i - 1])
            skip = cost[i][k - 1] if k else inf
            cost[i][k] = min(take, skip)
    pairs: _Pairs = []
    i, k = short, extra
    while i > 0:
        if k and cost[i][k] == cost[i][k - 1]:
            pairs.append((None, i + k - 1))
            k -= 1
        else:
            pairs.append((i - 1, i - 1 + k))
            i -= 1
    pairs += [(None, index) for index in range(k - 1, -1, -1)]
    pairs.reverse()
    return pairs


def _occurrence_pairs(before: Sequence[_Item], after: Sequence[_Item]) -> _Pairs:
    """The n-th item of each key in the baseline with the n-th of that key in the current."""
    positions: dict[tuple[object, ...], list[int]] = {}
    for j, (key, _) in enumerate(after):
        positions.setdefault(key, []).append(j)
    seen: dict[tuple[object, ...], int] = {}
    pairs: _Pairs = []
    for i, (key, _) in enumerate(before):
        count = seen.get(key, 0)
        seen[key] = count + 1
        candidates = positions.get(key, [])
        pairs.append((i, candidates[count] if count < len(candidates) else None))
    for key, candidates in positions.items():
        pairs += [(None, j) for j in candidates[seen.get(key, 0) :]]
    return pairs


def _time(item: Mapping[str, object]) -> int:
    t_ns = item["t_ns"]
    assert isinstance(t_ns, int)  # checked when the report was read
    return t_ns


def _difference_time(difference: Difference) -> int:
    old_t, new_t = difference.detail.get("baseline_t_ns"), difference.detail.get("current_t_ns")
    t = old_t if isinstance(old_t, int) else new_t
    return t if isinstance(t, int) else 0


def _kind(what: Literal["transition", "event"], how: str) -> Kind:
    kind = f"{what}_{how}"
    assert kind in KINDS
    return kind


def _cluster_differences(cluster_id: str, old: _Report, new: _Report) -> list[Difference]:
    before, after = old.cluster_by_id.get(cluster_id), new.cluster_by_id.get(cluster_id)
    if after is None:
        return [Difference("cluster_removed", cluster_id, {"baseline": dict(before or {})})]
    if before is None:
        return [Difference("cluster_added", cluster_id, {"current": dict(after)})]
    return [
        Difference(
            "cluster_changed",
            cluster_id,
            {"field": name, "baseline": before.get(name), "current": after.get(name)},
        )
        for name in CLUSTER_FIELDS
        if before.get(name) != after.get(name)
    ]


# --- human output ----------------------------------------------------------------------------

_KIND_TEXT: dict[str, str] = {
    "fault_added": "fault added",
    "fault_removed": "fault removed",
    "fault_changed": "fault changed",
    "transition_shifted": "transition shifted",
    "transition_missing": "transition missing",
    "transition_extra": "transition extra",
    "event_shifted": "event shifted",
    "event_missing": "event missing",
    "event_extra": "event extra",
    "cluster_added": "cluster added",
    "cluster_removed": "cluster removed",
    "cluster_changed": "cluster changed",
}
_MARKS = {
    "added": ("+", "green"),
    "extra": ("+", "green"),
    "removed": ("-", "red"),
    "missing": ("-", "red"),
    "changed": ("~", "yellow"),
    "shifted": ("~", "yellow"),
}
"""Per kind's last word: the mark at the start of its row, and the mark's colour."""
LEGEND = "- only in the baseline, + only in the current, ~ changed or shifted"


def _show(value: object) -> str:
    """Recorded text made safe for a terminal: control and bidirectional characters escaped."""
    out: list[str] = []
    for char in str(value):
        point = ord(char)
        if char in "\n\r\t":
            out.append(" ")
        elif point < 0x20 or 0x7F <= point <= 0x9F:
            out.append(f"\\x{point:02x}")
        elif point in (0x200E, 0x200F) or 0x202A <= point <= 0x202E or 0x2066 <= point <= 0x2069:
            out.append(f"\\u{point:04x}")
        else:
            out.append(char)
    return "".join(out)


def _value(value: object) -> str:
    if value is None:
        return "null"
    if isinstance(value, list):
        return "[" + ", ".join(_show(v) for v in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    return _show(value)


def _seconds(ns: int) -> str:
    return f"{ns / NS_PER_SEC:+.3f} s"


class _Clock:
    def __init__(self, origin_ns: int | None) -> None:
        self.origin_ns = origin_ns or 0

    def at(self, t_ns: object) -> str:
        if not isinstance(t_ns, int):
            return "-"
        return f"{(t_ns - self.origin_ns) / NS_PER_SEC:.3f} s"


def _what(difference: Difference) -> str:
    """What differs: a fault field, a status change, an event, the fault or cluster itself."""
    detail = difference.detail
    if difference.kind.startswith("event_"):
        return f"event {_show(detail.get('event_type'))}"
    if difference.kind.startswith("transition_"):
        origin = detail.get("from_status")
        text = f"{_show(origin) if origin is not None else '(new)'} -> {_show(detail['to_status'])}"
        cause = detail.get("cause")
        return text if cause == "report" else f"{text} ({_show(cause)})"
    if "field" in detail:
        return _show(detail["field"])
    return "cluster" if difference.subject_key == "cluster_id" else "fault"


def _presence(difference: Difference) -> str:
    """A fault by its status, a cluster by its members."""
    item = difference.detail.get("current") or difference.detail.get("baseline")
    if not isinstance(item, Mapping):
        return "present"
    if difference.subject_key == "cluster_id":
        return f"present: {_value(item.get('fault_codes'))}"
    return _value(item.get("status"))


def _cells(difference: Difference, clock: _Clock) -> tuple[str, str]:
    detail = difference.detail
    if "baseline_t_ns" in detail:
        old_t, new_t = detail["baseline_t_ns"], detail["current_t_ns"]
        current = clock.at(new_t)
        shift = detail.get("shift_ns")
        if isinstance(shift, int):
            current += f" ({_seconds(shift)})"
        return clock.at(old_t), current
    if "field" in detail:
        return _value(detail.get("baseline")), _value(detail.get("current"))
    if difference.kind.endswith("_added"):
        return "absent", _presence(difference)
    return _presence(difference), "absent"


def _headline(diff: ReportDiff) -> Text:
    tolerance = f"time tolerance {diff.time_tolerance_ns / NS_PER_SEC:.3f} s"
    if diff.equal:
        return Text.assemble(("reports are equal", "bold green"), f" ({tolerance})")
    counts = [(k, n) for k, n in diff.counts().items() if n]
    parts = ", ".join(f"{_KIND_TEXT[k]}: {n}" for k, n in counts)
    total = len(diff.differences)
    noun = "difference" if total == 1 else "differences"
    return Text.assemble(("reports differ", "bold red"), f": {total} {noun} ({parts}; {tolerance})")


def _rows_table(what_width: int, *, header: bool = False) -> Table:
    """One subject's rows; every such table has the same column widths, so they align."""
    table = Table(
        box=box.SIMPLE_HEAD,
        show_header=header,
        show_edge=False,
        pad_edge=False,
        padding=(0, 1),
        expand=True,
    )
    table.add_column("", width=1, no_wrap=True)
    table.add_column("what", width=what_width, overflow="fold")
    table.add_column("baseline", ratio=1, overflow="fold")
    table.add_column("current", ratio=1, overflow="fold")
    return table


def diff_renderable(diff: ReportDiff) -> Group:
    """The diff for people: a headline, then per fault (or cluster) one row per difference."""
    parts: list[RenderableType] = [
        Text.assemble(  # paths whole on one line, to copy them
            (label, "bold"), _show(name), no_wrap=True, overflow="ignore"
        )
        for label, name in (("baseline: ", diff.baseline_name), ("current:  ", diff.current_name))
    ]
    parts.append(_headline(diff))
    if diff.equal:
        return Group(*parts)
    clock = _Clock(diff.origin_ns)
    rows = [(d, _what(d), *_cells(d, clock)) for d in diff.differences[:MAX_ROWS]]
    what_width = min(max(len("what"), *(len(row[1]) for row in rows)), MAX_WHAT)
    parts += [
        Text(""),
        Text(f"{LEGEND}; times in s from the baseline recording's start", style="dim"),
        Padding(_rows_table(what_width, header=True), (0, 0, 0, 2)),
    ]
    previous: tuple[str, str] | None = None
    table = _rows_table(what_width)
    for difference, what, old, new in rows:
        subject = (difference.subject_key, difference.subject)
        if subject != previous:
            if previous is not None:
                parts.append(Padding(table, (0, 0, 0, 2)))
                table = _rows_table(what_width)
            prefix = "cluster " if difference.subject_key == "cluster_id" else ""
            parts.append(Text(prefix + _show(difference.subject), style="bold"))
            previous = subject
        mark, style = _MARKS[difference.kind.rsplit("_", 1)[1]]
        table.add_row(Text(mark, style=style), Text(what), Text(old), Text(new))
    parts.append(Padding(table, (0, 0, 0, 2)))
    if len(diff.differences) > MAX_ROWS:
        more = len(diff.differences) - MAX_ROWS
        parts.append(Text(f"... and {more} more (the JSON output lists all)", style="dim"))
    return Group(*parts)


def render_diff(diff: ReportDiff, width: int = 100) -> str:
    """The human output as plain text (no ANSI codes) laid out for ``width`` columns."""
    buffer = io.StringIO()
    console = Console(
        file=buffer,
        width=width,
        force_terminal=False,
        color_system=None,
        no_color=True,
        markup=False,
        emoji=False,
        highlight=False,
    )
    console.print(diff_renderable(diff), crop=False)
    return "\n".join(line.rstrip(" ") for line in buffer.getvalue().split("\n"))
