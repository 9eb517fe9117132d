"""Shared machinery for the ports of upstream's fault manager tests (fault-manager.md §4).

Not a test module: scenario steps, a storage-level and a node-level runner, and the registry
that ties every test to the upstream scenario IDs it ports (checked by test_upstream_coverage).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Literal, TypedDict, TypeVar, Unpack

from medkit_replay.engine.debounce import DebounceConfig
from medkit_replay.engine.manager import FaultManager, FaultManagerConfig
from medkit_replay.engine.queries import list_faults
from medkit_replay.engine.storage import (
    DEFAULT_NEAR_MISS_BOUND,
    DEFAULT_STORAGE_TYPE,
    FaultRecord,
    FaultStorage,
)
from medkit_replay.model import (
    NS_PER_SEC,
    ClearRequest,
    FaultEvent,
    FaultSnapshot,
    ReportRequest,
    Status,
)
from medkit_replay.releases import Release, default_release

INFO, WARN, ERROR, CRITICAL = 0, 1, 2, 3
FAILED, PASSED = 0, 1

EventSig = tuple[str, str]
"""A FaultEvent reduced to (event_type, fault.status)."""

CONFIRMED_EV: EventSig = ("fault_confirmed", "CONFIRMED")
UPDATED_EV: EventSig = ("fault_updated", "CONFIRMED")
HEALED_EV: EventSig = ("fault_cleared", "HEALED")
CLEARED_EV: EventSig = ("fault_cleared", "CLEARED")
NO_EVENTS: tuple[EventSig, ...] = ()

# -- scenario registry -------------------------------------------------------------------------

REGISTRY: dict[str, list[str]] = {}
"""Upstream scenario ID -> qualified names of the tests porting it."""

_Fn = TypeVar("_Fn", bound=Callable[..., object])


def upstream(*scenario_ids: str) -> Callable[[_Fn], _Fn]:
    """Record that the decorated test ports the given upstream scenario IDs."""

    def register(fn: _Fn) -> _Fn:
        name = f"{fn.__module__}.{getattr(fn, '__qualname__', repr(fn))}"
        for sid in scenario_ids:
            REGISTRY.setdefault(sid, []).append(name)
        return fn

    return register


def status_of(manager: FaultManager, code: str) -> Status:
    """The current status of a known fault (a call, so mypy does not narrow it across steps)."""
    return manager.storage.faults[code].status


def events_of(manager: FaultManager) -> list[FaultEvent]:
    """Every FaultEvent the manager has published, in order."""
    return list(manager.output.events)


def events_since(manager: FaultManager, count: int) -> list[FaultEvent]:
    """The FaultEvents published after the first ``count``."""
    return list(manager.output.events)[count:]


def signatures(events: Iterable[FaultEvent]) -> tuple[EventSig, ...]:
    """Events as (event_type, fault.status) pairs."""
    return tuple((e.event_type, e.fault.status) for e in events)


# -- scenario steps ----------------------------------------------------------------------------


class Expect(TypedDict, total=False):
    """What must hold after a step; absent keys are not checked.

    ``returns`` is the storage return value (is_new for reports, found for clears; for clears
    it is also the node's ``success``). ``events`` and ``message`` are node-level only.
    """

    returns: bool
    accepted: bool
    status: Status | None
    ctr: int
    count: int
    stored_severity: int
    sources: tuple[str, ...]
    stored_description: str
    first_ns: int
    last_ns: int
    last_passed_ns: int
    size: int
    near_misses: int
    events: tuple[EventSig, ...]
    message: str
    listed: tuple[str, ...]
    listed_status: Status


Op = Literal["F", "P", "CLEAR", "LIST"]


@dataclass(frozen=True, kw_only=True)
class Step:
    """One request (or ListFaults query) of a scenario, with its expectations."""

    op: Op
    code: str = ""
    severity: int = 0
    source: str = "/node1"
    description: str = ""
    t_ns: int | None = None
    config: DebounceConfig | None = None
    statuses: tuple[str, ...] = ()
    by_severity: bool = False
    expect: Expect = field(default_factory=Expect)


def failed(
    code: str,
    severity: int = ERROR,
    source: str = "/node1",
    description: str = "",
    *,
    t_ns: int | None = None,
    config: DebounceConfig | None = None,
    **expect: Unpack[Expect],
) -> Step:
    """A FAILED report (``config``: storage-level config of this report, else the case's)."""
    return Step(
        op="F",
        code=code,
        severity=severity,
        source=source,
        description=description,
        t_ns=t_ns,
        config=config,
        expect=expect,
    )


def passed(
    code: str,
    source: str = "/node1",
    severity: int = 0,
    description: str = "",
    *,
    t_ns: int | None = None,
    config: DebounceConfig | None = None,
    **expect: Unpack[Expect],
) -> Step:
    """A PASSED report."""
    return Step(
        op="P",
        code=code,
        severity=severity,
        source=source,
        description=description,
        t_ns=t_ns,
        config=config,
        expect=expect,
    )


def clear(code: str, *, t_ns: int | None = None, **expect: Unpack[Expect]) -> Step:
    """A ClearFault request (no correlation in these scenarios)."""
    return Step(op="CLEAR", code=code, t_ns=t_ns, expect=expect)


def query(
    statuses: Sequence[str] = (),
    by_severity: bool = False,
    severity: int = 0,
    *,
    code: str = "",
    **expect: Unpack[Expect],
) -> Step:
    """A ListFaults query; expect ``listed`` (codes in order), ``listed_status``, and the state
    of fault ``code`` (a query changes nothing, so it also serves as a pure state check)."""
    return Step(
        op="LIST",
        code=code,
        statuses=tuple(statuses),
        by_severity=by_severity,
        severity=severity,
        expect=expect,
    )


@dataclass(frozen=True, kw_only=True)
class Case:
    """An upstream scenario as data.

    ``config`` is the storage-level config (passed unsanitised with every report). The node run
    uses ``node_config`` when given, else a FaultManagerConfig around ``config`` (which the
    manager sanitises); ``node=False`` skips it for storage-only configs (crit off).
    ``release`` and ``storage_type`` choose the upstream rules both runs apply.
    """

    sid: str
    name: str
    steps: tuple[Step, ...]
    config: DebounceConfig = field(default_factory=DebounceConfig)
    node: bool = True
    node_config: FaultManagerConfig | None = None
    near_miss_bound: int = DEFAULT_NEAR_MISS_BOUND
    release: Release = field(default_factory=default_release)
    storage_type: str = DEFAULT_STORAGE_TYPE

    @property
    def test_id(self) -> str:
        """The pytest id: scenario ID and upstream test name."""
        return f"{self.sid}-{self.name}"


def schedule(steps: Sequence[Step], start_ns: int = NS_PER_SEC) -> list[int]:
    """Bag times of the steps: explicit ones as given, the others 1 s after the previous."""
    times: list[int] = []
    previous: int | None = None
    for step in steps:
        t = (
            step.t_ns
            if step.t_ns is not None
            else (start_ns if previous is None else previous + NS_PER_SEC)
        )
        times.append(t)
        previous = t
    return times


def _check_state(
    where: str,
    step: Step,
    *,
    fault: FaultRecord | None,
    size: int,
    near_misses: int,
    listed: Sequence[FaultRecord | FaultSnapshot] | None,
) -> None:
    exp = step.expect
    if "status" in exp:
        assert (fault.status if fault is not None else None) == exp["status"], where
    if "size" in exp:
        assert size == exp["size"], where
    if "near_misses" in exp:
        assert near_misses == exp["near_misses"], where
    if "listed" in exp:
        assert listed is not None, where
        assert tuple(f.fault_code for f in listed) == exp["listed"], where
    if "listed_status" in exp:
        assert listed is not None, where
        assert all(f.status == exp["listed_status"] for f in listed), where
    checks: list[tuple[str, Callable[[FaultRecord], object]]] = [
        ("ctr", lambda f: f.counter),
        ("count", lambda f: f.occurrence_count),
        ("stored_severity", lambda f: f.severity),
        ("sources", lambda f: f.sorted_sources()),
        ("stored_description", lambda f: f.description),
        ("first_ns", lambda f: f.first_occurred_ns),
        ("last_ns", lambda f: f.last_occurred_ns),
        ("last_passed_ns", lambda f: f.last_passed_ns),
    ]
    expected: dict[str, object] = dict(exp)
    for key, read in checks:
        if key in expected:
            assert fault is not None, f"{where}: no fault {step.code}"
            assert read(fault) == expected[key], f"{where}: {key}"


def _where(case: Case, layer: str, index: int, step: Step) -> str:
    return f"{case.sid} ({layer}) step {index + 1}: {step.op} {step.code}"


def run_storage(case: Case) -> FaultStorage:
    """Replay a case against FaultStorage with its explicit per-report configs."""
    storage = FaultStorage(case.near_miss_bound, case.release, case.storage_type)
    for index, (step, t_ns) in enumerate(zip(case.steps, schedule(case.steps), strict=True)):
        where = _where(case, "storage", index, step)
        returned: bool | None = None
        listed: list[FaultRecord] | None = None
        if step.op in ("F", "P"):
            outcome = storage.report(
                step.code,
                FAILED if step.op == "F" else PASSED,
                step.severity,
                step.description,
                step.source,
                t_ns,
                step.config or case.config,
            )
            returned = outcome[2]
        elif step.op == "CLEAR":
            returned = storage.clear(step.code)
        else:
            listed = list_faults(
                storage.faults.values(), step.statuses, step.by_severity, step.severity
            )
        if "returns" in step.expect:
            assert returned == step.expect["returns"], where
        _check_state(
            where,
            step,
            fault=storage.faults.get(step.code),
            size=len(storage.faults),
            near_misses=len(storage.near_misses.get(step.code, [])),
            listed=listed,
        )
    return storage


def node_config_of(case: Case) -> FaultManagerConfig:
    """The FaultManagerConfig a case's node run uses."""
    if case.node_config is not None:
        return case.node_config
    return FaultManagerConfig(
        debounce=case.config,
        near_miss_bound=case.near_miss_bound,
        release=case.release,
        storage_type=case.storage_type,
    )


def run_node(case: Case) -> FaultManager:
    """Replay a case through FaultManager and check events, responses and state per step."""
    manager = FaultManager(node_config_of(case))
    for index, (step, t_ns) in enumerate(zip(case.steps, schedule(case.steps), strict=True)):
        where = _where(case, "node", index, step)
        events_before = len(manager.output.events)
        listed: list[FaultSnapshot] | None = None
        if step.op in ("F", "P"):
            accepted = manager.report(
                ReportRequest(
                    t_ns=t_ns,
                    fault_code=step.code,
                    event_type=FAILED if step.op == "F" else PASSED,
                    severity=step.severity,
                    description=step.description,
                    source_id=step.source,
                )
            )
            assert accepted == step.expect.get("accepted", True), where
        elif step.op == "CLEAR":
            success = manager.clear(ClearRequest(t_ns=t_ns, fault_code=step.code))
            if "returns" in step.expect:
                assert success == step.expect["returns"], where
            if "message" in step.expect:
                assert manager.output.clears[-1].message == step.expect["message"], where
        else:
            listed = list_faults(manager.faults(), step.statuses, step.by_severity, step.severity)
        if "events" in step.expect:
            emitted = events_since(manager, events_before)
            assert signatures(emitted) == step.expect["events"], where
            assert all(e.t_ns == t_ns for e in emitted), where
            assert all(e.fault.fault_code == step.code for e in emitted), where
        _check_state(
            where,
            step,
            fault=manager.storage.faults.get(step.code),
            size=len(manager.storage.faults),
            near_misses=len(manager.storage.near_misses.get(step.code, [])),
            listed=listed,
        )
    return manager
