"""Every state a replayed fault went through, and the correlation view, indexed by bag time.

Filled once during a replay (``replay(history=...)``); answers "what did the manager hold at
time t" by bisection, with no replay per question (``medkit-replay serve`` asks it).
"""

from __future__ import annotations

from bisect import bisect_right
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from medkit_replay.model import Cluster, FaultSnapshot, MutedFault


@dataclass(frozen=True, slots=True)
class CorrelationState:
    """The correlation engine's muted map and active clusters, as ListFaults reports them."""

    muted: tuple[MutedFault, ...] = ()
    clusters: tuple[Cluster, ...] = ()


_NO_CORRELATION = CorrelationState()


def _utf8(code: str) -> bytes:
    return code.encode("utf-8")


@dataclass(slots=True)
class FaultHistory:
    """Per fault code, its snapshots at each bag time it changed; and the correlation states.

    A code's first entry is the report that created it, so a time before it finds no fault.
    Several changes at one bag time keep the last (the state once that moment has passed).
    """

    _times: dict[str, list[int]] = field(default_factory=dict)
    _states: dict[str, list[FaultSnapshot]] = field(default_factory=dict)
    _correlation_times: list[int] = field(default_factory=list)
    _correlation: list[CorrelationState] = field(default_factory=list)
    sources: set[str] = field(default_factory=set)
    """Every reporting source and logging node the replay saw, as ROS node names (the entities
    ``serve`` shows are made from them)."""

    # -- filling ---------------------------------------------------------------------------

    def put(self, t_ns: int, snapshot: FaultSnapshot) -> None:
        """Note ``snapshot`` as its fault's state from ``t_ns`` on (bag times never decrease)."""
        code = snapshot.fault_code
        times = self._times.get(code)
        if times is None:
            self._times[code] = [t_ns]
            self._states[code] = [snapshot]
            return
        states = self._states[code]
        if states[-1] == snapshot:
            return
        if times[-1] == t_ns:
            states[-1] = snapshot
        else:
            times.append(t_ns)
            states.append(snapshot)

    def put_correlation(self, t_ns: int, state: CorrelationState) -> None:
        """Note the correlation view from ``t_ns`` on, when it differs from the last one."""
        states = self._correlation
        if states and states[-1] == state:
            return
        if not states and state == _NO_CORRELATION:
            return
        if self._correlation_times and self._correlation_times[-1] == t_ns:
            states[-1] = state
        else:
            self._correlation_times.append(t_ns)
            states.append(state)

    # -- questions -------------------------------------------------------------------------

    @property
    def codes(self) -> tuple[str, ...]:
        """Every fault code the replay stored, in byte order."""
        return tuple(sorted(self._times, key=_utf8))

    @property
    def change_times(self) -> tuple[int, ...]:
        """Every bag time at which some fault or the correlation view changed, ascending."""
        times = {t for per_code in self._times.values() for t in per_code}
        times.update(self._correlation_times)
        return tuple(sorted(times))

    def fault_at(self, code: str, t_ns: int) -> FaultSnapshot | None:
        """The fault's state once bag time ``t_ns`` has passed; None before it existed."""
        times = self._times.get(code)
        if times is None:
            return None
        index = bisect_right(times, t_ns)
        return self._states[code][index - 1] if index else None

    def faults_at(self, t_ns: int) -> list[FaultSnapshot]:
        """Every fault known once ``t_ns`` has passed, in fault_code byte order."""
        found = []
        for code in self.codes:
            times = self._times[code]
            index = bisect_right(times, t_ns)
            if index:
                found.append(self._states[code][index - 1])
        return found

    def correlation_at(self, t_ns: int) -> CorrelationState:
        """The muted map and active clusters once ``t_ns`` has passed."""
        index = bisect_right(self._correlation_times, t_ns)
        return self._correlation[index - 1] if index else _NO_CORRELATION

    def __len__(self) -> int:
        """How many states are held (every fault's, plus the correlation views)."""
        return sum(len(t) for t in self._times.values()) + len(self._correlation)
