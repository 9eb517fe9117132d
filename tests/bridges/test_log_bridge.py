"""Ports of upstream's log bridge tests (bridges.md §8.3, L1-L31 and LI1-LI4).

Messages go through on_message where the pipeline order of §3.1 matters; helpers are tested alone.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import pytest

from medkit_replay.bridges.log import (
    LogBridge,
    LogBridgeConfig,
    is_medkit_stack_logger,
    map_level_to_severity,
    node_source_id,
)
from medkit_replay.config.bridges import log_bridge_config
from medkit_replay.errors import ConfigError
from medkit_replay.model import LOG_LEVEL_WARN, LOG_LEVELS, NS_PER_SEC, EventType, ReportRequest
from medkit_replay.result import Consumption, TopicUse
from tests.bridges.messages import LOG, log

if TYPE_CHECKING:
    from collections.abc import Mapping

S = NS_PER_SEC
TOPIC = "/rosout"
DEBUG, INFO, WARN, ERROR, FATAL = 10, 20, 30, 40, 50


def configured(params: Mapping[str, object]) -> LogBridge:
    config, _ = log_bridge_config(params)
    return LogBridge(config)


def send(bridge: LogBridge, t_ns: int, name: str, level: int, msg: str) -> list[ReportRequest]:
    return bridge.on_message(t_ns, TOPIC, log(name, level, msg))


def failed(code: str, t_ns: int, severity: int, description: str, source: str) -> ReportRequest:
    return ReportRequest(
        t_ns=t_ns,
        fault_code=code,
        event_type=EventType.FAILED,
        severity=severity,
        description=description,
        source_id=source,
        origin="log_bridge",
        topic=TOPIC,
    )


# --- L1-L4: level mapping ---


@pytest.mark.parametrize("level", [DEBUG, INFO])
def test_l1_debug_and_info_dropped(level: int) -> None:
    assert map_level_to_severity(level, 30) is None
    assert map_level_to_severity(level, 0) is None  # whatever the floor


def test_l2_warn_error_fatal() -> None:
    assert [map_level_to_severity(v, 30) for v in (WARN, ERROR, FATAL)] == [1, 2, 3]


def test_l3_floor_raised_to_error() -> None:
    assert map_level_to_severity(WARN, 40) is None
    assert map_level_to_severity(ERROR, 40) == 2


@pytest.mark.parametrize(("level", "floor"), [(45, 30), (25, 0), (35, 30), (60, 30), (255, 50)])
def test_l4_unknown_level_above_floor_treated_as_error(level: int, floor: int) -> None:
    assert map_level_to_severity(level, floor) == 2


def test_non_standard_level_below_floor_is_dropped() -> None:
    assert map_level_to_severity(25, 30) is None


# --- L5-L15: message templates and codes, through the bridge ---


def test_l5_l7_l8_templates_make_equal_codes() -> None:
    bridge = LogBridge()
    code = bridge.fault_code
    assert code("/n", "worldToMap failed: mx,my: 2200,2200") == code(
        "/n", "worldToMap failed: mx,my: 1500,1500"
    )
    assert code("/n", "connection lost to host A") == code("/n", "connection lost to host B")
    assert code("/n", "") == code("/n", "12345") == code("/n", "--- 0x1f ::")


def test_l6_numbers_and_hex_collapse_but_words_differ() -> None:
    code = LogBridge().fault_code
    acm0 = code("/n", "Failed to open /dev/ttyACM0 (errno 0x19)")
    assert acm0 == code("/n", "Failed to open /dev/ttyACM5 (errno 0x05)")
    assert acm0 != code("/n", "Failed to open /dev/ttyUSB0 (errno 0x19)")


def test_l10_generate_fault_code_stable_and_well_formed() -> None:
    code = LogBridge().fault_code
    first = code("/planner_server", "failed to create plan to (100.0, 100.0)")
    assert first == code("/planner_server", "failed to create plan to (5.0, 5.0)")
    assert first == "LOG_PLANNER_SERVER_ac8dd4db"


def test_l11_known_constant() -> None:
    assert LogBridge().fault_code("/ctrl", "oops 42") == "LOG_CTRL_0bf0b26e"


def test_l12_different_messages_differ() -> None:
    code = LogBridge().fault_code
    assert code("/ctrl", "command interface not available") == "LOG_CTRL_6fc3f7e3"
    assert code("/ctrl", "could not find controller") == "LOG_CTRL_8c6d058e"


def test_l13_empty_message_gets_sentinel() -> None:
    code = LogBridge().fault_code
    assert code("/ctrl", "") == code("/ctrl", "!!!") == "LOG_CTRL_a9b1099a"
    assert code("/ctrl", "actual failure") == "LOG_CTRL_81cad281"


def test_l14_namespace_disambiguates() -> None:
    code = LogBridge().fault_code
    assert code("/robot1/planner_server", "no plan").startswith("LOG_ROBOT1_PLANNER_SERVER_")
    assert code("/robot2/planner_server", "no plan").startswith("LOG_ROBOT2_PLANNER_SERVER_")


def test_l15_never_truncates_hash_long_node() -> None:
    code = LogBridge().fault_code("/" + "x" * 200 + "/planner_server", "boom")
    assert code == "LOG_" + "X" * 48 + "_c79493aa"


def test_configured_prefix_is_used() -> None:
    bridge = configured({"code_prefix": "my prefix"})
    assert bridge.fault_code("/ctrl", "oops") == "MY_PREFIX_CTRL_0bf0b26e"


# --- L16-L25: eligibility, medkit stack, sources ---


def test_l16_node_eligibility_default_allows() -> None:
    assert LogBridge().node_is_eligible("/any_node")


def test_l17_exclude_substring() -> None:
    bridge = configured({"exclude_nodes": ["chatty"]})
    assert not bridge.node_is_eligible("/chatty_logger")
    assert bridge.node_is_eligible("/planner_server")
    assert send(bridge, 1, "chatty_logger", ERROR, "x") == []


def test_l18_include_only_substring() -> None:
    bridge = configured({"include_only_nodes": ["planner"]})
    assert bridge.node_is_eligible("/planner_server")
    assert not bridge.node_is_eligible("/amcl")
    assert send(bridge, 1, "amcl", ERROR, "x") == []
    assert len(send(bridge, 1, "planner_server", ERROR, "x")) == 1


@pytest.mark.parametrize(
    "name",
    [
        "fault_manager",
        "robot1.fault_manager",
        "ros2_medkit_gateway",
        "diagnostic_bridge",
        "action_status_bridge",
    ],
)
def test_l19_medkit_stack_logger_matches_own_infra(name: str) -> None:
    assert is_medkit_stack_logger(name)


@pytest.mark.parametrize("name", ["bt_navigator", "robot1.controller_server", "amcl"])
def test_l20_medkit_stack_logger_allows_application_nodes(name: str) -> None:
    assert not is_medkit_stack_logger(name)


def test_l21_medkit_stack_skipped_by_default() -> None:
    bridge = LogBridge()
    assert send(bridge, 1, "fault_manager", ERROR, "boom") == []
    assert send(bridge, 1, "robot1.fault_manager", ERROR, "boom") == []
    assert send(bridge, 1, "bt_navigator", ERROR, "boom") == [
        failed("LOG_BT_NAVIGATOR_c79493aa", 1, 2, "boom", "/bt_navigator")
    ]


def test_l22_medkit_stack_toggle_disables() -> None:
    bridge = configured({"exclude_medkit_stack": False})
    assert send(bridge, 1, "fault_manager", ERROR, "boom") == [
        failed("LOG_FAULT_MANAGER_c79493aa", 1, 2, "boom", "/fault_manager")
    ]


def test_medkit_stack_matches_the_raw_logger_name() -> None:
    # "robot1.fault_manager" collapses to /robot1, yet is skipped: the raw name is checked.
    assert node_source_id("robot1.fault_manager") == "/robot1"
    assert send(LogBridge(), 1, "robot1.fault_manager", ERROR, "x") == []
    assert send(LogBridge(), 1, "my_fault_manager_x", ERROR, "x") == []


@pytest.mark.parametrize(
    ("name", "source"),
    [
        ("bt_navigator", "/bt_navigator"),  # L23
        ("planner_server", "/planner_server"),  # L23
        ("/amcl", "/amcl"),  # L24
        ("controller_manager.resource_manager", "/controller_manager"),  # L25
        ("robot1.planner_server", "/robot1"),
        ("", "/"),
        (".foo", "/.foo"),
    ],
)
def test_l23_l25_node_source_id(name: str, source: str) -> None:
    assert node_source_id(name) == source


def test_own_logs_are_never_promoted() -> None:
    bridge = configured({"exclude_medkit_stack": False})
    assert send(bridge, 1, "log_bridge", ERROR, "x") == []
    assert send(bridge, 1, "log_bridge.sub", ERROR, "x") == []
    renamed = LogBridge(node_fqn="/robot1/logs")
    assert send(renamed, 1, "/robot1/logs", ERROR, "x") == []
    assert send(renamed, 1, "log_bridge", ERROR, "x") == []


# --- L26-L28: ERROR/FATAL cooldown on bag time ---


def test_l26_cooldown_first_passes_then_suppressed_then_reopens() -> None:
    bridge = LogBridge()
    assert bridge.cooldown_allows("LOG_X_aaaa1111", 2, 0)
    assert not bridge.cooldown_allows("LOG_X_aaaa1111", 2, 1 * S)
    assert bridge.cooldown_allows("LOG_X_bbbb2222", 2, 1 * S)
    assert bridge.cooldown_allows("LOG_X_aaaa1111", 2, 6 * S)


def test_l27_cooldown_keyed_by_severity_escalation_not_suppressed() -> None:
    bridge = LogBridge()
    assert bridge.cooldown_allows("LOG_X_aaaa1111", 2, 0)
    assert bridge.cooldown_allows("LOG_X_aaaa1111", 3, 1 * S)
    assert not bridge.cooldown_allows("LOG_X_aaaa1111", 2, 1 * S)


def test_l28_cooldown_zero_disables() -> None:
    bridge = configured({"report_cooldown_sec": 0.0})
    assert bridge.cooldown_allows("LOG_X_aaaa1111", 2, 0)
    assert bridge.cooldown_allows("LOG_X_aaaa1111", 2, 0)


def test_cooldown_window_edge_passes_and_suppressed_lines_do_not_extend_it() -> None:
    bridge = LogBridge()
    out = [send(bridge, t, "ctrl", ERROR, "boom") for t in (0, 4 * S, 5 * S, 9 * S, 10 * S)]
    assert [len(o) for o in out] == [1, 0, 1, 0, 1]


def test_warn_is_never_cooled_only_filtered() -> None:
    bridge = LogBridge()
    out = [send(bridge, k, "ctrl", WARN, "w") for k in range(5)]
    assert [len(o) for o in out] == [0, 0, 1, 1, 1]


def test_cooled_lines_do_not_touch_the_reporter_cache() -> None:
    bridge = configured({"max_tracked_nodes": 1})
    send(bridge, 0, "a", ERROR, "boom")
    send(bridge, 0, "a", WARN, "w")
    send(bridge, 1, "b", ERROR, "boom")  # evicts /a
    send(bridge, 2, "b", ERROR, "boom")  # cooled: /b is not looked up again
    assert "/b" in bridge.reporters
    assert "/a" not in bridge.reporters


# --- L29-L31: reporters and node identity ---


def test_l29_reporter_reuse_same_source_returns_same_instance() -> None:
    bridge = LogBridge()
    first = bridge.reporters.get("/planner_server")
    assert bridge.reporters.get("/planner_server") is first
    assert len(bridge.reporters) == 1
    bridge.reporters.get("/amcl")
    assert len(bridge.reporters) == 2


def test_l30_reporter_bound_lru_eviction() -> None:
    bridge = configured({"max_tracked_nodes": 2})
    for source in ("/n1", "/n2", "/n1", "/n3"):
        bridge.reporters.get(source)
        assert len(bridge.reporters) <= 2
    assert "/n2" not in bridge.reporters
    assert "/n1" in bridge.reporters
    bridge.reporters.get("/n1")
    assert len(bridge.reporters) == 2


def test_l31_node_name() -> None:
    assert LogBridge.name == "log_bridge"
    assert LogBridge().origin == "log_bridge"


def test_warn_counts_are_per_node_and_per_code() -> None:
    bridge = LogBridge()
    msg = "low battery"
    assert send(bridge, 1, "a", WARN, msg) + send(bridge, 2, "b", WARN, msg) == []
    assert send(bridge, 3, "a", WARN, "other") + send(bridge, 4, "a", WARN, msg) == []
    # The third line of the same template from /a, though its number differs.
    [report] = send(bridge, 5, "a", WARN, msg + " 7%")
    assert report == failed(bridge.fault_code("/a", msg), 5, 1, msg + " 7%", "/a")


# --- LI1-LI4: the integration stimuli, offline ---

NO_COOLDOWN: dict[str, object] = {"rosout_topic": "/rosout", "report_cooldown_sec": 0.0}


def test_li1_error_from_planner() -> None:
    bridge = configured(NO_COOLDOWN)
    out = send(bridge, 1, "planner_server", ERROR, "failed to compute path")
    assert out == [
        failed("LOG_PLANNER_SERVER_09fef28f", 1, 2, "failed to compute path", "/planner_server")
    ]


def test_li2_one_warn_is_held_then_li2b_the_third_is_forwarded() -> None:
    bridge = configured(NO_COOLDOWN)
    msg = "goal tolerance exceeded"
    assert send(bridge, 0, "controller", WARN, msg) == []
    assert send(bridge, 2 * S, "controller", WARN, msg) == []
    third = 2 * S + 4 * S // 10
    assert send(bridge, third, "controller", WARN, msg) == [
        failed("LOG_CONTROLLER_2e4c897a", third, 1, msg, "/controller")
    ]


def test_li3_info_is_not_a_fault() -> None:
    assert send(configured(NO_COOLDOWN), 1, "chatter", INFO, "all good") == []


def test_li4_bad_parameters_are_warned_and_replaced() -> None:
    config, warnings = log_bridge_config(
        {
            "max_tracked_nodes": 0,
            "report_cooldown_sec": float("nan"),
            "include_only_nodes": ["__none__"],
        }
    )
    assert config.max_tracked_nodes == 1
    assert config.report_cooldown_sec == 5.0
    assert "log_bridge: max_tracked_nodes 0 clamped to 1" in warnings
    assert any("report_cooldown_sec nan must be finite and >= 0" in w for w in warnings)
    assert send(LogBridge(config), 1, "planner_server", ERROR, "x") == []


# --- Topic selection and parameters (§3.3) ---


def test_wants_the_configured_topic_and_type() -> None:
    assert LogBridge().wants("/rosout", LOG)
    assert not LogBridge().wants("/rosout", "std_msgs/msg/String")
    assert not LogBridge().wants("/rosout_agg", LOG)
    assert configured({"rosout_topic": "/robot/rosout"}).wants("/robot/rosout", LOG)


def test_parameter_defaults() -> None:
    config, warnings = log_bridge_config({})
    assert config == LogBridgeConfig()
    assert warnings == []


@pytest.mark.parametrize(
    ("value", "used", "warning"),
    [
        (-1, 0, "log_bridge: severity_floor=-1 out of range [0,50], clamping"),
        (60, 50, "log_bridge: severity_floor=60 out of range [0,50], clamping"),
        (2**32 + 30, 50, "log_bridge: severity_floor=4294967326 out of range [0,50], clamping"),
    ],
)
def test_severity_floor_is_clamped(value: int, used: int, warning: str) -> None:
    config, warnings = log_bridge_config({"severity_floor": value})
    assert (config.severity_floor, warnings) == (used, [warning])


@pytest.mark.parametrize(
    ("value", "text"),
    [
        (-0.5, "report_cooldown_sec -0.50 must be finite and >= 0. Using default 5.0."),
        (float("inf"), "report_cooldown_sec inf must be finite and >= 0. Using default 5.0."),
    ],
)
def test_report_cooldown_must_be_finite_and_not_negative(value: float, text: str) -> None:
    config, warnings = log_bridge_config({"report_cooldown_sec": value})
    assert config.report_cooldown_sec == 5.0
    assert warnings == ["log_bridge: " + text]


def test_max_tracked_nodes_upper_clamp_and_prefix_fallback() -> None:
    config, warnings = log_bridge_config(
        {"max_tracked_nodes": 2**40, "code_prefix": "!!!", "severity_floor": 40}
    )
    assert config.max_tracked_nodes == 2**31 - 1
    assert config.code_prefix == "LOG"
    assert config.severity_floor == 40
    assert warnings == ["log_bridge: max_tracked_nodes 1099511627776 clamped to 2147483647"]


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("rosout_topic", ["/rosout"]),
        ("severity_floor", "30"),
        ("report_cooldown_sec", 5),
        ("exclude_medkit_stack", 0),
        ("exclude_nodes", [None]),
        ("max_tracked_nodes", 3.0),
    ],
)
def test_wrong_parameter_types_stop_the_node(name: str, value: object) -> None:
    with pytest.raises(ConfigError, match=f"'{name}'"):
        log_bridge_config({name: value})


def test_the_default_floor_is_warn_for_the_bridge_its_config_and_the_no_report_line() -> None:
    assert LOG_LEVELS[LOG_LEVEL_WARN] == "WARN"
    assert LogBridgeConfig().severity_floor == LOG_LEVEL_WARN
    assert log_bridge_config({})[0].severity_floor == LOG_LEVEL_WARN
    took: dict[str, Any] = {
        "messages_read": 3,
        "holds_messages": True,
        "diagnostics_topic": "/diagnostics",
        "rosout_topic": "/rosout",
        "log_bridge": True,
        "taken": (TopicUse("log_bridge", "/rosout", 3),),
    }
    assert "none at WARN or above reported" in Consumption(**took).no_report()
    assert "none at ERROR or above" in Consumption(**took, log_floor=40).no_report()
