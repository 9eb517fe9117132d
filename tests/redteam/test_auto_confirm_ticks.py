"""Red team: time-based confirmation ticks cost what is due, not a scan of every fault.

The old full scan is kept here as the oracle; the indexed tick must give the same records.
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING

from hypothesis import given, settings, strategies as st

from medkit_replay.engine import DebounceConfig, FaultManager, FaultManagerConfig, Timeline
from medkit_replay.engine.thresholds import EntityOverride
from medkit_replay.engine.timeline import AUTO_CONFIRM_PERIOD_NS, _first_tick_at_or_after
from medkit_replay.model import ClearRequest, ReportRequest
from tests.redteam.support import run_limited

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.engine.storage import FaultStorage

S = 1_000_000_000
CODES = ["A", "B", "MOTOR", "MOTOR_2", "b", "Z\u00e9", "\u00e9"]
SOURCES = ["/s/one", "/s/two", "/other"]


class ScanTimeline(Timeline):
    """The timeline as it was: every tick looks at every fault (the oracle)."""

    def _catch_up_auto_confirm(self, t_ns: int) -> None:
        assert self.t0_ns is not None
        last_tick = self._last_tick_at_or_before(t_ns, AUTO_CONFIRM_PERIOD_NS)
        after_ns = self.manager.config.auto_confirm_after_ns
        due: list[tuple[int, bytes, str]] = []
        for code, fault in self.manager.storage.faults.items():
            if fault.status != "PREFAILED":
                continue
            tick = _first_tick_at_or_after(
                max(fault.last_failed_ns + after_ns, self._next_confirm_ns),
                self.t0_ns,
                AUTO_CONFIRM_PERIOD_NS,
            )
            if tick <= last_tick:
                due.append((tick, code.encode("utf-8"), code))
        due.sort()
        for tick, _, code in due:
            self.manager.confirm_by_timer(code, tick)
        self._next_confirm_ns = last_tick + AUTO_CONFIRM_PERIOD_NS


def scan_due(storage: FaultStorage, now_ns: int, after_ns: int) -> list[str]:
    """The storage's old due list: a scan of every fault, in fault_code byte order."""
    due = [
        code
        for code, fault in storage.faults.items()
        if fault.status == "PREFAILED" and now_ns - fault.last_failed_ns >= after_ns
    ]
    due.sort(key=lambda c: c.encode("utf-8"))
    return due


Step = tuple[int, str, str, int, int, str, bool]  # dt, op, code, event, severity, source, fast


@st.composite
def steps(draw: st.DrawFn) -> list[Step]:
    gaps = [0, 1, 300, 999, 1000, 1001, 2500, 7000]
    out: list[Step] = []
    for _ in range(draw(st.integers(1, 60))):
        out.append(
            (
                draw(st.sampled_from(gaps)) * 1_000_000,
                draw(st.sampled_from(["report"] * 8 + ["clear"])),
                draw(st.sampled_from(CODES)),
                draw(st.sampled_from([0, 0, 0, 1, 1])),
                draw(st.sampled_from([0, 1, 2, 3])),
                draw(st.sampled_from(SOURCES)),
                draw(st.booleans()),
            )
        )
    return out


@st.composite
def configs(draw: st.DrawFn) -> FaultManagerConfig:
    overrides: tuple[EntityOverride, ...] = ()
    if draw(st.booleans()):
        overrides = (
            EntityOverride(
                prefix="/s/two",
                confirmation_threshold=draw(st.integers(-5, -1)),
                healing_enabled=draw(st.booleans()),
                healing_threshold=draw(st.integers(0, 3)),
            ),
        )
    return FaultManagerConfig(
        debounce=DebounceConfig(
            confirmation_threshold=draw(st.integers(-5, -1)),
            healing_enabled=draw(st.booleans()),
            healing_threshold=draw(st.integers(0, 3)),
        ),
        auto_confirm_after_ns=draw(st.sampled_from([1, 999_999_999, S, 2 * S, 2_500_000_000])),
        entity_overrides=overrides,
    )


def drive(timeline: Timeline, stream: list[Step]) -> FaultManager:
    manager = timeline.manager
    t_ns = 5 * S + 123
    for dt, op, code, event, severity, source, fast in stream:
        t_ns += dt
        timeline.advance(t_ns)
        if op == "clear":
            timeline.apply(ClearRequest(t_ns=t_ns, fault_code=code))
        elif fast:  # the replay's hot path
            manager.report_fields(t_ns, "script", None, code, event, severity, "", source)
        else:
            timeline.apply(
                ReportRequest(
                    t_ns=t_ns,
                    fault_code=code,
                    event_type=event,
                    severity=severity,
                    source_id=source,
                )
            )
    return manager


def outcome(manager: FaultManager) -> tuple[object, ...]:
    out = manager.output
    return (
        list(out.transitions),
        list(out.events),
        list(out.reports),
        list(out.clears),
        manager.faults(),
    )


@settings(max_examples=400, deadline=None)
@given(config=configs(), stream=steps())
def test_indexed_ticks_equal_the_full_scan(config: FaultManagerConfig, stream: list[Step]) -> None:
    indexed = drive(Timeline(FaultManager(config)), stream)
    scanned = drive(ScanTimeline(FaultManager(config)), stream)
    assert outcome(indexed) == outcome(scanned)


@settings(max_examples=300, deadline=None)
@given(
    config=configs(),
    stream=steps(),
    checks=st.lists(st.integers(0, 9 * S), min_size=1, max_size=8),
)
def test_auto_confirm_tick_equals_the_scan(
    config: FaultManagerConfig, stream: list[Step], checks: list[int]
) -> None:
    """Storage-level ticks at arbitrary times (the upstream tests' path) against the scan."""
    manager = FaultManager(config)
    t_ns = 5 * S
    for index, (dt, op, code, event, severity, source, fast) in enumerate(stream):
        t_ns += dt
        if op == "clear":
            manager.clear(ClearRequest(t_ns=t_ns, fault_code=code))
        elif fast:
            manager.report_fields(t_ns, "script", None, code, event, severity, "", source)
        else:
            manager.report(
                ReportRequest(
                    t_ns=t_ns,
                    fault_code=code,
                    event_type=event,
                    severity=severity,
                    source_id=source,
                )
            )
        if index % 3 == 0:
            now = t_ns + checks[index % len(checks)]
            expected = scan_due(manager.storage, now, config.auto_confirm_after_ns)
            assert manager.auto_confirm_tick(now) == expected
    now = t_ns + max(checks)
    expected = scan_due(manager.storage, now, config.auto_confirm_after_ns)
    assert manager.auto_confirm_tick(now) == expected


def test_faults_failing_again_move_their_due_time() -> None:
    """A PREFAILED fault that fails again is due from its last FAILED, not its first."""
    manager = FaultManager(
        FaultManagerConfig(
            debounce=DebounceConfig(confirmation_threshold=-9), auto_confirm_after_ns=10 * S
        )
    )
    for t in (0, 6 * S):
        manager.report(ReportRequest(t_ns=t, fault_code="A", event_type=0, source_id="/s"))
    assert manager.auto_confirm_tick(12 * S) == []
    assert manager.auto_confirm_tick(16 * S) == ["A"]
    assert manager.auto_confirm_tick(99 * S) == []


PENDING = 100_000
AFTER_SEC = 4_000
HEARTBEATS = 5_000


def test_many_pending_faults_tick_in_time(tmp_path: Path) -> None:
    """10^5 PREFAILED codes, 5,000 one-second ticks: a scan visits 5·10^8 faults (many minutes).

    All of them confirm at one tick 4,000 s in; the ticks before and after have nothing due.
    """
    script = tmp_path / "pending.jsonl"
    with script.open("w") as out:
        for n in range(PENDING):
            line = {
                "t_ns": S,
                "op": "report",
                "fault_code": f"CODE_{n:06d}",
                "event_type": "FAILED",
                "severity": 1,
                "source_id": "/many",
            }
            out.write(json.dumps(line) + "\n")
        for k in range(1, HEARTBEATS + 1):
            line = {
                "t_ns": 2 * S + k * S,
                "op": "report",
                "fault_code": "HEARTBEAT",
                "event_type": "PASSED",
                "source_id": "/beat",
            }
            out.write(json.dumps(line) + "\n")
    config = tmp_path / "params.yaml"
    config.write_text(
        "fault_manager:\n  ros__parameters:\n    confirmation_threshold: -3\n"
        f"    auto_confirm_after_sec: {AFTER_SEC}.0\n"
    )
    report = tmp_path / "report.json"
    outcome = run_limited(
        ["analyze", script, "--config", config, "--json", report, "--quiet"],
        cpu_seconds=120,
        timeout=600,
    )
    assert outcome.status == 0, outcome.stderr[-2000:]
    data = json.loads(report.read_text())
    confirms = [t for t in data["transitions"] if t["cause"] == "auto_confirm"]
    assert len(confirms) == PENDING
    # Every code failed at t0 = 1 s, so all confirm at the tick t0 + 4,000 s.
    assert {t["t_ns"] for t in confirms} == {S + AFTER_SEC * S}
    assert [t["fault_code"] for t in confirms] == sorted(t["fault_code"] for t in confirms)
