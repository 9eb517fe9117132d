"""Ports of upstream's diagnostic bridge tests (bridges.md §8.2, D1-D22 and DI1-DI7).

Also the per-source LocalFilter of §2.1/§2.4: counts kept per reporter, lost on LRU eviction.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, cast

import pytest

from medkit_replay.bridges.diagnostic import (
    DiagnosticBridge,
    DiagnosticBridgeConfig,
    is_ok_level,
    map_to_severity,
)
from medkit_replay.config.bridges import diagnostic_bridge_config
from medkit_replay.engine.local_filter import LocalFilterConfig
from medkit_replay.errors import ConfigError
from medkit_replay.model import NS_PER_SEC, EventType, ReportRequest
from tests.bridges.messages import DIAGNOSTIC_ARRAY, ERROR, OK, STALE, WARN, diag, diag_array

if TYPE_CHECKING:
    from collections.abc import Mapping

    from rosbags.typesys.store import Msg

    from medkit_replay.bridges.diagnostic import DiagnosticStatusLike

S = NS_PER_SEC
TOPIC = "/diagnostics"
BRIDGE_FQN = "/diagnostic_bridge"


def status(msg: Msg) -> DiagnosticStatusLike:
    return cast("DiagnosticStatusLike", msg)


def send(bridge: DiagnosticBridge, t_ns: int, *statuses: Msg) -> list[ReportRequest]:
    return bridge.on_message(t_ns, TOPIC, diag_array(*statuses))


def failed(
    code: str, t_ns: int, severity: int, description: str = "", source: str = BRIDGE_FQN
) -> ReportRequest:
    return ReportRequest(
        t_ns=t_ns,
        fault_code=code,
        event_type=EventType.FAILED,
        severity=severity,
        description=description,
        source_id=source,
        origin="diagnostic_bridge",
        topic=TOPIC,
    )


def passed(code: str, t_ns: int, source: str = BRIDGE_FQN) -> ReportRequest:
    return ReportRequest(
        t_ns=t_ns,
        fault_code=code,
        event_type=EventType.PASSED,
        severity=0,
        description="",
        source_id=source,
        origin="diagnostic_bridge",
        topic=TOPIC,
    )


def configured(params: Mapping[str, object]) -> DiagnosticBridge:
    config, _ = diagnostic_bridge_config(params)
    return DiagnosticBridge(config)


HW: dict[str, object] = {"use_hardware_id_as_source_id": True}


# --- D1-D8: severity mapping and node identity ---


@pytest.mark.parametrize(
    ("test_id", "level", "severity"),
    [("D1", 1, 1), ("D2", 2, 2), ("D3", 3, 3), ("D4", 0, None), ("D5", 99, 2), ("-", 255, 2)],
)
def test_d1_d5_map_to_severity(test_id: str, level: int, severity: int | None) -> None:
    assert map_to_severity(level) == severity, test_id


def test_d6_is_ok_level_true() -> None:
    assert is_ok_level(0)


@pytest.mark.parametrize("level", [1, 2, 3])
def test_d7_is_ok_level_false(level: int) -> None:
    assert not is_ok_level(level)


def test_d8_node_name() -> None:
    assert DiagnosticBridge.name == "diagnostic_bridge"
    assert DiagnosticBridge().origin == "diagnostic_bridge"


# --- D9-D12: sources and the reporter cache ---


def test_d9_source_id_defaults_to_bridge_fqn() -> None:
    bridge = DiagnosticBridge()
    sensor = diag("sensor", ERROR, "down", hardware_id="/sensor_node")
    assert bridge.source_id_for(status(sensor)) == BRIDGE_FQN
    assert send(bridge, 1, sensor) == [failed("SENSOR", 1, 2, "down")]


@pytest.mark.parametrize("hardware_id", ["/sensor_node", "a/b"])
def test_d10_source_id_uses_slash_containing_hardware_id_when_enabled(hardware_id: str) -> None:
    bridge = configured(HW)
    sensor = diag("sensor", ERROR, "down", hardware_id=hardware_id)
    assert bridge.source_id_for(status(sensor)) == hardware_id
    assert send(bridge, 1, sensor) == [failed("SENSOR", 1, 2, "down", source=hardware_id)]


@pytest.mark.parametrize("hardware_id", ["SERIAL123", ""])
def test_d11_non_slash_hardware_id_falls_back_to_bridge_fqn(hardware_id: str) -> None:
    bridge = configured(HW)
    assert bridge.source_id_for(status(diag("s", ERROR, hardware_id=hardware_id))) == BRIDGE_FQN


def test_d12_reporter_cache_is_bounded() -> None:
    bridge = configured({"max_tracked_sources": 2})
    assert len(bridge.reporters) == 0
    bridge.reporters.get("/source_a")
    bridge.reporters.get("/source_b")
    assert len(bridge.reporters) == 2
    bridge.reporters.get("/source_c")
    assert len(bridge.reporters) == 2
    assert "/source_a" not in bridge.reporters
    assert "/source_b" in bridge.reporters


def test_d12_reporter_cache_through_messages() -> None:
    bridge = configured({**HW, "max_tracked_sources": 2})
    for source in ("/source_a", "/source_b", "/source_c"):
        send(bridge, 1, diag("s", ERROR, hardware_id=source))
    assert len(bridge.reporters) == 2
    assert "/source_a" not in bridge.reporters


def test_reporter_cache_returns_the_same_reporter() -> None:
    bridge = DiagnosticBridge()
    assert bridge.reporters.get("/x") is bridge.reporters.get("/x")


# --- D13-D22: fault codes ---


@pytest.mark.parametrize(
    ("name", "code"),
    [
        ("motor temp", "MOTOR_TEMP"),
        ("motor_temperature", "MOTOR_TEMPERATURE"),
        ("motor: Status", "MOTOR_STATUS"),
        ("/robot/sensor", "ROBOT_SENSOR"),
    ],
)
def test_d13_map_to_fault_code_auto_generate(name: str, code: str) -> None:
    assert DiagnosticBridge().map_to_fault_code(status(diag(name, WARN))) == code


@pytest.mark.parametrize("name", ["motor::temp", "motor  temp", "motor - temp"])
def test_d14_map_to_fault_code_special_characters(name: str) -> None:
    assert DiagnosticBridge().map_to_fault_code(status(diag(name, WARN))) == "MOTOR_TEMP"


@pytest.mark.parametrize("name", ["/motor", "motor/", "  motor  "])
def test_d15_map_to_fault_code_leading_trailing(name: str) -> None:
    assert DiagnosticBridge().map_to_fault_code(status(diag(name, WARN))) == "MOTOR"


def test_d16_map_to_fault_code_from_attribute() -> None:
    bridge = configured({"keyvalue_codes": ["code"]})
    motor = diag("/motor", WARN, "hot", values={"code": "MOTOR_FAULT"})
    assert bridge.map_to_fault_code(status(motor)) == "MOTOR_FAULT"


def test_d16_end_to_end_warn_needs_three_within_the_window() -> None:
    bridge = configured({"keyvalue_codes": ["code"]})
    motor = diag("/motor", WARN, "hot", values={"code": "MOTOR_FAULT"})
    assert send(bridge, 0, motor) == []
    assert send(bridge, 1 * S, motor) == []
    assert send(bridge, 2 * S, motor) == [failed("MOTOR_FAULT", 2 * S, 1, "hot")]
    assert send(bridge, 3 * S, motor) == [failed("MOTOR_FAULT", 3 * S, 1, "hot")]


def test_d17_key_configured_but_missing_falls_back_to_auto_generate() -> None:
    bridge = configured({"keyvalue_codes": ["fault_code", "error_id"]})
    motor = diag("/motor", WARN, values={"code": "MOTOR_FAULT"})
    assert bridge.map_to_fault_code(status(motor)) == "MOTOR"


def test_d18_key_missing_and_auto_generate_disabled_skips_the_status() -> None:
    bridge = configured(
        {"keyvalue_codes": ["fault_code", "error_id"], "auto_generate_codes": False}
    )
    motor = diag("/motor", ERROR, values={"code": "MOTOR_FAULT"})
    assert bridge.map_to_fault_code(status(motor)) == ""
    assert send(bridge, 1, motor) == []
    assert len(bridge.reporters) == 0  # skipped before any reporter is looked up


KEYS = ["primary_code", "secondary_code", "tertiary_code"]


def test_d19_multiple_configured_keys_use_configured_key_order() -> None:
    values = [("secondary_code", "SECOND"), ("primary_code", "PRIMARY"), ("tertiary_code", "T")]
    bridge = configured({"keyvalue_codes": KEYS})
    assert bridge.map_to_fault_code(status(diag("/m", WARN, values=values))) == "PRIMARY"


def test_d20_reordered_attributes_still_use_configured_order() -> None:
    values = [("tertiary_code", "T"), ("primary_code", "PRIMARY"), ("secondary_code", "SECOND")]
    bridge = configured({"keyvalue_codes": KEYS})
    assert bridge.map_to_fault_code(status(diag("/m", WARN, values=values))) == "PRIMARY"


def test_d21_empty_configured_keys_are_ignored() -> None:
    config, _ = diagnostic_bridge_config({"keyvalue_codes": ["", "", "code"]})
    assert config.keyvalue_codes == ("code",)
    motor = diag("/motor", WARN, values=[("", "EMPTY_KEY"), ("code", "MOTOR_FAULT")])
    assert DiagnosticBridge(config).map_to_fault_code(status(motor)) == "MOTOR_FAULT"


def test_d22_name_to_code_override_precedes_keyvalue_codes() -> None:
    bridge = configured({"keyvalue_codes": ["code"], "name_to_code./motor": "OVERRIDE_CODE"})
    motor = diag("/motor", WARN, values={"code": "FROM_ATTRIBUTE"})
    assert bridge.map_to_fault_code(status(motor)) == "OVERRIDE_CODE"


def test_first_key_value_with_the_key_wins_even_if_empty() -> None:
    # [inferred] §2.3: an empty value is returned verbatim, so the status is skipped.
    bridge = configured({"keyvalue_codes": ["code"]})
    motor = diag("/motor", ERROR, values=[("code", ""), ("code", "LATER")])
    assert bridge.map_to_fault_code(status(motor)) == ""
    assert send(bridge, 1, motor) == []


def test_name_to_code_is_exact_verbatim_and_case_sensitive() -> None:
    bridge = configured({"name_to_code.motor: Temp.x": "raw code!", "name_to_code.n": 5})
    assert bridge.map_to_fault_code(status(diag("motor: Temp.x", WARN))) == "raw code!"
    assert bridge.map_to_fault_code(status(diag("Motor: Temp.x", WARN))) == "MOTOR_TEMP_X"
    assert bridge.map_to_fault_code(status(diag("n", WARN))) == "N"  # non-string ignored


def test_empty_or_separator_name_is_skipped() -> None:
    bridge = DiagnosticBridge()
    assert send(bridge, 1, diag("", ERROR), diag("---", ERROR)) == []


# --- DI1-DI7: the integration stimuli, offline ---


def test_di1_error_is_forwarded_at_once() -> None:
    bridge = configured(HW)
    sensor = diag("test_sensor", ERROR, "Sensor failure", hardware_id="test_hw")
    assert send(bridge, 1, sensor) == [failed("TEST_SENSOR", 1, 2, "Sensor failure")]


def test_di2_warn_appears_after_three_within_ten_seconds() -> None:
    bridge = configured(HW)
    warn = diag("warning_component", WARN, "Low battery", hardware_id="test_hw")
    times = [0, 3 * S // 10, 6 * S // 10]
    out = [send(bridge, t, warn) for t in times]
    expected = failed("WARNING_COMPONENT", times[2], 1, "Low battery")
    assert out == [[], [], [expected]]


def test_di3_stale_is_critical() -> None:
    bridge = configured(HW)
    stale = diag("stale_sensor", STALE, "No data", hardware_id="test_hw")
    assert send(bridge, 1, stale) == [failed("STALE_SENSOR", 1, 3, "No data")]


def test_di4_ok_heals_from_the_third_ok() -> None:
    bridge = configured(HW)
    assert send(bridge, 0, diag("healing_test", ERROR, "bad")) == [
        failed("HEALING_TEST", 0, 2, "bad")
    ]
    ok = diag("healing_test", OK, "fine")
    out = [send(bridge, k * S // 3, ok) for k in range(1, 5)]
    assert out == [[], [], [passed("HEALING_TEST", S)], [passed("HEALING_TEST", 4 * S // 3)]]


def test_di5_several_names_in_one_array_in_order() -> None:
    bridge = configured(HW)
    out = send(bridge, 1, *(diag(n, ERROR) for n in ("motor temp", "sensor: status", "/robot/arm")))
    assert [r.fault_code for r in out] == ["MOTOR_TEMP", "SENSOR_STATUS", "ROBOT_ARM"]


def test_di6_one_code_from_two_hardware_sources() -> None:
    bridge = configured(HW)
    lidar = diag("shared_sensor", STALE, "x", hardware_id="/my_lidar_driver")
    camera = diag("shared_sensor", STALE, "x", hardware_id="/my_camera_driver")
    assert send(bridge, 1, lidar) + send(bridge, 2, camera) == [
        failed("SHARED_SENSOR", 1, 3, "x", source="/my_lidar_driver"),
        failed("SHARED_SENSOR", 2, 3, "x", source="/my_camera_driver"),
    ]


def test_di7_empty_hardware_id_reports_as_the_bridge() -> None:
    bridge = configured(HW)
    [report] = send(bridge, 1, diag("fallback_sensor", STALE, hardware_id=""))
    assert report.source_id == BRIDGE_FQN


# --- The per-source LocalFilter (§2.1, §2.4) ---


def warn_from(source: str, name: str = "x") -> Msg:
    return diag(name, WARN, "w", hardware_id=source)


def test_each_source_has_its_own_filter_counts() -> None:
    bridge = configured(HW)
    assert send(bridge, 1, warn_from("/a"), warn_from("/b"), warn_from("/a"), warn_from("/b")) == []
    assert send(bridge, 2, warn_from("/a")) == [failed("X", 2, 1, "w", source="/a")]
    assert send(bridge, 3, warn_from("/b")) == [failed("X", 3, 1, "w", source="/b")]


def test_eviction_forgets_the_filter_counts() -> None:
    bridge = configured({**HW, "max_tracked_sources": 1})
    assert send(bridge, 1, warn_from("/a"), warn_from("/a")) == []
    assert send(bridge, 2, warn_from("/b")) == []  # evicts /a with its two counts
    assert send(bridge, 3, warn_from("/a")) == []  # a fresh reporter: count 1
    assert send(bridge, 4, warn_from("/a")) == []
    assert send(bridge, 5, warn_from("/a")) == [failed("X", 5, 1, "w", source="/a")]


def test_lookup_refreshes_recency() -> None:
    bridge = configured({**HW, "max_tracked_sources": 2})
    send(bridge, 1, warn_from("/a"), warn_from("/a"), warn_from("/b"))
    send(bridge, 2, diag("y", OK, hardware_id="/a"))  # an OK touches /a too
    send(bridge, 3, warn_from("/c"))  # evicts /b, the least recently used
    assert "/b" not in bridge.reporters
    assert send(bridge, 4, warn_from("/a")) == [failed("X", 4, 1, "w", source="/a")]


def test_window_keeps_a_time_exactly_at_the_cutoff() -> None:
    bridge = DiagnosticBridge()
    for t in (0, 5 * S):
        assert send(bridge, t, warn_from("")) == []
    assert send(bridge, 10 * S, warn_from("")) == [failed("X", 10 * S, 1, "w")]
    late = DiagnosticBridge()
    for t in (0, 5 * S):
        send(late, t, warn_from(""))
    assert send(late, 10 * S + 1, warn_from("")) == []


def test_bypassed_errors_do_not_count_towards_warns() -> None:
    bridge = DiagnosticBridge()
    out = send(bridge, 1, warn_from(""), diag("x", ERROR, "e"), warn_from(""))
    assert out == [failed("X", 1, 2, "e")]
    assert send(bridge, 2, warn_from("")) == [failed("X", 2, 1, "w")]


def test_passed_and_failed_are_counted_apart() -> None:
    bridge = DiagnosticBridge()
    ok = diag("x", OK)
    assert send(bridge, 1, warn_from(""), ok, warn_from(""), ok) == []
    assert send(bridge, 2, warn_from(""), ok) == [failed("X", 2, 1, "w"), passed("X", 2)]


def test_filter_parameters_apply_to_every_reporter() -> None:
    bridge = configured({"fault_reporter.local_filtering.enabled": False})
    assert send(bridge, 1, warn_from(""), diag("x", OK)) == [failed("X", 1, 1, "w"), passed("X", 1)]
    strict = configured({"fault_reporter.local_filtering.bypass_severity": 3})
    assert send(strict, 1, diag("x", ERROR, "e")) == []


# --- Topic selection and parameters (§2.5) ---


def test_wants_the_configured_topic_and_type() -> None:
    bridge = DiagnosticBridge()
    assert bridge.wants("/diagnostics", DIAGNOSTIC_ARRAY)
    assert not bridge.wants("/diagnostics_agg", DIAGNOSTIC_ARRAY)
    assert not bridge.wants("/diagnostics", "std_msgs/msg/String")
    assert configured({"diagnostics_topic": "/robot/diag"}).wants("/robot/diag", DIAGNOSTIC_ARRAY)


def test_relative_topic_and_source_follow_the_node_namespace() -> None:
    config = DiagnosticBridgeConfig(diagnostics_topic="diagnostics")
    bridge = DiagnosticBridge(config, node_fqn="/robot1/diagnostic_bridge")
    assert bridge.topic == "/robot1/diagnostics"
    assert DiagnosticBridge(config).topic == "/diagnostics"
    [report] = bridge.on_message(1, "/robot1/diagnostics", diag_array(diag("s", ERROR)))
    assert report.source_id == "/robot1/diagnostic_bridge"
    assert report.topic == "/robot1/diagnostics"


def test_parameter_defaults() -> None:
    config, warnings = diagnostic_bridge_config({})
    assert config == DiagnosticBridgeConfig()
    assert config.local_filter == LocalFilterConfig()
    assert warnings == []


@pytest.mark.parametrize(
    ("value", "used", "warning"),
    [
        (0, 1, "diagnostic_bridge: max_tracked_sources=0 clamped to 1"),
        (-5, 1, "diagnostic_bridge: max_tracked_sources=-5 clamped to 1"),
        (
            2**31,
            2**31 - 1,
            "diagnostic_bridge: max_tracked_sources=2147483648 clamped to 2147483647",
        ),
    ],
)
def test_max_tracked_sources_is_clamped(value: int, used: int, warning: str) -> None:
    config, warnings = diagnostic_bridge_config({"max_tracked_sources": value})
    assert config.max_tracked_sources == used
    assert warnings == [warning]


def test_local_filter_parameters_are_narrowed_like_the_reporter() -> None:
    config, warnings = diagnostic_bridge_config(
        {
            "fault_reporter.local_filtering.default_threshold": 2**32 + 2,
            "fault_reporter.local_filtering.default_window_sec": 2.5,
            "fault_reporter.local_filtering.bypass_severity": 256 + 3,
        }
    )
    assert warnings == []
    assert config.local_filter == LocalFilterConfig(
        default_threshold=2, default_window_sec=2.5, bypass_severity=3
    )


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("diagnostics_topic", 5),
        ("auto_generate_codes", "true"),
        ("use_hardware_id_as_source_id", None),
        ("max_tracked_sources", 1.5),
        ("max_tracked_sources", 2**63),
        ("keyvalue_codes", [1, 2]),
        ("fault_reporter.local_filtering.default_window_sec", 10),
        ("fault_reporter.local_filtering.default_window_sec", float("nan")),
        ("fault_reporter.local_filtering.default_threshold", True),
    ],
)
def test_wrong_parameter_types_stop_the_node(name: str, value: object) -> None:
    with pytest.raises(ConfigError, match=f"'{name}'"):
        diagnostic_bridge_config({name: value})
