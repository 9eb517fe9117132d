"""Compares two JSON reports (schema ``medkit-replay/report/v1``): what changed between runs.

Pure: two report dicts in, a :class:`ReportDiff` out; no file, no clock, no terminal.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, get_args

from medkit_replay.diffing.align import align
from medkit_replay.errors import InputError
from medkit_replay.model import NS_PER_SEC
from medkit_replay.result import REPORT_SCHEMA

if TYPE_CHECKING:
    from medkit_replay.diffing.align import KeyFunction

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
KINDS: tuple[Kind, ...] = get_args(Kind)
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
    warnings: tuple[str, ...] = ()
    """What the reader should know before trusting the differences (reports of two releases)."""

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
            **({"warnings": list(self.warnings)} if self.warnings else {}),
        }


# --- the report view -------------------------------------------------------------------------


class _Report:
    """The parts of one report a diff reads, checked as they are read."""

    def __init__(self, report: object, name: str) -> None:
        self.name = name
        if not isinstance(report, Mapping):
            raise InputError("not a medkit-replay report (not a JSON object)", path=name)
        schema = report.get("schema")
        if schema != REPORT_SCHEMA:
            raise InputError(
                f"not a medkit-replay report: schema is {_short(schema)}, "
                f"expected {REPORT_SCHEMA!r}",
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
        release = report.get("upstream_release")  # absent from reports made before it existed
        self.release = release if isinstance(release, str) else None

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

    What counts as a difference:

    - a fault in one report and not in the other (``fault_added``, ``fault_removed``; its events
      and transitions are not listed again), or a fault whose ``status``, ``severity``,
      ``occurrence_count``, ``reporting_sources``, ``muted``, ``root_cause_code`` or
      ``cluster_ids`` changed (``fault_changed``, one per field);
    - per fault code, the transitions (keyed on ``from_status``, ``to_status``, ``cause``) and the
      FaultEvents (keyed on ``event_type``) of both reports are aligned in order as a text diff
      aligns lines; an aligned pair more than the tolerance apart in bag time is ``*_shifted``, an
      unaligned baseline item ``*_missing``, an unaligned current item ``*_extra``;
    - an active cluster in one report and not in the other (``cluster_added``,
      ``cluster_removed``), or whose rule, representative or members changed
      (``cluster_changed``).

    Descriptions, input paths, tool versions, warnings, requests and summaries are not compared;
    reports naming different ``upstream_release`` values get one warning
    (``ReportDiff.warnings``).

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
        warnings=_release_warnings(old.release, new.release),
    )


def _release_warnings(baseline: str | None, current: str | None) -> tuple[str, ...]:
    """One warning when the reports name different ros2_medkit releases (a report made before
    ``upstream_release`` existed names none, and is compared as it is)."""
    if baseline is None or current is None or baseline == current:
        return ()
    return (
        f"warning: the reports model different ros2_medkit releases (baseline {_short(baseline)}, "
        f"current {_short(current)}): some differences may be the release's, not the robot's",
    )


def _fault_differences(code: str, old: _Report, new: _Report, tolerance: int) -> list[Difference]:
    before, after = old.fault_by_code.get(code), new.fault_by_code.get(code)
    if before is not None and after is None:
        return [Difference("fault_removed", code, {"baseline": dict(before)})]
    if before is None and after is not None:
        return [Difference("fault_added", code, {"current": dict(after)})]
    found: list[Difference] = []
    if before is not None and after is not None:
        found += _changed_fields("fault_changed", code, before, after, FAULT_FIELDS)
    found += _item_differences(
        code,
        "transition",
        old.transitions_of(code),
        new.transitions_of(code),
        _transition_key,
        tolerance,
    )
    found += _item_differences(
        code, "event", old.events_of(code), new.events_of(code), _event_key, tolerance
    )
    return found


def _transition_key(transition: Mapping[str, object]) -> tuple[object, ...]:
    return (transition.get("from_status"), transition["to_status"], transition.get("cause"))


def _event_key(event: Mapping[str, object]) -> tuple[object, ...]:
    return (event["event_type"],)


def _key_detail(what: Literal["transition", "event"], key: tuple[object, ...]) -> JsonObject:
    if what == "event":
        return {"event_type": key[0]}
    return {"from_status": key[0], "to_status": key[1], "cause": key[2]}


def _item_differences(
    code: str,
    what: Literal["transition", "event"],
    before: Sequence[Mapping[str, object]],
    after: Sequence[Mapping[str, object]],
    key: KeyFunction,
    tolerance: int,
) -> list[Difference]:
    """One fault's transitions or events that :func:`align` leaves unaligned or shifted."""
    found: list[Difference] = []
    for how, k, old_t, new_t in align(before, after, key, tolerance):
        detail = _key_detail(what, k)
        shift = new_t - old_t if old_t is not None and new_t is not None else None
        detail |= {"baseline_t_ns": old_t, "current_t_ns": new_t, "shift_ns": shift}
        found.append(Difference(_kind(what, how), code, detail))
    return found


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
    return _changed_fields("cluster_changed", cluster_id, before, after, CLUSTER_FIELDS)


def _changed_fields(
    kind: Kind,
    key: str,
    before: Mapping[str, object],
    after: Mapping[str, object],
    names: Iterable[str],
) -> list[Difference]:
    """One ``kind`` difference per field of ``names`` whose value changed."""
    return [
        Difference(
            kind, key, {"field": name, "baseline": before.get(name), "current": after.get(name)}
        )
        for name in names
        if before.get(name) != after.get(name)
    ]
