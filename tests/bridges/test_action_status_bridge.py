"""Ports of upstream's action status bridge tests (bridges.md §8.1, A1-A31 and AI1-AI3).

Upstream asserts transition kinds; the emitted request details are those §8's preamble infers.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, cast

import numpy as np
import pytest

from medkit_replay.bridges.action_status import (
    ActionStatusBridge,
    ActionStatusBridgeConfig,
    NetState,
    action_name_from_status_topic,
    derive_state,
    failure_is_cancel,
    server_fqn_from_endpoint,
    uuid_to_hex,
)
from medkit_replay.config.bridges import action_status_bridge_config
from medkit_replay.engine.local_filter import LocalFilterConfig
from medkit_replay.errors import ConfigError
from medkit_replay.model import NS_PER_SEC, EventType, ReportRequest
from tests.bridges.messages import (
    ABORTED,
    CANCELED,
    EXECUTING,
    GOAL_STATUS_ARRAY,
    SUCCEEDED,
    arr,
    goal,
    goal_array,
    one,
    status_topic,
)

if TYPE_CHECKING:
    from collections.abc import Sequence

    from medkit_replay.bridges.action_status import GoalStatusArrayLike, GoalStatusLike

S = NS_PER_SEC
A, C, E, OK = ABORTED, CANCELED, EXECUTING, SUCCEEDED


def raised(
    action: str,
    t_ns: int,
    *,
    canceled: bool = False,
    severity: int = 2,
    source: str | None = None,
) -> ReportRequest:
    """The FAILED request §8's preamble infers for a RAISE."""
    verb = "canceled" if canceled else "aborted"
    return ReportRequest(
        t_ns=t_ns,
        fault_code=ActionStatusBridge().fault_code(action, canceled=canceled),
        event_type=EventType.FAILED,
        severity=severity,
        description=f"Action {action} {verb}",
        source_id=source or action,
        origin="action_status_bridge",
        topic=status_topic(action),
    )


def healed(
    action: str, t_ns: int, *, canceled_is_fault: bool = False, source: str | None = None
) -> list[ReportRequest]:
    """The PASSED request(s) of a HEAL: _ABORTED, then _CANCELED when cancels are faults."""
    flags = [False, True] if canceled_is_fault else [False]
    return [
        ReportRequest(
            t_ns=t_ns,
            fault_code=ActionStatusBridge().fault_code(action, canceled=canceled),
            event_type=EventType.PASSED,
            severity=0,
            description="",
            source_id=source or action,
            origin="action_status_bridge",
            topic=status_topic(action),
        )
        for canceled in flags
    ]


def feed(bridge: ActionStatusBridge, action: str, msg: object, t_ns: int) -> list[ReportRequest]:
    return bridge.on_message(t_ns, status_topic(action), msg)


def bridge_with(
    *, canceled_is_fault: bool = False, heal_on_succeeded: bool = True
) -> ActionStatusBridge:
    config = ActionStatusBridgeConfig(
        canceled_is_fault=canceled_is_fault, heal_on_succeeded=heal_on_succeeded
    )
    return ActionStatusBridge(config)


# --- A1-A10: helpers and node identity ---


def test_a1_action_name_from_status_topic_valid() -> None:
    assert action_name_from_status_topic("/navigate_to_pose/_action/status") == "/navigate_to_pose"
    assert action_name_from_status_topic("/move_action/_action/status") == "/move_action"
    assert action_name_from_status_topic("/ns/a/_action/status") == "/ns/a"
    assert action_name_from_status_topic("x/_action/status") == "x"


@pytest.mark.parametrize(
    "topic", ["/some/topic", "/navigate_to_pose/_action/feedback", "/_action/status"]
)
def test_a2_action_name_from_status_topic_not_a_status_topic(topic: str) -> None:
    assert action_name_from_status_topic(topic) == ""
    assert not ActionStatusBridge().wants(topic, GOAL_STATUS_ARRAY)


@pytest.mark.parametrize(
    ("node", "namespace", "fqn"),
    [
        ("planner_server", "/", "/planner_server"),
        ("planner_server", "", "/planner_server"),
        ("planner_server", "/nav", "/nav/planner_server"),
    ],
)
def test_a3_server_fqn_from_endpoint_resolved(node: str, namespace: str, fqn: str) -> None:
    assert server_fqn_from_endpoint(node, namespace) == fqn


@pytest.mark.parametrize(
    ("node", "namespace"),
    [
        ("_NODE_NAME_UNKNOWN_", "_NODE_NAMESPACE_UNKNOWN_"),
        ("_NODE_NAME_UNKNOWN_", "/nav"),
        ("planner_server", "_NODE_NAMESPACE_UNKNOWN_"),
        ("", "/"),
    ],
)
def test_a4_server_fqn_from_endpoint_unresolved_returns_empty(node: str, namespace: str) -> None:
    assert server_fqn_from_endpoint(node, namespace) == ""


def test_a5_fault_code_aborted_well_formed() -> None:
    code = ActionStatusBridge().fault_code("/navigate_to_pose", canceled=False)
    assert code == "ACTION_NAVIGATE_TO_POSE_ABORTED"


def test_a6_fault_code_canceled_uses_canceled_suffix() -> None:
    code = ActionStatusBridge().fault_code("/move_action", canceled=True)
    assert code == "ACTION_MOVE_ACTION_CANCELED"


def test_a7_fault_code_long_name_status_suffix_survives_clamp() -> None:
    bridge = ActionStatusBridge()
    aborted = bridge.fault_code("/" + "a" * 80, canceled=False)
    canceled = bridge.fault_code("/" + "a" * 80, canceled=True)
    assert aborted == "ACTION_" + "A" * 42 + "_4A4E_ABORTED"
    assert canceled == "ACTION_" + "A" * 42 + "_4A4E_CANCELED"
    assert len(aborted) <= 64
    assert len(canceled) <= 64


def test_a8_fault_code_shared_long_prefix_no_collision() -> None:
    bridge = ActionStatusBridge()
    alpha = bridge.fault_code("/" + "x" * 60 + "_alpha", canceled=False)
    bravo = bridge.fault_code("/" + "x" * 60 + "_bravo", canceled=False)
    assert alpha != bravo
    assert alpha.endswith("_3997_ABORTED")
    assert bravo.endswith("_0972_ABORTED")


def test_a9_uuid_to_hex() -> None:
    uuid = np.zeros(16, dtype=np.uint8)
    uuid[0], uuid[1], uuid[15] = 0xAB, 0x01, 0xFF
    text = uuid_to_hex(uuid)
    assert len(text) == 32
    assert text.startswith("ab01")
    assert text.endswith("ff")


def test_a10_node_name() -> None:
    assert ActionStatusBridge.name == "action_status_bridge"
    assert ActionStatusBridge().origin == "action_status_bridge"


# --- A11-A15: derive_state ---


def goals_of(msg: object) -> Sequence[GoalStatusLike]:
    return cast("GoalStatusArrayLike", msg).status_list


def test_a11_derive_state_aborted_is_failed() -> None:
    assert derive_state(goals_of(one(1, A)), False) is NetState.FAILED


def test_a12_derive_state_succeeded_is_healthy() -> None:
    assert derive_state(goals_of(one(1, OK)), False) is NetState.HEALTHY


def test_a13_derive_state_no_terminal_is_unknown() -> None:
    assert derive_state(goals_of(one(1, E)), False) is NetState.UNKNOWN
    assert derive_state(goals_of(arr()), False) is NetState.UNKNOWN


def test_a14_derive_state_canceled_respects_flag() -> None:
    goals = goals_of(one(1, C))
    assert derive_state(goals, False) is NetState.HEALTHY
    assert derive_state(goals, True) is NetState.FAILED


def test_a15_derive_state_order_independent() -> None:
    for msg in (arr((1, A), (2, OK)), arr((2, OK), (1, A))):
        assert derive_state(goals_of(msg), False) is NetState.FAILED


def test_failure_is_cancel_only_without_aborts() -> None:
    cancels = goals_of(arr((1, C), (2, OK)))
    mixed = goals_of(arr((1, C), (2, A)))
    assert failure_is_cancel(cancels, True)
    assert not failure_is_cancel(cancels, False)
    assert not failure_is_cancel(mixed, True)


# --- A16-A25: applying messages ---


def test_a16_abort_raises_then_succeed_heals() -> None:
    bridge = ActionStatusBridge()
    assert feed(bridge, "/nav", one(1, A), 1 * S) == [raised("/nav", 1 * S)]
    assert feed(bridge, "/nav", one(2, OK), 2 * S) == healed("/nav", 2 * S)
    assert raised("/nav", 0).fault_code == "ACTION_NAV_ABORTED"


def test_a17_dedup_no_double_raise_or_heal() -> None:
    bridge = ActionStatusBridge()
    assert feed(bridge, "/nav", one(1, A), 1 * S) == [raised("/nav", 1 * S)]
    assert feed(bridge, "/nav", one(1, A), 2 * S) == []
    assert feed(bridge, "/nav", one(2, OK), 3 * S) == healed("/nav", 3 * S)
    assert feed(bridge, "/nav", one(2, OK), 4 * S) == []


def test_a18_succeeded_first_no_spurious_heal() -> None:
    bridge = ActionStatusBridge()
    assert feed(bridge, "/nav", one(1, OK), 1 * S) == []
    view = bridge.action_state("/nav")
    assert view is not None
    assert view.reported is None


@pytest.mark.parametrize("order", ["aborted_first", "succeeded_first"])
def test_a19_multi_goal_one_array_order_independent(order: str) -> None:
    msg = arr((1, A), (2, OK)) if order == "aborted_first" else arr((2, OK), (1, A))
    assert feed(ActionStatusBridge(), "/nav", msg, 5) == [raised("/nav", 5)]


def test_a20_heal_only_when_failing_goal_ages_out() -> None:
    bridge = ActionStatusBridge()
    assert feed(bridge, "/nav", one(1, A), 1 * S) == [raised("/nav", 1 * S)]
    assert feed(bridge, "/nav", arr((1, A), (2, OK)), 2 * S) == []
    assert feed(bridge, "/nav", one(2, OK), 3 * S) == healed("/nav", 3 * S)


def test_a21_flapping_only_net_state_changes_transition() -> None:
    bridge = ActionStatusBridge()
    out: list[ReportRequest] = []
    for k, g in enumerate((10, 11, 12, 13)):
        out += feed(bridge, "/nav", one(g, A), k * S)
    assert out == [raised("/nav", 0)]
    assert feed(bridge, "/nav", one(99, OK), 9 * S) == healed("/nav", 9 * S)


def test_a22_canceled_not_fault_by_default() -> None:
    assert feed(ActionStatusBridge(), "/nav", one(1, C), 1 * S) == []


def test_a23_canceled_is_fault_raises_then_heals_on_success() -> None:
    bridge = bridge_with(canceled_is_fault=True)
    expected_raise = raised("/nav", 1 * S, canceled=True)
    assert expected_raise.fault_code == "ACTION_NAV_CANCELED"
    assert expected_raise.description == "Action /nav canceled"
    assert feed(bridge, "/nav", one(1, C), 1 * S) == [expected_raise]
    heal = feed(bridge, "/nav", one(2, OK), 2 * S)
    assert heal == healed("/nav", 2 * S, canceled_is_fault=True)
    assert [r.fault_code for r in heal] == ["ACTION_NAV_ABORTED", "ACTION_NAV_CANCELED"]


def test_a24_heal_disabled_no_heal_transition() -> None:
    bridge = bridge_with(heal_on_succeeded=False)
    assert feed(bridge, "/nav", one(1, A), 1 * S) == [raised("/nav", 1 * S)]
    assert feed(bridge, "/nav", one(2, OK), 2 * S) == []
    assert feed(bridge, "/nav", one(3, A), 3 * S) == []  # still failed: nothing to raise


def test_a25_per_action_isolation() -> None:
    bridge = ActionStatusBridge()
    assert feed(bridge, "/nav", one(1, A), 1) == [raised("/nav", 1)]
    assert feed(bridge, "/arm", one(1, A), 2) == [raised("/arm", 2)]
    assert feed(bridge, "/arm", one(2, OK), 3) == healed("/arm", 3)
    assert feed(bridge, "/nav", one(3, OK), 4) == healed("/nav", 4)


def test_cancel_failure_is_not_re_raised_by_a_later_abort() -> None:
    # [inferred] in §1.3: the net state stays FAILED, so _ABORTED is never raised.
    bridge = bridge_with(canceled_is_fault=True)
    assert feed(bridge, "/nav", one(1, C), 1) == [raised("/nav", 1, canceled=True)]
    assert feed(bridge, "/nav", one(2, A), 2) == []


def test_abort_dominates_cancel_in_one_array() -> None:
    bridge = bridge_with(canceled_is_fault=True)
    assert feed(bridge, "/nav", arr((1, C), (2, A)), 1) == [raised("/nav", 1)]


# --- A26: reporter and source_id ---


def test_a26_reporter_sticky_created_once_never_swapped() -> None:
    bridge = ActionStatusBridge()
    # The reporter is made on the first array, even one without a verdict.
    assert feed(bridge, "/nav", one(1, E), 1) == []
    view = bridge.action_state("/nav")
    assert view is not None
    assert view.source_id == "/nav"
    bridge.action_sources["/nav"] = "/bt_navigator"  # learnt too late: never re-attributed
    assert feed(bridge, "/nav", one(1, A), 2) == [raised("/nav", 2, source="/nav")]


def test_action_sources_mapping_names_the_server() -> None:
    bridge = ActionStatusBridge(action_sources={"/nav": "/nav/planner_server"})
    assert feed(bridge, "/nav", one(1, A), 1) == [raised("/nav", 1, source="/nav/planner_server")]
    assert feed(bridge, "/arm", one(1, A), 2) == [raised("/arm", 2)]


# --- A27-A30: delivery deferred while the manager's service is down ---


def test_a27_fault_deferred_when_service_unavailable() -> None:
    bridge = ActionStatusBridge()
    bridge.service_ready = False
    assert feed(bridge, "/nav", one(1, A), 1) == []
    view = bridge.action_state("/nav")
    assert view is not None
    assert view.reported is not NetState.FAILED
    assert view.desired is NetState.FAILED
    assert view.pending


def test_a28_deferred_raise_delivered_once_service_ready() -> None:
    bridge = ActionStatusBridge()
    bridge.service_ready = False
    assert feed(bridge, "/nav", one(1, A), 1) == []
    bridge.service_ready = True
    assert bridge.reconcile_pending(2) == [raised("/nav", 2)]
    view = bridge.action_state("/nav")
    assert view is not None
    assert not view.pending
    assert bridge.reconcile_pending(3) == []


def test_a29_deferred_heal_delivered_once_service_ready() -> None:
    bridge = ActionStatusBridge()
    assert feed(bridge, "/nav", one(1, A), 1) == [raised("/nav", 1)]
    bridge.service_ready = False
    assert feed(bridge, "/nav", one(2, OK), 2) == []
    view = bridge.action_state("/nav")
    assert view is not None
    assert view.reported is NetState.FAILED
    bridge.service_ready = True
    assert bridge.reconcile_pending(3) == healed("/nav", 3)


def test_a30_reconcile_pending_retries_without_dropping_while_service_down() -> None:
    bridge = ActionStatusBridge()
    bridge.service_ready = False
    feed(bridge, "/nav", one(1, A), 1)
    assert bridge.reconcile_pending(2) == []
    assert bridge.reconcile_pending(3) == []
    view = bridge.action_state("/nav")
    assert view is not None
    assert view.pending


def test_flap_inside_an_outage_produces_nothing() -> None:
    bridge = ActionStatusBridge()
    bridge.service_ready = False
    feed(bridge, "/nav", one(1, A), 1)
    feed(bridge, "/nav", one(2, OK), 2)
    bridge.service_ready = True
    assert bridge.reconcile_pending(3) == []


def test_reconcile_pending_runs_in_action_name_order() -> None:
    bridge = ActionStatusBridge()
    bridge.service_ready = False
    feed(bridge, "/zeta", one(1, A), 1)
    feed(bridge, "/alpha", one(1, A), 2)
    bridge.service_ready = True
    assert bridge.reconcile_pending(3) == [raised("/alpha", 3), raised("/zeta", 3)]


# --- A31: vanished actions ---


def test_a31_prune_drops_vanished_action() -> None:
    # Offline every watched action has a reporter (made on its first array), so the vanished
    # failed one is healed before it is forgotten (§1.7); upstream's seam had no reporter.
    bridge = ActionStatusBridge()
    feed(bridge, "/nav", one(1, A), 1)
    feed(bridge, "/arm", one(1, A), 2)
    assert bridge.prune(3, ["/nav"]) == healed("/arm", 3)
    assert bridge.action_state("/arm") is None
    view = bridge.action_state("/nav")
    assert view is not None
    assert view.reported is NetState.FAILED
    # A reappearing action starts from scratch: absent counts as healthy, so it raises again.
    assert feed(bridge, "/arm", one(2, A), 4) == [raised("/arm", 4)]


def test_prune_without_healing_or_service_only_forgets() -> None:
    bridge = bridge_with(heal_on_succeeded=False)
    feed(bridge, "/arm", one(1, A), 1)
    assert bridge.prune(2, []) == []
    assert bridge.action_state("/arm") is None
    ready = ActionStatusBridge()
    feed(ready, "/arm", one(1, A), 1)
    ready.service_ready = False
    assert ready.prune(2, []) == []
    assert ready.action_state("/arm") is None


def test_prune_leaves_healthy_actions_silent() -> None:
    bridge = ActionStatusBridge()
    feed(bridge, "/nav", one(1, A), 1)
    feed(bridge, "/nav", one(2, OK), 2)
    assert bridge.prune(3, []) == []


# --- Eligibility and topic selection (§1.1) ---


def test_wants_needs_the_status_type_and_suffix() -> None:
    bridge = ActionStatusBridge()
    assert bridge.wants("/nav/_action/status", GOAL_STATUS_ARRAY)
    assert not bridge.wants("/nav/_action/status", "std_msgs/msg/String")


def test_include_and_exclude_are_unanchored_substrings() -> None:
    bridge = ActionStatusBridge(
        ActionStatusBridgeConfig(include_only_actions=("nav",), exclude_actions=("", "through"))
    )
    assert bridge.wants("/navigate_to_pose/_action/status", GOAL_STATUS_ARRAY)
    assert not bridge.wants("/navigate_through_poses/_action/status", GOAL_STATUS_ARRAY)
    assert not bridge.wants("/arm/_action/status", GOAL_STATUS_ARRAY)
    assert feed(bridge, "/arm", one(1, A), 1) == []


def test_include_only_of_empty_strings_excludes_everything() -> None:
    bridge = ActionStatusBridge(ActionStatusBridgeConfig(include_only_actions=("",)))
    assert not bridge.wants("/nav/_action/status", GOAL_STATUS_ARRAY)


def test_goal_ids_do_not_gate_transitions() -> None:
    # The per-goal dedup of upstream only gates DEBUG logs: a fresh failure after a heal raises.
    bridge = ActionStatusBridge()
    msg = goal_array(goal(range(16), A))
    assert feed(bridge, "/nav", msg, 1) == [raised("/nav", 1)]
    assert feed(bridge, "/nav", one(2, OK), 2) == healed("/nav", 2)
    assert feed(bridge, "/nav", msg, 3) == [raised("/nav", 3)]


# --- The reporter's local filter (pre-declared off, §1.3) ---


def test_local_filter_is_off_by_default() -> None:
    config, _ = action_status_bridge_config({})
    assert config.local_filter.enabled is False
    assert ActionStatusBridgeConfig().local_filter.enabled is False


def test_local_filter_turned_on_throttles_passed_only() -> None:
    config, _ = action_status_bridge_config({"fault_reporter.local_filtering.enabled": True})
    bridge = ActionStatusBridge(config)
    assert feed(bridge, "/nav", one(1, A), 1) == [raised("/nav", 1)]  # ERROR bypasses
    assert feed(bridge, "/nav", one(2, OK), 2) == []  # 1st PASSED held, heal still committed
    view = bridge.action_state("/nav")
    assert view is not None
    assert view.reported is NetState.HEALTHY


def test_low_severity_raise_is_held_by_an_enabled_filter() -> None:
    config = ActionStatusBridgeConfig(
        aborted_severity=1, local_filter=LocalFilterConfig(enabled=True)
    )
    bridge = ActionStatusBridge(config)
    assert feed(bridge, "/nav", one(1, A), 1) == []
    view = bridge.action_state("/nav")
    assert view is not None
    assert view.reported is NetState.FAILED  # committed although the filter held it


# --- Parameters (§1.6) and the integration tests ---


def test_ai1_ai2_integration_raise_then_heal() -> None:
    uuid_ones = [1] * 16
    bridge = ActionStatusBridge(action_sources={"/test_action": "/test_action_status_client"})
    aborted = goal_array(goal(uuid_ones, A))
    [report] = feed(bridge, "/test_action", aborted, 1)
    assert report.fault_code == "ACTION_TEST_ACTION_ABORTED"
    assert report.severity == 2
    assert report.source_id == "/test_action_status_client"
    succeeded = goal_array(goal([2] * 16, OK))
    [heal] = feed(bridge, "/test_action", succeeded, 2)
    assert (heal.fault_code, heal.event_type) == ("ACTION_TEST_ACTION_ABORTED", EventType.PASSED)
    assert heal.source_id == "/test_action_status_client"


def test_ai3_bad_parameters_are_warned_and_replaced() -> None:
    config, warnings = action_status_bridge_config(
        {"aborted_severity": 4294967298, "dedup_capacity": 4294967296}
    )
    assert (config.aborted_severity, config.dedup_capacity) == (2, 4096)
    assert any("aborted_severity 4294967298 out of range [0,3]" in w for w in warnings)
    assert any("dedup_capacity 4294967296 out of range" in w for w in warnings)


def test_parameter_defaults() -> None:
    config, warnings = action_status_bridge_config({})
    assert config == ActionStatusBridgeConfig()
    assert warnings == []


def test_parameters_are_read_and_normalised() -> None:
    config, warnings = action_status_bridge_config(
        {
            "aborted_severity": 3,
            "canceled_is_fault": True,
            "heal_on_succeeded": False,
            "code_prefix": "nav2 actions",
            "exclude_actions": ["/a"],
            "include_only_actions": ["/b", "/c"],
            "dedup_capacity": 10,
        }
    )
    assert warnings == []
    assert config.aborted_severity == 3
    assert config.canceled_is_fault
    assert not config.heal_on_succeeded
    assert config.code_prefix == "NAV2_ACTIONS"
    assert config.exclude_actions == ("/a",)
    assert config.include_only_actions == ("/b", "/c")
    assert config.dedup_capacity == 10
    code = ActionStatusBridge(config).fault_code("/nav", canceled=False)
    assert code == "NAV2_ACTIONS_NAV_ABORTED"


@pytest.mark.parametrize(
    ("params", "field", "value", "warning"),
    [
        ({"aborted_severity": -1}, "aborted_severity", 2, "aborted_severity -1 out of range"),
        ({"code_prefix": "!!!"}, "code_prefix", "ACTION", "code_prefix empty after normalization"),
        ({"rescan_period_sec": 0.0}, "rescan_period_sec", 2.0, "rescan_period_sec 0.000 not"),
        ({"retry_period_sec": -1.0}, "retry_period_sec", 0.05, "retry_period_sec -1.000 not"),
        ({"dedup_capacity": 0}, "dedup_capacity", 4096, "dedup_capacity 0 out of range"),
        ({"dedup_capacity": 2**31}, "dedup_capacity", 4096, "dedup_capacity 2147483648 out"),
    ],
)
def test_out_of_range_parameters(
    params: dict[str, object], field: str, value: object, warning: str
) -> None:
    config, warnings = action_status_bridge_config(params)
    assert getattr(config, field) == value
    assert len(warnings) == 1
    assert warnings[0].startswith("action_status_bridge: " + warning)


def test_longest_valid_dedup_capacity_is_kept() -> None:
    config, warnings = action_status_bridge_config({"dedup_capacity": 2**31 - 1})
    assert (config.dedup_capacity, warnings) == (2**31 - 1, [])


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("aborted_severity", "2"),
        ("aborted_severity", 2.0),
        ("canceled_is_fault", 1),
        ("rescan_period_sec", 2),
        ("code_prefix", 5),
        ("exclude_actions", "/nav"),
        ("include_only_actions", ["/nav", 3]),
        ("fault_reporter.local_filtering.enabled", "false"),
    ],
)
def test_wrong_parameter_types_stop_the_node(name: str, value: object) -> None:
    with pytest.raises(ConfigError, match=f"'{name}'"):
        action_status_bridge_config({name: value})
