"""ListFaults and ListFaultsForEntity query semantics of ros2_medkit's fault manager (§1.10).

Pure filters over FaultRecord or FaultSnapshot values: no storage access, no correlation, no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Generic, TypeVar

from medkit_replay.engine.storage import FaultRecord
from medkit_replay.model import STATUSES, FaultSnapshot, Status

if TYPE_CHECKING:
    from collections.abc import Iterable

FaultT = TypeVar("FaultT", FaultRecord, FaultSnapshot)

KNOWN_STATUSES: tuple[Status, ...] = STATUSES
EMPTY_ENTITY_ID_ERROR = "entity_id cannot be empty"


def requested_statuses(statuses: Iterable[str]) -> frozenset[Status]:
    """The statuses a ListFaults request selects.

    Matching is exact and case-sensitive; unknown strings are dropped, and when nothing valid
    remains (including an empty request) only CONFIRMED is selected.
    """
    wanted = frozenset(s for s in KNOWN_STATUSES if s in set(statuses))
    return wanted or frozenset({"CONFIRMED"})


def list_faults(
    faults: Iterable[FaultT],
    statuses: Iterable[str],
    filter_by_severity: bool = False,
    severity: int = 0,
) -> list[FaultT]:
    """ListFaults: faults in the requested statuses, in ascending fault_code byte order.

    ``filter_by_severity`` keeps only faults whose stored (escalated) severity equals
    ``severity`` exactly. Correlation muting is not applied here.
    """
    wanted = requested_statuses(statuses)
    selected = [
        fault
        for fault in faults
        if fault.status in wanted and (not filter_by_severity or fault.severity == severity)
    ]
    selected.sort(key=lambda fault: fault.fault_code.encode("utf-8"))
    return selected


def matches_entity(sources: Iterable[str], entity_id: str) -> bool:
    """True when a reporting source equals ``entity_id`` or ends with ``"/" + entity_id``."""
    suffix = "/" + entity_id
    return any(source == entity_id or source.endswith(suffix) for source in sources)


@dataclass(frozen=True, slots=True)
class EntityFaults(Generic[FaultT]):
    """A ListFaultsForEntity response: ``error_message`` is empty on success."""

    success: bool
    error_message: str
    faults: tuple[FaultT, ...]


def list_faults_for_entity(faults: Iterable[FaultT], entity_id: str) -> EntityFaults[FaultT]:
    """ListFaultsForEntity: faults in any status with a source matching ``entity_id``.

    An empty ``entity_id`` is refused as upstream refuses it. Faults come in ascending
    fault_code byte order.
    """
    if not entity_id:
        return EntityFaults(success=False, error_message=EMPTY_ENTITY_ID_ERROR, faults=())
    selected = [fault for fault in faults if matches_entity(_sources(fault), entity_id)]
    selected.sort(key=lambda fault: fault.fault_code.encode("utf-8"))
    return EntityFaults(success=True, error_message="", faults=tuple(selected))


def _sources(fault: FaultRecord | FaultSnapshot) -> Iterable[str]:
    if isinstance(fault, FaultRecord):
        return fault.sources
    return fault.reporting_sources
