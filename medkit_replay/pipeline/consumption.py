"""Which paths into the fault manager took how much of a recording, from what one pass left.

Costs nothing per message: the routes the loop cached (one per role, topic and type), the
inputs' counts per topic and the recorded calls, put together once at the end.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.inputs.selection import DIAGNOSTICS_TYPE, LOG_TYPE
from medkit_replay.model import LOG_LEVEL_WARN
from medkit_replay.result import Consumption, TopicUse

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence

    from medkit_replay.model import InputSummary
    from medkit_replay.pipeline.routing import Handler, Router

ORIGINS = {
    "diagnostics": "diagnostic_bridge",
    "action_status": "action_status_bridge",
    "rosout": "log_bridge",
    "report_fault": "report_fault",
    "clear_fault": "clear_fault",
    "script": "script",
    "fault_events": "fault_events",
}
"""The path a message of each role takes (a bridge's role only when the bridge wants it)."""
BRIDGE_ROLES = ("diagnostics", "rosout")
"""Roles whose messages reach their bridge only if it wants their topic and type."""


def consumption(
    router: Router,
    routes: Mapping[tuple[str, str, str], Handler | None],
    summaries: Sequence[InputSummary],
    messages: int,
) -> Consumption:
    """What each path took in one pass: ``routes`` maps every (role, topic, type) the loop
    met to the bridge handler it chose (None: the message went to the router's requests).

    A path took a topic when the loop handed it messages of the topic's role; the topics are
    named as recorded (a ROS 1 ``<a>/status`` keeps its name) with the inputs' counts.
    """
    delivered: dict[str, list[str]] = {}
    for (role, topic, _), handler in routes.items():
        if role in ORIGINS and not (role in BRIDGE_ROLES and handler is None):
            delivered.setdefault(role, []).append(topic)
    taken: dict[tuple[str, str], int] = {}
    for summary in summaries:
        for use in summary.topics:
            if use.role in delivered and use.messages:
                key = (ORIGINS[use.role], use.topic)
                taken[key] = taken.get(key, 0) + use.messages
    if "script" in delivered:
        taken[("script", "")] = sum(s.message_count for s in summaries if s.storage == "jsonl")
    for role, topics in delivered.items():
        if not any(origin == ORIGINS[role] for origin, _ in taken):
            # Messages reached the path though no input counts any (a damaged index): 0,
            # how many unknown.
            taken.update({(ORIGINS[role], topic): 0 for topic in topics})
    order = list(ORIGINS.values())
    uses = sorted(taken.items(), key=lambda item: (order.index(item[0][0]), item[0][1]))
    rosout = router.log.topic if router.log is not None else "/rosout"
    calls = router.services.calls
    return Consumption(
        messages_read=messages,
        holds_messages=messages > 0 or any(s.message_count for s in summaries),
        diagnostics_topic=router.diagnostic.topic,
        rosout_topic=rosout,
        log_bridge=router.log is not None,
        taken=tuple(TopicUse(origin, topic, count) for (origin, topic), count in uses),
        report_calls=calls.get("report", 0),
        clear_calls=calls.get("clear", 0),
        metadata_only=sum(router.services.metadata_only.values()),
        unread=_unread(router, summaries, rosout),
        log_floor=router.log.config.severity_floor if router.log is not None else LOG_LEVEL_WARN,
    )


def _unread(router: Router, summaries: Sequence[InputSummary], rosout: str) -> tuple[TopicUse, ...]:
    """Topics a path would read if configured so: log messages while the log bridge is off,
    DiagnosticArrays on another topic than the diagnostic bridge's."""
    found: dict[tuple[str, str], int] = {}
    for summary in summaries:
        for topic in summary.topics:
            key: tuple[str, str] | None = None
            if topic.type == LOG_TYPE and topic.topic == rosout and router.log is None:
                key = ("log_bridge", topic.topic)
            elif topic.type == DIAGNOSTICS_TYPE and topic.topic != router.diagnostic.topic:
                key = ("diagnostic_bridge", topic.topic)
            if key is not None:
                found[key] = found.get(key, 0) + topic.messages
    return tuple(TopicUse(o, topic, n) for (o, topic), n in sorted(found.items()) if n > 0)
