"""The action status bridge at ros2_medkit 0.6.0 (bdcc4ed0): upstream's transition tests of that
commit (its ``apply_message`` was rewritten around deferred delivery after it), as data, and each
0.6.0 difference beside 0.7.0 on the same input.

0.6.0 acts on a verdict at once and commits it even while the manager's service is not ready,
so the request is lost (ab3a90f8, 243a2f4a keep it pending and retry it), has no
``retry_period_sec``, and narrows ``aborted_severity`` and ``dedup_capacity`` to int before
their range checks (26611619).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

from medkit_replay.bridges.action_status import (
    ActionStatusBridge,
    ActionStatusBridgeConfig,
    NetState,
)
from medkit_replay.config.bridges import action_status_bridge_config
from medkit_replay.engine.local_filter import LocalFilterConfig
from medkit_replay.errors import ConfigError
from medkit_replay.model import EventType
from medkit_replay.releases import release_named
from tests.bridges.messages import ABORTED, CANCELED, SUCCEEDED, arr, status_topic

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence

    from medkit_replay.releases import Release

R060, R070 = release_named("0.6.0"), release_named("0.7.0")
A, C, OK = ABORTED, CANCELED, SUCCEEDED


def bridge_at(release: Release, params: Mapping[str, object] | None = None) -> ActionStatusBridge:
    config, _ = action_status_bridge_config(params or {}, release)
    return ActionStatusBridge(config, release=release)


def feed(bridge: ActionStatusBridge, action: str, t_ns: int, *goals: tuple[int, int]) -> list[str]:
    """The requests one status array gives, each as ``FAILED <code>`` or ``PASSED <code>``."""
    out = bridge.on_message(t_ns, status_topic(action), arr(*goals))
    return [f"{EventType(r.event_type).name} {r.fault_code}" for r in out]


def raise_(action: str, *, canceled: bool = False) -> list[str]:
    suffix = "CANCELED" if canceled else "ABORTED"
    return [f"FAILED ACTION_{action.strip('/').upper()}_{suffix}"]


def heal(action: str, *, canceled_is_fault: bool = False) -> list[str]:
    name = action.strip("/").upper()
    return [f"PASSED ACTION_{name}_ABORTED"] + (
        [f"PASSED ACTION_{name}_CANCELED"] if canceled_is_fault else []
    )


# --- Ported: ActionStatusBridgeTest.Apply_* @bdcc4ed0 ---------------------------------------
# A step is (action, goals of one array); the kind upstream asserts is what the requests show:
# kFailed a raise, kHealthy a heal, kUnknown nothing.

Step = tuple[str, tuple[tuple[int, int], ...], list[str]]

CFI: dict[str, object] = {"canceled_is_fault": True}
APPLY: list[tuple[str, dict[str, object], list[Step]]] = [
    ("Apply_AbortRaisesThenSucceedHeals", {}, [
        ("/nav", ((1, A),), raise_("/nav")),
        ("/nav", ((2, OK),), heal("/nav")),
    ]),
    ("Apply_DedupNoDoubleRaiseOrHeal", {}, [
        ("/nav", ((1, A),), raise_("/nav")),
        ("/nav", ((1, A),), []),
        ("/nav", ((2, OK),), heal("/nav")),
        ("/nav", ((2, OK),), []),
    ]),
    ("Apply_SucceededFirstNoSpuriousHeal", {}, [("/nav", ((1, OK),), [])]),
    ("Apply_MultiGoalOneArray_OrderIndependent", {}, [("/nav", ((1, A), (2, OK)), raise_("/nav"))]),
    ("Apply_MultiGoalOneArray_OrderIndependent", {}, [("/nav", ((2, OK), (1, A)), raise_("/nav"))]),
    ("Apply_HealOnlyWhenFailingGoalAgesOut", {}, [
        ("/nav", ((1, A),), raise_("/nav")),
        ("/nav", ((1, A), (2, OK)), []),
        ("/nav", ((2, OK),), heal("/nav")),
    ]),
    ("Apply_Flapping_OnlyNetStateChangesTransition", {}, [
        *(("/nav", ((g, A),), raise_("/nav") if g == 10 else []) for g in range(10, 14)),
        ("/nav", ((99, OK),), heal("/nav")),
    ]),
    ("Apply_CanceledNotFaultByDefault", {}, [("/nav", ((1, C),), [])]),
    ("Apply_CanceledIsFault_RaisesThenHealsOnSuccess", CFI, [
        ("/nav", ((1, C),), raise_("/nav", canceled=True)),
        ("/nav", ((2, OK),), heal("/nav", canceled_is_fault=True)),
    ]),
    ("Apply_HealDisabled_NoHealTransition", {"heal_on_succeeded": False}, [
        ("/nav", ((1, A),), raise_("/nav")),
        ("/nav", ((2, OK),), []),
    ]),
    ("Apply_PerActionIsolation", {}, [
        ("/nav", ((1, A),), raise_("/nav")),
        ("/arm", ((1, A),), raise_("/arm")),
        ("/arm", ((2, OK),), heal("/arm")),
        ("/nav", ((3, OK),), heal("/nav")),
    ]),
]  # fmt: skip


@pytest.mark.parametrize(("upstream_test", "params", "steps"), APPLY)
def test_apply_message_at_060(
    upstream_test: str, params: Mapping[str, object], steps: Sequence[Step]
) -> None:
    bridge = bridge_at(R060, params)
    seen = [feed(bridge, action, t, *goals) for t, (action, goals, _) in enumerate(steps)]
    assert seen == [expected for *_, expected in steps], upstream_test


# --- Delivery while the manager's service is not ready, 0.6.0 beside 0.7.0 ----------------------


def test_a_verdict_made_while_the_service_is_down_is_lost_at_060() -> None:
    old, new = bridge_at(R060), bridge_at(R070)
    for bridge in (old, new):
        bridge.service_ready = False
        assert feed(bridge, "/nav", 1, (1, A)) == []
    old_view, new_view = old.action_state("/nav"), new.action_state("/nav")
    assert old_view is not None
    assert new_view is not None
    assert (old_view.reported, old_view.pending) == (NetState.FAILED, False)  # committed
    assert (new_view.reported, new_view.pending) == (None, True)  # kept for the retry
    for bridge in (old, new):
        bridge.service_ready = True
    assert old.reconcile_pending(2) == []
    assert [r.fault_code for r in new.reconcile_pending(2)] == ["ACTION_NAV_ABORTED"]
    # 0.6.0 then heals a fault the manager never heard of; 0.7.0 heals the one it raised.
    assert feed(old, "/nav", 3, (2, OK)) == heal("/nav")
    assert feed(new, "/nav", 3, (2, OK)) == heal("/nav")


def test_a_heal_made_while_the_service_is_down_is_lost_at_060() -> None:
    old, new = bridge_at(R060), bridge_at(R070)
    for bridge in (old, new):
        assert feed(bridge, "/nav", 1, (1, A)) == raise_("/nav")
        bridge.service_ready = False
        assert feed(bridge, "/nav", 2, (2, OK)) == []
        bridge.service_ready = True
    assert old.reconcile_pending(3) == []  # the manager keeps the fault active
    assert [r.event_type for r in new.reconcile_pending(3)] == [EventType.PASSED]
    # Both raise the next failure, though at 0.6.0 the manager never heard the first heal.
    assert feed(old, "/nav", 4, (3, A)) == raise_("/nav")
    assert feed(new, "/nav", 4, (3, A)) == raise_("/nav")


def test_the_lost_request_still_counts_in_the_local_filter_at_060() -> None:
    # The reporter filters before its client finds the service missing (send_report).
    config = ActionStatusBridgeConfig(aborted_severity=1, local_filter=LocalFilterConfig())
    old = ActionStatusBridge(config, release=R060)
    new = ActionStatusBridge(config, release=R070)
    out: dict[str, list[str]] = {}
    for name, bridge in (("0.6.0", old), ("0.7.0", new)):
        bridge.service_ready = False
        seen = feed(bridge, "/nav", 1, (1, A)) + feed(bridge, "/nav", 2, (2, OK))
        bridge.service_ready = True
        seen += feed(bridge, "/nav", 3, (3, A)) + feed(bridge, "/nav", 4, (4, OK))
        out[name] = seen + feed(bridge, "/nav", 5, (5, A))
    # 0.6.0: the WARN raises counted 1 (lost), 2 (held), 3 (sent); 0.7.0 never sent the first.
    assert out["0.6.0"] == raise_("/nav")
    assert out["0.7.0"] == []


def test_a_vanished_action_is_healed_into_the_void_at_060() -> None:
    for release in (R060, R070):
        bridge = bridge_at(release)
        feed(bridge, "/arm", 1, (1, A))
        bridge.service_ready = False
        assert bridge.prune(2, []) == [], release.name
        assert bridge.action_state("/arm") is None, release.name


# --- Parameters, 0.6.0 beside 0.7.0 -------------------------------------------------------


def test_ai3_bad_parameters_wrap_into_range_at_060() -> None:
    params = {"aborted_severity": 4294967298, "dedup_capacity": 4294967296}
    config, warnings = action_status_bridge_config(params, R060)
    assert (config.aborted_severity, config.dedup_capacity) == (2, 4096)
    assert warnings == ["action_status_bridge: dedup_capacity 0 not positive; using 4096"]
    config, warnings = action_status_bridge_config(params, R070)
    assert (config.aborted_severity, config.dedup_capacity) == (2, 4096)
    assert warnings == [
        "action_status_bridge: aborted_severity 4294967298 out of range [0,3]; clamping to ERROR",
        "action_status_bridge: dedup_capacity 4294967296 out of range; using 4096",
    ]


def test_a_wrapped_aborted_severity_raises_a_warn_at_060() -> None:
    params = {"aborted_severity": 2**32 + 1, "dedup_capacity": 2**32 + 5}
    old, old_warnings = action_status_bridge_config(params, R060)
    new, _ = action_status_bridge_config(params, R070)
    assert (old.aborted_severity, old.dedup_capacity, old_warnings) == (1, 5, [])
    assert (new.aborted_severity, new.dedup_capacity) == (2, 4096)
    requests = {
        release.name: ActionStatusBridge(config, release=release).on_message(
            1, status_topic("/nav"), arr((1, A))
        )
        for release, config in ((R060, old), (R070, new))
    }
    assert [r.severity for r in requests["0.6.0"]] == [1]
    assert [r.severity for r in requests["0.7.0"]] == [2]


def test_out_of_range_aborted_severity_is_named_narrowed_at_060() -> None:
    _, warnings = action_status_bridge_config({"aborted_severity": 2**31 + 7}, R060)
    assert warnings == [
        "action_status_bridge: aborted_severity -2147483641 out of range [0,3]; clamping to ERROR"
    ]


@pytest.mark.parametrize(("value", "warned"), [("fast", False), (-1.0, True), (0.2, False)])
def test_retry_period_sec_is_not_a_parameter_at_060(value: object, warned: bool) -> None:
    params = {"retry_period_sec": value}
    assert action_status_bridge_config(params, R060) == (ActionStatusBridgeConfig(), [])
    if isinstance(value, str):
        with pytest.raises(ConfigError, match="'retry_period_sec'"):
            action_status_bridge_config(params, R070)
        return
    _, warnings = action_status_bridge_config(params, R070)
    assert bool(warnings) == warned


def test_the_parameters_both_releases_share_are_read_alike() -> None:
    params: dict[str, object] = {
        "aborted_severity": 3,
        "canceled_is_fault": True,
        "heal_on_succeeded": False,
        "rescan_period_sec": 0.5,
        "code_prefix": "nav2 actions",
        "exclude_actions": ["/a"],
        "include_only_actions": ["/b"],
        "dedup_capacity": 10,
        "fault_reporter.local_filtering.enabled": True,
    }
    assert action_status_bridge_config(params, R060) == action_status_bridge_config(params, R070)
