"""The diagnostic bridge at ros2_medkit 0.6.0 (bdcc4ed0): upstream's tests of that commit whose
behaviour later changed, as data, and each 0.6.0 difference beside 0.7.0 on the same input.

0.6.0 has no ``keyvalue_codes`` (71b1a79e, #527) and no ``use_hardware_id_as_source_id`` or
``max_tracked_sources`` (56d85b83, #622): codes come from names, and every status reports as
the bridge itself through one reporter, so one LocalFilter history per code.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, cast

import pytest

from medkit_replay.bridges.diagnostic import DiagnosticBridge, DiagnosticBridgeConfig
from medkit_replay.config.bridges import diagnostic_bridge_config
from medkit_replay.errors import ConfigError
from medkit_replay.model import NS_PER_SEC
from medkit_replay.releases import release_named
from tests.bridges.messages import ERROR, OK, STALE, WARN, diag
from tests.bridges.test_diagnostic_bridge import BRIDGE_FQN, failed, passed, send

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence

    from medkit_replay.bridges.diagnostic import DiagnosticStatusLike
    from medkit_replay.model import ReportRequest
    from medkit_replay.releases import Release

S = NS_PER_SEC
R060, R070 = release_named("0.6.0"), release_named("0.7.0")


def configured(params: Mapping[str, object], release: Release) -> DiagnosticBridge:
    config, _ = diagnostic_bridge_config(params, release)
    return DiagnosticBridge(config)


def request(
    code: str, t_ns: int, severity: int | None, description: str = "", source: str = BRIDGE_FQN
) -> ReportRequest:
    """A FAILED request, or a PASSED one when ``severity`` is None."""
    if severity is None:
        return passed(code, t_ns, source)
    return failed(code, t_ns, severity, description, source)


# --- Ported: DiagnosticBridgeTest.MapToFaultCode_* @bdcc4ed0 took the name alone ----------------

# Each status also carries a ``code`` KeyValue, and the config asks for it: 0.6.0 has no such
# parameter, so the name decides, as the name-only signature of these tests says.
CODE_FROM_NAME = [
    ("MapToFaultCode_AutoGenerate", "motor temp", "MOTOR_TEMP"),
    ("MapToFaultCode_AutoGenerate", "motor_temperature", "MOTOR_TEMPERATURE"),
    ("MapToFaultCode_AutoGenerate", "motor: Status", "MOTOR_STATUS"),
    ("MapToFaultCode_AutoGenerate", "/robot/sensor", "ROBOT_SENSOR"),
    ("MapToFaultCode_SpecialCharacters", "motor::temp", "MOTOR_TEMP"),
    ("MapToFaultCode_SpecialCharacters", "motor  temp", "MOTOR_TEMP"),
    ("MapToFaultCode_SpecialCharacters", "motor - temp", "MOTOR_TEMP"),
    ("MapToFaultCode_LeadingTrailing", "/motor", "MOTOR"),
    ("MapToFaultCode_LeadingTrailing", "motor/", "MOTOR"),
    ("MapToFaultCode_LeadingTrailing", "  motor  ", "MOTOR"),
]


@pytest.mark.parametrize(("upstream_test", "name", "code"), CODE_FROM_NAME)
def test_map_to_fault_code_takes_the_name_at_060(upstream_test: str, name: str, code: str) -> None:
    bridge = configured({"keyvalue_codes": ["code"]}, R060)
    status = diag(name, WARN, values={"code": "FROM_VALUES"})
    assert bridge.map_to_fault_code(cast("DiagnosticStatusLike", status)) == code, upstream_test


# --- Ported: test_integration.test.py @bdcc4ed0 (hardware_id 'test_hw', 0.5 s between sends) ----

Send = tuple[float, str, int, str]
"""Seconds, status name, level, message."""
Expected = tuple[float, str, "int | None", str]
"""Seconds, code, severity (None: PASSED), description."""
M = "Test message"  # publish_diagnostic's default message

INTEGRATION: list[tuple[str, list[Send], list[Expected]]] = [
    (
        "test_01_error_diagnostic_creates_fault",
        [(0.0, "test_sensor", ERROR, "Sensor failure")],
        [(0.0, "TEST_SENSOR", 2, "Sensor failure")],
    ),
    (
        "test_02_warn_diagnostic_creates_fault",
        [(t, "warning_component", WARN, "Low battery") for t in (0.0, 0.5, 1.0)],
        [(1.0, "WARNING_COMPONENT", 1, "Low battery")],
    ),
    (
        "test_03_stale_diagnostic_creates_critical_fault",
        [(0.0, "stale_sensor", STALE, "No data")],
        [(0.0, "STALE_SENSOR", 3, "No data")],
    ),
    (
        "test_04_ok_diagnostic_heals_fault",
        [(0.0, "healing_test", ERROR, "Error")]
        + [(t, "healing_test", OK, M) for t in (0.5, 1.0, 1.5, 2.0)],
        [
            (0.0, "HEALING_TEST", 2, "Error"),
            (1.5, "HEALING_TEST", None, ""),
            (2.0, "HEALING_TEST", None, ""),
        ],
    ),
    (
        "test_05_fault_code_generation",
        [
            (0.0, "motor temp", ERROR, M),
            (0.5, "sensor: status", ERROR, M),
            (1.0, "/robot/arm", ERROR, M),
        ],
        [(0.0, "MOTOR_TEMP", 2, M), (0.5, "SENSOR_STATUS", 2, M), (1.0, "ROBOT_ARM", 2, M)],
    ),
]


@pytest.mark.parametrize(("upstream_test", "sends", "expected"), INTEGRATION)
def test_integration_stimuli_at_060(
    upstream_test: str, sends: Sequence[Send], expected: Sequence[Expected]
) -> None:
    params = {"diagnostics_topic": "/diagnostics", "auto_generate_codes": True}
    bridge = configured(params, R060)
    out: list[ReportRequest] = []
    for seconds, name, level, message in sends:
        status = diag(name, level, message, hardware_id="test_hw")
        out += send(bridge, round(seconds * S), status)
    assert out == [
        request(code, round(seconds * S), severity, description)
        for seconds, code, severity, description in expected
    ], upstream_test


# --- B1: keyvalue_codes, 0.6.0 beside 0.7.0 -------------------------------------------------


def test_keyvalue_codes_is_not_a_parameter_at_060() -> None:
    params = {"keyvalue_codes": ["code"]}
    motor = diag("/motor", ERROR, "hot", values={"code": "MOTOR_FAULT"})
    assert send(configured(params, R060), 1, motor) == [request("MOTOR", 1, 2, "hot")]
    assert send(configured(params, R070), 1, motor) == [request("MOTOR_FAULT", 1, 2, "hot")]


def test_a_keyvalue_code_that_would_skip_the_status_does_not_at_060() -> None:
    params = {"keyvalue_codes": ["code"]}
    motor = diag("/motor", ERROR, "hot", values={"code": ""})
    assert send(configured(params, R060), 1, motor) == [request("MOTOR", 1, 2, "hot")]
    assert send(configured(params, R070), 1, motor) == []


def test_a_mistyped_keyvalue_codes_stops_only_the_070_node() -> None:
    config, warnings = diagnostic_bridge_config({"keyvalue_codes": 5}, R060)
    assert (config, warnings) == (DiagnosticBridgeConfig(), [])
    with pytest.raises(ConfigError, match="'keyvalue_codes'"):
        diagnostic_bridge_config({"keyvalue_codes": 5}, R070)


# --- B2: sources and reporters, 0.6.0 beside 0.7.0 ------------------------------------------

HW = {"use_hardware_id_as_source_id": True}


def test_hardware_id_is_never_the_source_at_060() -> None:
    lidar = diag("shared_sensor", STALE, "x", hardware_id="/my_lidar_driver")
    camera = diag("shared_sensor", STALE, "x", hardware_id="/my_camera_driver")
    old, new = configured(HW, R060), configured(HW, R070)
    assert send(old, 1, lidar) + send(old, 2, camera) == [
        request("SHARED_SENSOR", 1, 3, "x"),
        request("SHARED_SENSOR", 2, 3, "x"),
    ]
    assert send(new, 1, lidar) + send(new, 2, camera) == [
        request("SHARED_SENSOR", 1, 3, "x", source="/my_lidar_driver"),
        request("SHARED_SENSOR", 2, 3, "x", source="/my_camera_driver"),
    ]


def test_one_reporter_pools_the_warn_counts_of_every_hardware_id_at_060() -> None:
    warns = [diag("x", WARN, "w", hardware_id=h) for h in ("/a", "/b", "/a")]
    assert send(configured(HW, R060), 1, *warns) == [request("X", 1, 1, "w")]
    assert send(configured(HW, R070), 1, *warns) == []  # /a has 2, /b has 1


def test_max_tracked_sources_is_not_a_parameter_at_060() -> None:
    params = {**HW, "max_tracked_sources": 0}
    config, warnings = diagnostic_bridge_config(params, R060)
    assert (config.use_hardware_id_as_source_id, config.max_tracked_sources) == (False, 512)
    assert warnings == []
    config, warnings = diagnostic_bridge_config(params, R070)
    assert (config.use_hardware_id_as_source_id, config.max_tracked_sources) == (True, 1)
    assert warnings == ["diagnostic_bridge: max_tracked_sources=0 clamped to 1"]


@pytest.mark.parametrize(
    ("name", "value"), [("use_hardware_id_as_source_id", "yes"), ("max_tracked_sources", 2.0)]
)
def test_mistyped_source_parameters_stop_only_the_070_node(name: str, value: object) -> None:
    assert diagnostic_bridge_config({name: value}, R060) == (DiagnosticBridgeConfig(), [])
    with pytest.raises(ConfigError, match=f"'{name}'"):
        diagnostic_bridge_config({name: value}, R070)


def test_the_parameters_both_releases_share_are_read_alike() -> None:
    params: dict[str, object] = {
        "diagnostics_topic": "/robot/diag",
        "auto_generate_codes": False,
        "name_to_code.motor temp": "MOTOR_HOT",
        "fault_reporter.local_filtering.default_threshold": 2,
        "fault_reporter.local_filtering.bypass_severity": 3,
    }
    old, _ = diagnostic_bridge_config(params, R060)
    new, _ = diagnostic_bridge_config(params, R070)
    assert old == new
    assert old.local_filter.default_threshold == 2
