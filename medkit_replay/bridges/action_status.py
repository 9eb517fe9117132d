"""Action goal status → faults: upstream's action_status_bridge replayed over GoalStatusArrays.

One net state per action; a fault is raised on healthy→failed and healed on failed→healthy only.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol, cast

from medkit_replay.bridges.base import FaultReporter, MessageBridge, RequestList, passes_lists
from medkit_replay.bridges.codes import action_fault_code
from medkit_replay.engine.local_filter import LocalFilterConfig
from medkit_replay.releases import Release, default_release

if TYPE_CHECKING:
    from collections.abc import Iterable, Mapping, Sequence

    from medkit_replay.model import Origin, ReportFields, ReportRequest, ReportSink

NODE_NAME = "action_status_bridge"
STATUS_SUFFIX = "/_action/status"
GOAL_STATUS_ARRAY = "action_msgs/msg/GoalStatusArray"
STATUS_SUCCEEDED = 4
STATUS_CANCELED = 5
STATUS_ABORTED = 6
_UNKNOWN_NODE_NAME = "_NODE_NAME_UNKNOWN_"
_UNKNOWN_NODE_NAMESPACE = "_NODE_NAMESPACE_UNKNOWN_"


class NetState(enum.Enum):
    """An action's verdict from one status array (``derive_state``)."""

    UNKNOWN = "unknown"
    HEALTHY = "healthy"
    FAILED = "failed"


class GoalStatusLike(Protocol):
    """The field of action_msgs/msg/GoalStatus the bridge reads."""

    status: int


class GoalStatusArrayLike(Protocol):
    """action_msgs/msg/GoalStatusArray as the bridge reads it."""

    status_list: Sequence[GoalStatusLike]


@dataclass(frozen=True, slots=True, kw_only=True)
class ActionStatusBridgeConfig:
    """The node's parameters after upstream's load-time checks (bridges.md §1.6)."""

    aborted_severity: int = 2
    canceled_is_fault: bool = False
    heal_on_succeeded: bool = True
    rescan_period_sec: float = 2.0  # live graph rescans; kept for the record
    retry_period_sec: float = 0.05  # live retry timer; kept for the record
    code_prefix: str = "ACTION"
    exclude_actions: tuple[str, ...] = ()
    include_only_actions: tuple[str, ...] = ()
    dedup_capacity: int = 4096  # only ever gated DEBUG log lines upstream
    local_filter: LocalFilterConfig = field(
        default_factory=lambda: LocalFilterConfig(enabled=False)
    )


def action_name_from_status_topic(topic: str) -> str:
    """The action a ``<action>/_action/status`` topic belongs to, or ``""`` for any other topic."""
    if len(topic) <= len(STATUS_SUFFIX) or not topic.endswith(STATUS_SUFFIX):
        return ""
    return topic[: -len(STATUS_SUFFIX)]


def server_fqn_from_endpoint(node_name: str, node_namespace: str) -> str:
    """A publisher's node FQN, or ``""`` while discovery still reports placeholders."""
    if (
        not node_name
        or node_name == _UNKNOWN_NODE_NAME
        or node_namespace == _UNKNOWN_NODE_NAMESPACE
    ):
        return ""
    if node_namespace in ("", "/"):
        return "/" + node_name
    return f"{node_namespace}/{node_name}"


def uuid_to_hex(uuid: Iterable[int]) -> str:
    """A goal id as 32 lowercase hex digits, first byte first."""
    return bytes(int(b) & 0xFF for b in uuid).hex()


def derive_state(goals: Iterable[GoalStatusLike], canceled_is_fault: bool) -> NetState:
    """Any failing goal fails the action; else any other terminal goal makes it healthy."""
    terminal = False
    for goal in goals:
        status = goal.status
        if status == STATUS_ABORTED or (status == STATUS_CANCELED and canceled_is_fault):
            return NetState.FAILED
        if status in (STATUS_SUCCEEDED, STATUS_CANCELED):
            terminal = True
    return NetState.HEALTHY if terminal else NetState.UNKNOWN


def failure_is_cancel(goals: Iterable[GoalStatusLike], canceled_is_fault: bool) -> bool:
    """True when only CANCELED goals (counted as faults) make the array fail; ABORTED dominates."""
    saw_cancel = False
    for goal in goals:
        if goal.status == STATUS_ABORTED:
            return False
        if goal.status == STATUS_CANCELED and canceled_is_fault:
            saw_cancel = True
    return saw_cancel


@dataclass(frozen=True, slots=True)
class ActionView:
    """What the bridge holds for one action: its reporter's source and the two state maps."""

    source_id: str
    desired: NetState
    desired_canceled: bool
    reported: NetState | None  # None: never delivered, which counts as HEALTHY

    @property
    def pending(self) -> bool:
        """A verdict not yet delivered (only while the manager's service is down)."""
        return self.desired is not NetState.UNKNOWN and self.desired is not (
            self.reported or NetState.HEALTHY
        )


@dataclass(slots=True)
class _Action:
    topic: str
    reporter: FaultReporter
    aborted_code: str
    canceled_code: str
    desired: NetState = NetState.UNKNOWN
    desired_canceled: bool = False
    reported: NetState | None = None


class ActionStatusBridge(MessageBridge):
    """Mirrors upstream node ``action_status_bridge`` (ros2_medkit 0.6.0 @ 505bc2d5, bridges.md §1).

    Every ``*/_action/status`` topic of type GoalStatusArray that passes the include/exclude lists
    is an action. A reporter (with its fixed source_id) is made on the first status array of an
    action: the server node from ``action_sources`` if mapped, else the action name (§1.4, §10.3).
    The manager's service is ready unless ``service_ready`` is set false; while it is, verdicts stay
    pending until :meth:`reconcile_pending` runs with the service back (upstream's retry timer),
    or, for a ``release`` without that retry (0.6.0), are acted on at once and lost.
    """

    name = NODE_NAME
    origin: Origin = "action_status_bridge"

    def __init__(
        self,
        config: ActionStatusBridgeConfig | None = None,
        *,
        action_sources: Mapping[str, str] | None = None,
        release: Release | None = None,
    ) -> None:
        self.config = config or ActionStatusBridgeConfig()
        self.action_sources: dict[str, str] = dict(action_sources or {})
        self.service_ready = True
        self._actions: dict[str, _Action] = {}
        # Where a verdict goes while the service is down: nowhere yet (None: it stays pending),
        # or, without deferred delivery, through the reporter to a client that drops it.
        defers = (release or default_release()).action_bridge_defers_delivery
        self._unready_sink: ReportSink | None = None if defers else _lost

    def is_eligible(self, action_name: str) -> bool:
        """``include_only_actions`` then ``exclude_actions``, as unanchored substrings."""
        cfg = self.config
        return passes_lists(cfg.include_only_actions, cfg.exclude_actions, action_name)

    def fault_code(self, action_name: str, *, canceled: bool) -> str:
        """The ``_ABORTED`` or ``_CANCELED`` code of an action under this config's prefix."""
        return action_fault_code(self.config.code_prefix, action_name, canceled=canceled)

    def wants(self, topic: str, msgtype: str) -> bool:
        """A GoalStatusArray on an eligible ``<action>/_action/status`` topic."""
        if msgtype != GOAL_STATUS_ARRAY:
            return False
        action = action_name_from_status_topic(topic)
        return bool(action) and self.is_eligible(action)

    def feed(self, t_ns: int, topic: str, msg: object, report: ReportSink) -> None:
        """Apply one status array: update the desired state, then deliver what differs."""
        action = action_name_from_status_topic(topic)
        if not action or not self.is_eligible(action):
            return
        state = self._actions.get(action) or self._watch(action, topic)
        goals = cast("GoalStatusArrayLike", msg).status_list
        net = derive_state(goals, self.config.canceled_is_fault)
        if net is NetState.UNKNOWN:
            return
        if net is NetState.FAILED:
            state.desired = NetState.FAILED
            state.desired_canceled = failure_is_cancel(goals, self.config.canceled_is_fault)
        elif self.config.heal_on_succeeded:
            # Without healing a success leaves the desired state alone: a failure stays failed.
            state.desired = NetState.HEALTHY
        self._reconcile(t_ns, state, action, report)

    def watched_actions(self) -> list[str]:
        """Names of the actions seen so far, sorted."""
        return sorted(self._actions)

    def reconcile_pending(self, t_ns: int) -> list[ReportRequest]:
        """Retry every undelivered verdict, in action-name order (the retry timer's pass)."""
        out = RequestList()
        for action in sorted(self._actions):
            self._reconcile(t_ns, self._actions[action], action, out)
        return out

    def prune(self, t_ns: int, present: Iterable[str]) -> list[ReportRequest]:
        """Forget actions not in ``present``, healing one still failed first (§1.7).

        A bag shows no graph, so nothing calls this unless the replay asks for a vanish.
        """
        keep = set(present)
        out = RequestList()
        for action in sorted(self._actions, key=lambda name: self._actions[name].topic):
            if action in keep:
                continue
            state = self._actions.pop(action)
            if state.reported is not NetState.FAILED or not self.config.heal_on_succeeded:
                continue
            if self.service_ready:
                self._heal(t_ns, state, out)
            elif self._unready_sink is not None:
                self._heal(t_ns, state, self._unready_sink)
        return out

    def action_state(self, action_name: str) -> ActionView | None:
        """The bridge's view of one action, or None when it has never seen (or has pruned) it."""
        state = self._actions.get(action_name)
        if state is None:
            return None
        return ActionView(
            state.reporter.source_id, state.desired, state.desired_canceled, state.reported
        )

    def _watch(self, action: str, topic: str) -> _Action:
        source_id = self.action_sources.get(action) or action
        state = _Action(
            topic=topic,
            reporter=FaultReporter(source_id, self.config.local_filter, origin=self.origin),
            aborted_code=self.fault_code(action, canceled=False),
            canceled_code=self.fault_code(action, canceled=True),
        )
        self._actions[action] = state
        return state

    def _reconcile(self, t_ns: int, state: _Action, action: str, report: ReportSink) -> None:
        desired = state.desired
        if desired is NetState.UNKNOWN or desired is (state.reported or NetState.HEALTHY):
            return
        if not self.service_ready:
            if self._unready_sink is None:
                return  # stays pending; nothing is committed
            report = self._unready_sink
        state.reported = desired
        if desired is NetState.HEALTHY:
            self._heal(t_ns, state, report)
            return
        canceled = state.desired_canceled
        code = state.canceled_code if canceled else state.aborted_code
        verb = "canceled" if canceled else "aborted"
        description = f"Action {action} {verb}"
        state.reporter.report(
            t_ns, state.topic, code, self.config.aborted_severity, description, report
        )

    def _heal(self, t_ns: int, state: _Action, report: ReportSink) -> None:
        # Both codes are healed whichever was raised; only the one that exists matters upstream.
        state.reporter.report_passed(t_ns, state.topic, state.aborted_code, report)
        if self.config.canceled_is_fault:
            state.reporter.report_passed(t_ns, state.topic, state.canceled_code, report)


def _lost(*_request: *ReportFields) -> None:
    """A ReportSink for requests sent while the manager's service is not discovered: the
    reporter's local filter has counted each, and its client drops it (``send_report``)."""
