"""The bodies of the gateway's fault lists (all, per entity) and the per-entity scope of a fault,
built from a replay's state at one moment: plain JSON-ready values, no web framework, no I/O.
The detail route's body is in ``detail_json``.

Upstream: ros2_medkit at 505bc2d5 — fault_handlers.cpp (status filter, lists, the detail's
scope checks), core/faults/fault_scope.cpp (per-entity scope),
ros2/conversions/fault_msg_conversions.cpp and ros2_fault_service_transport.cpp (the fault and
correlation JSON), the fault manager's ListFaults and GetFault. Bag time stands where
the live gateway shows its wall clock.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from typing import TYPE_CHECKING

from medkit_replay.engine.queries import list_faults
from medkit_replay.engine.validation import fault_code_error
from medkit_replay.gateway.errors import (
    ERR_RESOURCE_NOT_FOUND,
    ERR_SERVICE_UNAVAILABLE,
    ID_FIELDS,
    GatewayError,
    invalid_parameter,
)
from medkit_replay.model import NS_PER_SEC, SEVERITY_NAMES

if TYPE_CHECKING:
    from collections.abc import Collection, Iterable, Mapping, Sequence

    from medkit_replay.history import CorrelationState
    from medkit_replay.model import Cluster, FaultSnapshot, Status

JsonObject = dict[str, object]

_MAX_ROUTE_CODE = 256  # the detail handler's own bound on a fault code, before the manager's

# -- times -------------------------------------------------------------------------------------


def time_msg(t_ns: int) -> tuple[int, int]:
    """builtin_interfaces/Time of a nanosecond count: (sec, nanosec)."""
    return divmod(t_ns, NS_PER_SEC)


def unix_seconds(t_ns: int) -> float:
    """A fault time as the fault JSON writes it: ``sec + nanosec / 1e9``."""
    sec, nanosec = time_msg(t_ns)
    return sec + nanosec / 1e9


def iso8601(t_ns: int) -> str:
    """``2026-02-04T10:30:00.123Z``: UTC to the millisecond, truncated (format_timestamp_ns)."""
    seconds = abs(t_ns) // NS_PER_SEC * (1 if t_ns >= 0 else -1)
    millis = int((t_ns - seconds * NS_PER_SEC) / 1_000_000)
    try:
        moment = datetime(1970, 1, 1, tzinfo=UTC) + timedelta(seconds=seconds)
    except OverflowError:
        return "1970-01-01T00:00:00.000Z"
    return f"{moment.strftime('%Y-%m-%dT%H:%M:%S')}.{millis:03d}Z"


# -- the status filter -------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class StatusFilter:
    """Which statuses a fault list asks the manager for (absent ``status``: the defaults)."""

    include_pending: bool = True
    include_confirmed: bool = True
    include_cleared: bool = False
    include_healed: bool = False

    @property
    def statuses(self) -> tuple[Status, ...]:
        """The ListFaults request's statuses: ``healed`` asks for PREPASSED too."""
        wanted: list[Status] = []
        if self.include_pending:
            wanted.append("PREFAILED")
        if self.include_confirmed:
            wanted.append("CONFIRMED")
        if self.include_cleared:
            wanted.append("CLEARED")
        if self.include_healed:
            wanted += ["HEALED", "PREPASSED"]
        return tuple(wanted)


_FILTERS = {
    "pending": StatusFilter(True, False, False, False),
    "confirmed": StatusFilter(False, True, False, False),
    "cleared": StatusFilter(False, False, True, True),
    "healed": StatusFilter(False, False, False, True),
    "all": StatusFilter(True, True, True, True),
}


STATUS_VALUES = tuple(_FILTERS)
"""Every ``status`` query value the fault routes accept."""


def parse_status_filter(
    value: str | None, extra_params: Mapping[str, object] | None = None
) -> StatusFilter:
    """The filter of a ``status`` query value (None: absent). An unknown value, an empty one
    included, raises the 400 the handler answers; ``extra_params`` join its parameters (the
    per-entity route adds ``{"app_id": id}`` and the like)."""
    if value is None:
        return StatusFilter()
    found = _FILTERS.get(value)
    if found is None:
        params: JsonObject = {
            "allowed_values": ", ".join(STATUS_VALUES),
            "parameter": "status",
            "value": value,
        }
        params.update(extra_params or {})
        raise invalid_parameter("Invalid status parameter value", params)
    return found


def query_bool(value: str | None) -> bool:
    """A boolean query parameter: ``true`` or ``1`` in any case; anything else is false."""
    return value is not None and value.lower() in ("true", "1")


# -- fault JSON --------------------------------------------------------------------------------


def severity_label(severity: int) -> str:
    """INFO, WARN, ERROR, CRITICAL; UNKNOWN beyond them."""
    return SEVERITY_NAMES[severity] if 0 <= severity < len(SEVERITY_NAMES) else "UNKNOWN"


def fault_json(fault: FaultSnapshot) -> JsonObject:
    """One fault as the lists and the stream carry it; ``last_passed`` only once it passed."""
    item: JsonObject = {
        "fault_code": fault.fault_code,
        "severity": fault.severity,
        "description": fault.description,
        "first_occurred": unix_seconds(fault.first_occurred_ns),
        "last_occurred": unix_seconds(fault.last_occurred_ns),
    }
    if fault.last_passed_ns != 0:
        item["last_passed"] = unix_seconds(fault.last_passed_ns)
    item["occurrence_count"] = fault.occurrence_count
    item["status"] = fault.status
    item["reporting_sources"] = list(fault.reporting_sources)
    item["severity_label"] = severity_label(fault.severity)
    return item


def _cluster_json(cluster: Cluster) -> JsonObject:
    """ClusterInfo as the gateway writes it: its fields, the times as Unix seconds."""
    fields = dataclasses.asdict(cluster)
    fields["fault_codes"] = list(cluster.fault_codes)
    fields["first_at"] = unix_seconds(fields.pop("first_at_ns"))
    fields["last_at"] = unix_seconds(fields.pop("last_at_ns"))
    return fields


def _listed(
    faults: Iterable[FaultSnapshot],
    correlation: CorrelationState,
    status: StatusFilter,
    include_muted: bool,
) -> list[FaultSnapshot]:
    """ListFaults: the statuses asked for, in code order; muted symptoms left out unless asked."""
    selected = list_faults(faults, status.statuses)
    if include_muted or not correlation.muted:
        return selected
    muted = {m.fault_code for m in correlation.muted}
    return [fault for fault in selected if fault.fault_code not in muted]


def fault_list_body(
    faults: Iterable[FaultSnapshot],
    correlation: CorrelationState,
    status: StatusFilter,
    *,
    include_muted: bool = False,
    include_clusters: bool = False,
) -> JsonObject:
    """``GET /faults``: the items and the x-medkit counts; the muted and cluster details only
    when asked for and not empty. With correlation off, ``correlation`` is empty and the
    counts are 0, as the manager answers without an engine."""
    items = [fault_json(f) for f in _listed(faults, correlation, status, include_muted)]
    extension: JsonObject = {
        "count": len(items),
        "muted_count": len(correlation.muted),
        "cluster_count": len(correlation.clusters),
    }
    if include_muted and correlation.muted:
        extension["muted_faults"] = [dataclasses.asdict(m) for m in correlation.muted]
    if include_clusters and correlation.clusters:
        extension["clusters"] = [_cluster_json(c) for c in correlation.clusters]
    return {"items": items, "x-medkit": extension}


# -- per-entity scope --------------------------------------------------------------------------


def _source_in_scope(source: str, scope: Collection[str]) -> bool:
    for fqn in scope:
        if source == fqn or (source.startswith(fqn) and source[len(fqn) : len(fqn) + 1] == "/"):
            return True
    return False


def in_scope(reporting_sources: Sequence[str], sources: Collection[str]) -> bool:
    """Whether a fault belongs to an entity: it has reporting sources, and every one is one of
    the entity's sources or a path below one (``/a/b`` is below ``/a``, ``/ab`` is not)."""
    if not sources or not reporting_sources:
        return False
    return all(_source_in_scope(source, sources) for source in reporting_sources)


def entity_fault_list_body(
    faults: Iterable[FaultSnapshot],
    correlation: CorrelationState,
    status: StatusFilter,
    *,
    kind: str,
    entity_id: str,
    sources: frozenset[str],
    source_id: str = "",
    component_count: int = 0,
) -> JsonObject:
    """``GET /{kind}/{id}/faults``: the faults in the entity's scope (muted ones always left
    out), with the x-medkit block of its kind.

    ``kind`` is the route collection (``apps``...), ``sources`` the entity's reporting-source
    FQNs; ``source_id`` (apps) is the app's FQN; ``component_count`` (areas) the components
    directly in the area.
    """
    listed = _listed(faults, correlation, status, include_muted=False)
    items = [fault_json(f) for f in listed if in_scope(f.reporting_sources, sources)]
    extension: JsonObject
    if kind == "apps":
        extension = {
            "entity_id": entity_id,
            "source_id": source_id,
            "count": len(items),
            "muted_count": len(correlation.muted),
            "cluster_count": len(correlation.clusters),
        }
        return {"items": items, "x-medkit": extension}
    extension = {"entity_id": entity_id, "aggregated": True}
    if kind == "functions":
        extension["aggregation_level"] = "function"
        extension["host_count"] = len(sources)
    elif kind == "components":
        extension["aggregation_level"] = "component"
        extension["app_count"] = len(sources)
    else:
        extension["aggregation_level"] = "area"
        extension["component_count"] = component_count
        extension["app_count"] = len(sources)
    if sources:
        extension["aggregation_sources"] = sorted(sources, key=lambda s: s.encode("utf-8"))
    extension["count"] = len(items)
    return {"items": items, "x-medkit": extension}


# -- the fault detail --------------------------------------------------------------------------


def scoped_fault(
    code: str,
    fault: FaultSnapshot | None,
    *,
    kind: str,
    entity_id: str,
    sources: frozenset[str],
    max_code_length: int,
) -> FaultSnapshot:
    """The fault ``GET /{kind}/{id}/faults/{code}`` shows, or the error the handler answers.

    ``fault`` is what the manager holds under ``code`` (None: nothing); ``max_code_length``
    the release's bound on a code. A code the manager refuses as malformed answers 503, as the
    gateway passes on any GetFault failure that does not say "not found".
    """
    id_field = ID_FIELDS[kind]
    if not code or len(code.encode("utf-8", "surrogateescape")) > _MAX_ROUTE_CODE:
        raise invalid_parameter(
            "Invalid fault code",
            {"details": f"Fault code must be between 1 and {_MAX_ROUTE_CODE} characters"},
        )
    reason = fault_code_error(code, max_code_length)
    if reason is not None:
        raise GatewayError(
            503,
            ERR_SERVICE_UNAVAILABLE,
            "Failed to get fault",
            {"details": reason, id_field: entity_id, "fault_code": code},
        )
    if fault is None:
        raise GatewayError(
            404,
            ERR_RESOURCE_NOT_FOUND,
            "Fault not found",
            {"details": f"Fault not found: {code}", id_field: entity_id, "fault_code": code},
        )
    if not in_scope(fault.reporting_sources, sources):
        raise GatewayError(
            404,
            ERR_RESOURCE_NOT_FOUND,
            "Fault not found",
            {
                "details": "Fault is not in scope for this entity: every reporting source must "
                "be one of the entity's owned apps, and a mixed-source fault that includes any "
                "out-of-entity reporter is rejected to prevent cross-entity disclosure",
                id_field: entity_id,
                "fault_code": code,
            },
        )
    return fault
