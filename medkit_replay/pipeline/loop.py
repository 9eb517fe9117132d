"""The replay loop: every message in time order to its bridge or the gate, timers first.

Records pile up as rows in the spools' tails and are settled every SETTLE_EVERY messages.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

from medkit_replay.inputs import Message

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from medkit_replay.inputs import Recording
    from medkit_replay.pipeline.meter import Meter
    from medkit_replay.pipeline.routing import Gate, Handler, Request, Router
    from medkit_replay.pipeline.tracing import Tracer
    from medkit_replay.spool import Spool

SETTLE_EVERY = 1024
"""Messages between two spills of the records the loop piled up (bounds memory)."""


class Clock(Protocol):
    """The timers the loop runs between messages: a Timeline, or several driven as one (a
    sweep's fan-out)."""

    last_ns: int | None

    def advance(self, t_ns: int) -> None:
        """Run every timer tick due at or before ``t_ns``."""

    def due_ns(self) -> int:
        """The earliest message time at which :meth:`advance` has more to do than noting it."""


def replay_loop(
    recording: Recording,
    meter: Meter | None,
    timeline: Clock,
    router: Router,
    gate: Gate,
    spools: Sequence[Spool[Any]] = (),
    tracer: Tracer | None = None,
    routes: dict[tuple[str, str, str], Handler | None] | None = None,
) -> int:
    """Every message, in time order, to its bridge (field by field into the manager, which
    records rows) or as request objects to the gate; timers run before each message's time.
    ``spools`` are settled now and then. ``routes`` is left holding the bridge handler chosen
    for every (role, topic, type) met (None: to the router's requests).

    A ``tracer`` (``explain``) sees every message and request on the way and forwards them."""
    messages = 0
    next_at = meter.next_at if meter is not None else 0  # 0: never reached
    settle_at = SETTLE_EVERY
    report = gate.report
    apply: Callable[[Request], None] = gate.apply
    tuples = recording.message_tuples()
    if tracer is not None:
        report, apply = tracer.sink(report), tracer.apply(apply)
        tuples = tracer.messages(tuples, recording)
    handlers: dict[tuple[str, str, str], Handler | None] = {} if routes is None else routes
    due = timeline.due_ns()
    t_ns: int | None = None
    for t_ns, input_index, topic, msgtype, role, msg in tuples:
        messages += 1
        if messages == next_at and meter is not None:
            meter.tick(messages, t_ns)
            next_at = meter.next_at
        if messages == settle_at:
            settle_at += SETTLE_EVERY
            for spool in spools:
                spool.settle()
        if t_ns >= due:
            timeline.advance(t_ns)
            due = timeline.due_ns()
        key = (role, topic, msgtype)
        try:
            handler = handlers[key]
        except KeyError:
            handler = handlers[key] = router.handler(role, topic, msgtype)
        if handler is not None:
            handler(t_ns, topic, msg, report)
        else:
            message = Message(t_ns, input_index, topic, msgtype, role, msg)
            for request in router.requests(message):
                apply(request)
    if t_ns is not None:
        timeline.last_ns = t_ns  # what each advance(t) before the due time would have noted
    return messages
