"""FaultManager.report_fields against the plain oracle, and the bridges' feed against on_message.

Random request sequences (valid and invalid, known and new faults, clears in between) under
several configurations (healing, thresholds, entity overrides, correlation with muting and
clusters) go through both entries of two managers: every record, every state must agree.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from medkit_replay.bridges.diagnostic import DiagnosticBridge, DiagnosticBridgeConfig
from medkit_replay.bridges.log import LogBridge, LogBridgeConfig
from medkit_replay.config.fault_manager import fault_manager_config
from medkit_replay.config.params import load_parameters
from medkit_replay.engine.debounce import DebounceConfig
from medkit_replay.engine.local_filter import LocalFilterConfig
from medkit_replay.engine.manager import FaultManager, FaultManagerConfig
from medkit_replay.engine.thresholds import EntityOverride
from medkit_replay.model import (
    CLEAR_ROWS,
    EVENT_ROWS,
    REPORT_ROWS,
    TRANSITION_ROWS,
    ClearRequest,
    EngineOutput,
    ReportRequest,
)
from medkit_replay.spool import Spool
from tests.inputs.builders import TS
from tests.oracle.bridges import oracle_diagnostic, oracle_log
from tests.oracle.manager import oracle_report

if TYPE_CHECKING:
    from medkit_replay.model import Origin

RULES = Path(__file__).resolve().parents[2] / "rules" / "nav2"
CODES = (
    "MOTOR_LEFT_OVERHEAT",
    "MOTOR_LEFT_COMM_LINK",
    "WHEEL_ODOMETRY_SLIP",
    "LIDAR_SCAN_RATE",
    "CAMERA_FRONT_RATE",
    "IMU_STATUS",
    "ACTION_NAVIGATE_TO_POSE_ABORTED",
    "WIFI_SIGNAL",
    "bad code",
    "",
    "A..B",
)
SOURCES = ("/diagnostic_bridge", "/powertrain/motor_left", "/sensors/lidar", "")


def nav2_config() -> FaultManagerConfig:
    params = load_parameters([RULES / "fault_manager.yaml"])
    return fault_manager_config(params.node("fault_manager"))[0]


CONFIGS = {
    "defaults": FaultManagerConfig(),
    "healing": FaultManagerConfig(
        debounce=DebounceConfig(
            confirmation_threshold=-2, healing_enabled=True, healing_threshold=2
        ),
        entity_overrides=(EntityOverride(prefix="/powertrain", confirmation_threshold=-4),),
        near_miss_bound=3,
    ),
    "nav2": nav2_config(),
}


@dataclass(frozen=True)
class Step:
    kind: Literal["report", "clear"]
    dt_ns: int
    code: str
    event_type: int
    severity: int
    description: str
    source: str
    skip: bool


steps = st.builds(
    Step,
    st.sampled_from(["report"] * 9 + ["clear"]),
    st.integers(0, 2_000_000_000),
    st.sampled_from(CODES),
    st.sampled_from([0, 0, 1, 1, 1, 2]),
    st.sampled_from([0, 1, 2, 3, 4]),
    st.sampled_from(["", "hot", "cold"]),
    st.sampled_from(SOURCES),
    st.booleans(),
)


def spooled() -> EngineOutput:
    return EngineOutput(
        events=Spool(3, codec=EVENT_ROWS),
        transitions=Spool(3, codec=TRANSITION_ROWS),
        reports=Spool(3, codec=REPORT_ROWS),
        clears=Spool(3, codec=CLEAR_ROWS),
    )


def state(manager: FaultManager) -> tuple[object, ...]:
    out = manager.output
    correlation = manager.correlation
    return (
        list(out.reports),
        list(out.events),
        list(out.transitions),
        list(out.clears),
        out.retroactive_mutes,
        out.warnings,
        out.event_counts,
        out.published_by_code,
        out.withheld_by_code,
        out.reports_accepted,
        manager.faults(),
        {code: list(series) for code, series in manager.storage.near_misses.items()},
        (correlation.muted_faults(), correlation.clusters()) if correlation else None,
    )


@pytest.mark.parametrize("config", list(CONFIGS), ids=list(CONFIGS))
@pytest.mark.parametrize("rows", ["lists", "spools"])
@settings(max_examples=120, suppress_health_check=[HealthCheck.too_slow], deadline=None)
@given(sequence=st.lists(steps, max_size=60))
def test_report_fields_does_what_report_does(config: str, rows: str, sequence: list[Step]) -> None:
    reference = FaultManager(CONFIGS[config])
    fast = FaultManager(CONFIGS[config], spooled() if rows == "spools" else None)
    if rows == "spools":  # the replay's own wiring: rows straight into the spools' tails
        assert isinstance(fast.output.reports, Spool)
        assert isinstance(fast.output.events, Spool)
        assert isinstance(fast.output.transitions, Spool)
        fast.set_row_sinks(
            fast.output.reports.row_sink(),
            fast.output.events.row_sink(),
            fast.output.transitions.row_sink(),
        )
    t_ns = 1_000_000_000
    origin: Origin = "diagnostic_bridge"
    for step in sequence:
        t_ns += step.dt_ns
        reference.cleanup_tick(t_ns)
        fast.cleanup_tick(t_ns)
        if step.kind == "clear":
            request = ClearRequest(
                t_ns=t_ns, fault_code=step.code, skip_correlation_auto_clear=step.skip
            )
            assert reference.clear(request) == fast.clear(request)
            continue
        oracle_report(
            reference,
            ReportRequest(
                t_ns=t_ns,
                fault_code=step.code,
                event_type=step.event_type,
                severity=step.severity,
                description=step.description,
                source_id=step.source,
                origin=origin,
                topic="/diagnostics",
            ),
        )
        fast.report_fields(
            t_ns,
            origin,
            "/diagnostics",
            step.code,
            step.event_type,
            step.severity,
            step.description,
            step.source,
        )
        for log in (fast.output.reports, fast.output.events, fast.output.transitions):
            if isinstance(log, Spool):
                log.settle()
    assert state(fast) == state(reference)


# -- bridges: feed against the plain oracles ------------------------------------------------------


def _new(msgtype: str, /, **fields: Any) -> Any:
    return TS.types[msgtype](**fields)


def _kv(key: str, value: str) -> object:
    return _new("diagnostic_msgs/msg/KeyValue", key=key, value=value)


def _status(level: int, name: str, message: str, hardware_id: str, code: str) -> object:
    return _new(
        "diagnostic_msgs/msg/DiagnosticStatus",
        level=level,
        name=name,
        message=message,
        hardware_id=hardware_id,
        values=[_kv("code", code), _kv("x", "1")],
    )


def _array(statuses: list[object]) -> object:
    header = _new(
        "std_msgs/msg/Header",
        stamp=_new("builtin_interfaces/msg/Time", sec=1, nanosec=0),
        frame_id="",
    )
    return _new("diagnostic_msgs/msg/DiagnosticArray", header=header, status=statuses)


statuses = st.builds(
    _status,
    st.sampled_from([0, 0, 0, 1, 2, 3, 7, -1]),
    st.sampled_from(["motor: Temp", "lidar: Rate", "wifi", "***", "mapped name"]),
    st.sampled_from(["OK", "hot", ""]),
    st.sampled_from(["", "/hw/motor", "hw"]),
    st.sampled_from(["", "KV_CODE"]),
)
DIAG_CONFIGS = {
    "defaults": DiagnosticBridgeConfig(),
    "mapped": DiagnosticBridgeConfig(
        name_to_code={"mapped name": "MAPPED", "wifi": ""},
        use_hardware_id_as_source_id=True,
        max_tracked_sources=2,
        local_filter=LocalFilterConfig(default_threshold=2, default_window_sec=0.5),
    ),
    "no_auto": DiagnosticBridgeConfig(auto_generate_codes=False, name_to_code={"wifi": "W"}),
    "keyvalue": DiagnosticBridgeConfig(keyvalue_codes=("code",)),
}


class Sink:
    def __init__(self) -> None:
        self.requests: list[tuple[object, ...]] = []

    def __call__(self, *fields: object) -> None:
        self.requests.append(fields)


@pytest.mark.parametrize("config", list(DIAG_CONFIGS), ids=list(DIAG_CONFIGS))
@settings(max_examples=80, suppress_health_check=[HealthCheck.too_slow], deadline=None)
@given(arrays=st.lists(st.lists(statuses, max_size=6), max_size=30))
def test_diagnostic_feed_does_what_the_oracle_does(config: str, arrays: list[list[object]]) -> None:
    reference = DiagnosticBridge(DIAG_CONFIGS[config])
    fast = DiagnosticBridge(DIAG_CONFIGS[config])
    expected: list[tuple[object, ...]] = []
    sink = Sink()
    for k, array in enumerate(arrays):
        msg = _array(array)
        expected += oracle_diagnostic(reference, k * 100_000_000, "/diagnostics", msg)
        fast.feed(k * 100_000_000, "/diagnostics", msg, sink)
    assert sink.requests == expected


logs = st.builds(
    lambda level, name, text: TS.types["rcl_interfaces/msg/Log"](
        stamp=TS.types["builtin_interfaces/msg/Time"](sec=1, nanosec=0),
        level=level,
        name=name,
        msg=text,
        file="f",
        function="g",
        line=1,
    ),
    st.sampled_from([10, 20, 30, 40, 50, 25, 60]),
    st.sampled_from(["planner", "ns.controller", "fault_manager", "log_bridge", ""]),
    st.sampled_from(["failed 1", "failed 2", "timeout", ""]),
)


@pytest.mark.parametrize(
    "config",
    [LogBridgeConfig(), LogBridgeConfig(severity_floor=0, report_cooldown_sec=0.0)],
    ids=["defaults", "floor0"],
)
@settings(max_examples=80, suppress_health_check=[HealthCheck.too_slow], deadline=None)
@given(messages=st.lists(logs, max_size=40))
def test_log_feed_does_what_the_oracle_does(
    config: LogBridgeConfig, messages: list[object]
) -> None:
    reference, fast = LogBridge(config), LogBridge(config)
    expected: list[tuple[object, ...]] = []
    sink = Sink()
    for k, msg in enumerate(messages):
        expected += oracle_log(reference, k * 300_000_000, "/rosout", msg)
        fast.feed(k * 300_000_000, "/rosout", msg, sink)
    assert sink.requests == expected
