"""Recorded ReportFault/ClearFault service traffic (rosbag2 introspection) back into requests.

One call per (client_gid, sequence_number), applied at its earliest request-side event (§2).
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, cast

from medkit_replay.model import ClearRequest, ReportRequest

if TYPE_CHECKING:
    from collections.abc import Sequence

REPORT_FAULT_EVENT = "ros2_medkit_msgs/srv/ReportFault_Event"
CLEAR_FAULT_EVENT = "ros2_medkit_msgs/srv/ClearFault_Event"
REQUEST_SENT = 0
REQUEST_RECEIVED = 1
RESPONSE_SENT = 2
RESPONSE_RECEIVED = 3
# Copies of one call arrive within milliseconds; remembering this many keys is ample.
MAX_TRACKED_CALLS = 65536


class EventInfoLike(Protocol):
    """service_msgs/msg/ServiceEventInfo."""

    event_type: int
    client_gid: Sequence[int]
    sequence_number: int


class ServiceEventLike(Protocol):
    """A ``<Srv>_Event`` message: info plus at most one request and one response."""

    info: EventInfoLike
    request: Sequence[object]
    response: Sequence[object]


@dataclass(frozen=True, slots=True)
class RecordedResponse:
    """What the live fault manager answered to one recorded call."""

    t_ns: int
    request_t_ns: int
    topic: str
    fault_code: str
    kind: str  # "report" or "clear"
    accepted: bool  # ReportFault.accepted or ClearFault.success
    message: str
    auto_cleared_codes: tuple[str, ...]


@dataclass(slots=True)
class _Call:
    kind: str
    fault_code: str
    applied: bool
    t_ns: int = 0
    responded: bool = False


class ServiceCallReplayer:
    """Turns ``*/report_fault/_service_event`` and ``*/clear_fault/_service_event`` into requests.

    Not a bridge of upstream's but the same shape: messages in, requests out. Responses are
    kept in :attr:`responses` for the parity check; calls whose request payload was not
    recorded (metadata-only introspection) are counted in :attr:`metadata_only` (by topic), the
    calls turned into requests in :attr:`calls` (by kind: ``report`` or ``clear``).
    """

    name = "service_calls"

    def __init__(self) -> None:
        self._calls: OrderedDict[tuple[bytes, int, str], _Call] = OrderedDict()
        self.responses: list[RecordedResponse] = []
        self.metadata_only: dict[str, int] = {}
        self.calls: dict[str, int] = {}

    def wants(self, topic: str, msgtype: str) -> bool:
        """Service-event topics of the two fault-manager services that change state."""
        return msgtype in (REPORT_FAULT_EVENT, CLEAR_FAULT_EVENT) and topic.endswith(
            "/_service_event"
        )

    def on_message(
        self, t_ns: int, topic: str, msgtype: str, message: object
    ) -> list[ReportRequest | ClearRequest]:
        """Feed one service event; return the call's request the first time it is seen."""
        kind = "report" if msgtype == REPORT_FAULT_EVENT else "clear"
        msg = cast("ServiceEventLike", message)
        info = msg.info
        key = (
            bytes(bytearray(int(b) & 0xFF for b in info.client_gid)),
            int(info.sequence_number),
            topic,
        )
        call = self._calls.get(key)
        if info.event_type in (REQUEST_SENT, REQUEST_RECEIVED):
            if call is not None and call.applied:
                return []
            if not msg.request:
                if call is None:
                    self._remember(key, _Call(kind, "", applied=False))
                    self.metadata_only[topic] = self.metadata_only.get(topic, 0) + 1
                return []
            request = self._request(t_ns, topic, kind, msg.request[0])
            if call is not None and not call.applied and not call.fault_code:
                # A payload after a metadata-only copy of the same call: it counts after all.
                self.metadata_only[topic] -= 1
            self._remember(key, _Call(kind, request.fault_code, applied=True, t_ns=t_ns))
            self.calls[kind] = self.calls.get(kind, 0) + 1
            return [request]
        if info.event_type in (RESPONSE_SENT, RESPONSE_RECEIVED) and msg.response:
            self._response(t_ns, topic, kind, call, msg.response[0])
        return []

    def _remember(self, key: tuple[bytes, int, str], call: _Call) -> None:
        self._calls[key] = call
        self._calls.move_to_end(key)
        if len(self._calls) > MAX_TRACKED_CALLS:
            self._calls.popitem(last=False)

    @staticmethod
    def _request(t_ns: int, topic: str, kind: str, payload: object) -> ReportRequest | ClearRequest:
        code = str(getattr(payload, "fault_code", ""))
        if kind == "report":
            return ReportRequest(
                t_ns=t_ns,
                fault_code=code,
                event_type=int(getattr(payload, "event_type", 0)),
                severity=int(getattr(payload, "severity", 0)),
                description=str(getattr(payload, "description", "")),
                source_id=str(getattr(payload, "source_id", "")),
                origin="report_fault",
                topic=topic,
            )
        return ClearRequest(
            t_ns=t_ns,
            fault_code=code,
            skip_correlation_auto_clear=bool(
                getattr(payload, "skip_correlation_auto_clear", False)
            ),
            origin="report_fault",
            topic=topic,
        )

    def _response(
        self, t_ns: int, topic: str, kind: str, call: _Call | None, payload: object
    ) -> None:
        if call is None or not call.applied or call.kind != kind or call.responded:
            return  # unknown call, or the other side's copy of a response already kept
        call.responded = True
        accepted = bool(getattr(payload, "accepted", getattr(payload, "success", False)))
        codes = getattr(payload, "auto_cleared_codes", ())
        self.responses.append(
            RecordedResponse(
                t_ns=t_ns,
                request_t_ns=call.t_ns,
                topic=topic,
                fault_code=call.fault_code,
                kind=kind,
                accepted=accepted,
                message=str(getattr(payload, "message", "")),
                auto_cleared_codes=tuple(str(c) for c in codes),
            )
        )
