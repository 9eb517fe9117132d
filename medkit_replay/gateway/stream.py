"""``GET /faults/stream``: the replay's FaultEvents as server-sent events, paced by ``--speed``.

Follows the gateway's SSE fault handler at 505bc2d5: ids count events from 1 in the order the
manager published them, ``Last-Event-ID`` (digits only, else 0; clamped to the newest id) resumes
after it, a ``:keepalive`` comment is sent after 30 s without an event, and at most
``sse.max_clients`` (2 by default) streams are open at once (503 beyond). Unlike the live
gateway, the stream ends after the recording's last event.
"""

from __future__ import annotations

import asyncio
import itertools
import time
import weakref
from bisect import bisect_left
from typing import TYPE_CHECKING

from starlette.responses import StreamingResponse

from medkit_replay.gateway.errors import ERR_SERVICE_UNAVAILABLE, GatewayError
from medkit_replay.gateway.stream_json import (
    KEEPALIVE,
    KEEPALIVE_INTERVAL_SEC,
    event_app_id,
    parse_last_event_id,
    sse_event,
)
from medkit_replay.model import NS_PER_SEC
from medkit_replay.spool import Spool

if TYPE_CHECKING:
    from collections.abc import AsyncIterator, Sequence

    from medkit_replay.gateway.recording import ServedRecording
    from medkit_replay.model import FaultEvent


def _times(events: Sequence[FaultEvent]) -> list[int]:
    """Every event's bag time; a spool's from its rows (whose first field it is), undecoded."""
    if isinstance(events, Spool) and events.codec is not None:
        return [row[0] for row in events.rows()]  # type: ignore[misc]  # t_ns, an int
    return [event.t_ns for event in events]


class EventStream:
    """Opens paced event streams over one recording's events, at most ``max_clients`` at once."""

    def __init__(self, served: ServedRecording, *, speed: float, max_clients: int) -> None:
        self.events = served.result.events
        apps = served.entities.list("apps")
        self.apps = {a.id for a in apps}
        self.node_to_app = {a.fqn: a.id for a in apps if a.fqn}
        self.times = _times(self.events)
        self.speed = speed
        self.max_clients = max_clients
        # A stream is open while its generator lives and has not ended; one a client dropped
        # before it started is collected, so no count can be left behind.
        self._streams: weakref.WeakSet[AsyncIterator[str]] = weakref.WeakSet()

    @property
    def open(self) -> int:
        """Streams open now."""
        return sum(1 for stream in self._streams if getattr(stream, "ag_frame", None) is not None)

    def response(self, header: str | None, start_ns: int | None) -> StreamingResponse:
        """A stream for one client: after ``Last-Event-ID`` (``header``), or from the first
        event at or after ``start_ns`` (an ``at`` moment), else from the first event."""
        if self.open >= self.max_clients:
            raise GatewayError(
                503,
                ERR_SERVICE_UNAVAILABLE,
                "Maximum number of SSE clients reached. Please try again later.",
            )
        first = parse_last_event_id(header, len(self.events))
        if first == 0 and start_ns is not None:
            first = bisect_left(self.times, start_ns)
        frames = self._frames(first)
        self._streams.add(frames)
        return StreamingResponse(
            frames,
            media_type="text/event-stream",
            headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"},
        )

    async def _frames(self, first: int) -> AsyncIterator[str]:
        """Frames of events ``first + 1`` (1-based ids) onwards, each sent when its bag time
        comes at ``speed`` times the recorded pace (0: at once); the pace uses the monotonic
        clock, the events keep bag time."""
        times, speed = self.times, self.speed
        if first >= len(times):
            return
        origin_ns, started = times[first], time.monotonic()
        # In order from the first asked: a spool read by index would reload a chunk each
        # time two streams take turns; one read from its start would decode every event before.
        events = self.events
        ordered = (
            events.iter_from(first)
            if isinstance(events, Spool)
            else itertools.islice(events, first, None)
        )
        for index, event in enumerate(ordered, first):
            if speed > 0:
                due = started + (times[index] - origin_ns) / NS_PER_SEC / speed
                while (wait := due - time.monotonic()) > 0:
                    await asyncio.sleep(min(wait, KEEPALIVE_INTERVAL_SEC))
                    if due - time.monotonic() > 0:
                        yield KEEPALIVE
            app = event_app_id(event.fault, self.apps, self.node_to_app)
            yield sse_event(event, index + 1, app_id=app)
