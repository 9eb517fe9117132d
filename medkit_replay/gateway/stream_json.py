"""The gateway's fault event stream (``GET /faults/stream``): one server-sent event per
FaultEvent, the keep-alive comment, the app an event names, Last-Event-ID resumption.

Upstream: ros2_medkit at 505bc2d5 — sse_fault_handler.cpp (format_sse_event,
resolve_entity_context, parse_last_event_id and the stream loop's clamp).
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING

from medkit_replay.gateway.faults_json import fault_json, time_msg

if TYPE_CHECKING:
    from collections.abc import Container, Mapping

    from medkit_replay.model import FaultEvent, FaultSnapshot

KEEPALIVE = ":keepalive\n\n"
"""The comment the fault stream sends when nothing happened for KEEPALIVE_INTERVAL_SEC."""
KEEPALIVE_INTERVAL_SEC = 30
_UINT64_DIGITS = 20  # longer ids are out of range, as for the gateway's stoull


def _event_seconds(t_ns: int) -> float:
    # The stream's own conversion multiplies by 1e-9, which can differ in the last bit.
    sec, nanosec = time_msg(t_ns)
    return float(sec) + float(nanosec) * 1e-9


def sse_event(event: FaultEvent, event_id: int, *, app_id: str | None = None) -> str:
    """One server-sent event: ``id``, ``event`` and ``data`` lines and the blank line.

    ``app_id``: the app the fault's first reporting source resolves to (event_app_id); the
    data then names it under ``x-medkit``.
    """
    kind = event.event_type.replace("\r", "").replace("\n", "")
    data: dict[str, object] = {
        "event_type": kind,
        "fault": fault_json(event.fault),
        "timestamp": _event_seconds(event.t_ns),
    }
    if event.auto_cleared_codes:
        data["auto_cleared_codes"] = list(event.auto_cleared_codes)
    if app_id is not None:
        data["x-medkit"] = {"entity_type": "apps", "entity_id": app_id}
    text = json.dumps(
        data, separators=(",", ":"), sort_keys=True, ensure_ascii=False, allow_nan=False
    )
    return f"id: {event_id}\nevent: {kind}\ndata: {text}\n\n"


def event_app_id(
    fault: FaultSnapshot,
    app_ids: Container[str],
    node_to_app: Mapping[str, str] | None = None,
) -> str | None:
    """The app an event's fault is shown under: its first reporting source's app (by the
    node-to-app links when given, else the app named like the node, else
    ``<namespace with _ for />_<node>``); None when no app matches."""
    if not fault.reporting_sources or not fault.reporting_sources[0]:
        return None
    fqn = fault.reporting_sources[0]
    if node_to_app:
        linked = node_to_app.get(fqn) or (node_to_app.get(fqn[1:]) if fqn[0] == "/" else None)
        if linked:
            return linked
    cut = fqn.rfind("/")
    name = fqn[cut + 1 :]
    if name and name in app_ids:
        return name
    if cut > 0:
        namespaced = fqn[1:cut].replace("/", "_") + "_" + name
        if namespaced in app_ids:
            return namespaced
    return None


def parse_last_event_id(value: str | None, newest_id: int) -> int:
    """The id a resuming client last saw: digits only (else 0), at most ``newest_id``."""
    if not value or len(value) > _UINT64_DIGITS or not value.isascii() or not value.isdigit():
        return 0
    number = int(value)
    return 0 if number >= 1 << 64 else min(number, newest_id)
