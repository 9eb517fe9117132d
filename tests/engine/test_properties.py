"""Property-based checks of the engine's invariants over random request streams.

Counter band, status rule, event rules, field rules and determinism hold for any stream.
"""

from __future__ import annotations

from hypothesis import given, settings, strategies as st

from medkit_replay.engine import DebounceConfig, FaultManager, FaultManagerConfig, Timeline
from medkit_replay.engine.correlation import CorrelationConfig, CorrelationRule, Representative
from medkit_replay.engine.thresholds import EntityOverride
from medkit_replay.model import ClearRequest, ReportRequest, Status

CODES = ["MOTOR_OVERHEAT", "MOTOR_COMM_FL", "SENSOR_LIDAR", "SENSOR_IMU", "ESTOP_001", "bad code"]
SOURCES = ["/powertrain/motor", "/sensors/lidar", "/sensors/lidar/front", "/other", ""]


@st.composite
def streams(draw: st.DrawFn) -> list[ReportRequest | ClearRequest]:
    n = draw(st.integers(min_value=1, max_value=80))
    t = 1_000_000_000
    out: list[ReportRequest | ClearRequest] = []
    for _ in range(n):
        t += draw(st.sampled_from([0, 1, 10, 300, 1000, 2500])) * 1_000_000
        code = draw(st.sampled_from(CODES))
        if draw(st.integers(0, 9)) == 0:
            out.append(
                ClearRequest(
                    t_ns=t, fault_code=code, skip_correlation_auto_clear=draw(st.booleans())
                )
            )
            continue
        out.append(
            ReportRequest(
                t_ns=t,
                fault_code=code,
                event_type=draw(st.sampled_from([0, 0, 1, 1, 2])),
                severity=draw(st.sampled_from([0, 1, 2, 3, 4])),
                description=draw(st.sampled_from(["", "d1", "d2"])),
                source_id=draw(st.sampled_from(SOURCES)),
            )
        )
    return out


@st.composite
def configs(draw: st.DrawFn) -> FaultManagerConfig:
    overrides: tuple[EntityOverride, ...] = ()
    if draw(st.booleans()):
        overrides = (
            EntityOverride(
                prefix="/sensors",
                confirmation_threshold=draw(st.integers(-4, -1)),
                healing_threshold=draw(st.integers(0, 5)),
            ),
            EntityOverride(prefix="/sensors/lidar", healing_enabled=draw(st.booleans())),
        )
    correlation = None
    if draw(st.booleans()):
        correlation = CorrelationConfig(
            enabled=True,
            patterns={"motor": ("MOTOR_*",), "sensor": ("SENSOR_*",)},
            rules=(
                CorrelationRule(
                    id="estop",
                    name="estop",
                    root_cause_codes=("ESTOP_001",),
                    symptom_pattern_ids=("motor",),
                    window_ms=2000,
                    auto_clear_with_root=draw(st.booleans()),
                ),
                CorrelationRule(
                    id="storm",
                    name="storm",
                    mode="auto_cluster",
                    match_pattern_ids=("sensor",),
                    min_count=2,
                    window_ms=1500,
                    representative=draw(st.sampled_from(list(Representative))),
                ),
            ),
        )
    return FaultManagerConfig(
        debounce=DebounceConfig(
            confirmation_threshold=draw(st.integers(-4, -1)),
            healing_enabled=draw(st.booleans()),
            healing_threshold=draw(st.integers(0, 4)),
        ),
        auto_confirm_after_ns=draw(st.sampled_from([0, 0, 2_000_000_000])),
        near_miss_bound=draw(st.sampled_from([0, 2, 200])),
        entity_overrides=overrides,
        correlation=correlation,
    )


def expected_status(counter: int, before: Status, cfg: DebounceConfig) -> Status:
    if counter <= cfg.confirmation_threshold:
        return "CONFIRMED"
    if cfg.healing_enabled and counter >= cfg.healing_threshold:
        return "HEALED"
    if before in ("CONFIRMED", "HEALED"):
        return before
    if counter < 0:
        return "PREFAILED"
    if counter > 0:
        return "PREPASSED"
    return before


@settings(max_examples=300, deadline=None)
@given(config=configs(), stream=streams())
def test_each_report_obeys_counter_status_and_event_rules(
    config: FaultManagerConfig, stream: list[ReportRequest | ClearRequest]
) -> None:
    manager = FaultManager(config)
    timeline = Timeline(manager)
    occurrences: dict[str, int] = {}
    max_severity: dict[str, int] = {}
    sources: dict[str, set[str]] = {}
    for request in stream:
        timeline.advance(request.t_ns)
        faults = manager.storage.faults
        before = faults[request.fault_code].status if request.fault_code in faults else None
        counter_before = faults[request.fault_code].counter if before is not None else None
        n_events = len(manager.output.events)
        n_transitions = len(manager.output.transitions)
        timeline.apply(request)
        new_events = list(manager.output.events)[n_events:]
        if isinstance(request, ClearRequest):
            assert all(e.event_type == "fault_cleared" for e in new_events)
            continue
        record = manager.output.reports[-1]
        fault = faults.get(request.fault_code)
        if not record.accepted:
            assert not new_events
            assert len(manager.output.transitions) == n_transitions
            assert (fault.status if fault else None) == before
            continue
        if fault is None:
            assert request.event_type == 1 and not new_events
            continue
        cfg = manager.resolver.resolve(request.source_id)
        failed = request.event_type == 0
        if before is None or (before == "CLEARED" and failed):
            assert fault.counter == -1
            occurrences[request.fault_code] = occurrences.get(request.fault_code, 0) + 1
        elif before == "CLEARED":
            assert fault.status == "CLEARED" and not new_events
            continue
        else:
            # The counter moved one step inside this report's band (after re-clamping).
            assert counter_before is not None
            assert cfg.confirmation_threshold <= fault.counter <= cfg.healing_threshold
            start = min(max(counter_before, cfg.confirmation_threshold), cfg.healing_threshold)
            step = -1 if failed else 1
            assert fault.counter == min(
                max(start + step, cfg.confirmation_threshold), cfg.healing_threshold
            )
            if failed and request.severity == 3:
                assert fault.status == "CONFIRMED"
            else:
                assert fault.status == expected_status(fault.counter, before, cfg)
        if failed:
            max_severity[request.fault_code] = max(
                max_severity.get(request.fault_code, 0), request.severity
            )
            sources.setdefault(request.fault_code, set()).add(request.source_id)
        assert fault.occurrence_count == occurrences[request.fault_code]
        assert fault.severity == max_severity[request.fault_code]
        assert set(fault.sources) == sources[request.fault_code]
        # At most one event per report, of the kind the event rules give.
        assert len(new_events) <= 1
        after = fault.status
        is_new = before is None or before == "CLEARED"
        if after == "HEALED" and before != "HEALED" and not is_new:
            assert [e.event_type for e in new_events] == ["fault_cleared"]
        elif after == "CONFIRMED":
            kind = "fault_updated" if before == "CONFIRMED" else "fault_confirmed"
            if new_events:
                assert new_events[0].event_type == kind
            else:
                assert manager.correlation is not None  # only muting withholds it
        else:
            assert not new_events


@settings(max_examples=150, deadline=None)
@given(config=configs(), stream=streams())
def test_transitions_chain_and_near_misses_are_bounded(
    config: FaultManagerConfig, stream: list[ReportRequest | ClearRequest]
) -> None:
    manager = FaultManager(config)
    timeline = Timeline(manager)
    for request in stream:
        timeline.advance(request.t_ns)
        timeline.apply(request)
    last: dict[str, Status] = {}
    for transition in manager.output.transitions:
        assert transition.from_status == last.get(transition.fault_code)
        assert transition.from_status != transition.to_status
        last[transition.fault_code] = transition.to_status
    assert last == {code: f.status for code, f in manager.storage.faults.items()}
    for series in manager.storage.near_misses.values():
        assert config.near_miss_bound == 0 or len(series) <= config.near_miss_bound
        assert all(entry.resulting_status != "CONFIRMED" for entry in series)


@settings(max_examples=150, deadline=None)
@given(config=configs(), stream=streams())
def test_correlation_without_clears_changes_events_only(
    config: FaultManagerConfig, stream: list[ReportRequest | ClearRequest]
) -> None:
    reports = [r for r in stream if isinstance(r, ReportRequest)]
    plain = FaultManager(
        FaultManagerConfig(debounce=config.debounce, entity_overrides=config.entity_overrides)
    )
    correlated = FaultManager(
        FaultManagerConfig(
            debounce=config.debounce,
            entity_overrides=config.entity_overrides,
            correlation=config.correlation or CorrelationConfig(enabled=True),
        )
    )
    for request in reports:
        plain.report(request)
        correlated.report(request)
    assert plain.output.transitions == correlated.output.transitions
    strip = [(e.t_ns, e.event_type, e.fault.fault_code) for e in plain.output.events]
    kept = [(e.t_ns, e.event_type, e.fault.fault_code) for e in correlated.output.events]
    assert set(kept) <= set(strip)
    assert [k for k in strip if k[1] == "fault_cleared"] == [
        k for k in kept if k[1] == "fault_cleared"
    ]


@settings(max_examples=60, deadline=None)
@given(config=configs(), stream=streams())
def test_two_runs_give_identical_outputs(
    config: FaultManagerConfig, stream: list[ReportRequest | ClearRequest]
) -> None:
    outputs = []
    for _ in range(2):
        manager = FaultManager(config)
        timeline = Timeline(manager)
        for request in stream:
            timeline.advance(request.t_ns)
            timeline.apply(request)
        outputs.append((manager.output, manager.faults()))
    assert outputs[0] == outputs[1]
