"""What a replay's Result says that a budget's rules ask about, indexed once per evaluation.

Confirmations, CONFIRMED stretches, final states, muting and clusters, with the times from the
recording's start; and the Offender, a fault that breaks a rule at some time.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from medkit_replay.text import seconds

if TYPE_CHECKING:
    from medkit_replay.model import FaultSnapshot
    from medkit_replay.result import Result


@dataclass(frozen=True, slots=True)
class Offender:
    """A fault that makes a rule fail, with the time it did so."""

    fault_code: str
    t_ns: int | None
    """Bag time of the offence (a confirmation, the start of a stretch, the last occurrence)."""
    offset_ns: int | None
    """The same time from the recording's start."""
    detail: str

    @property
    def at(self) -> str:
        """``78.372 s`` from the recording's start, or an empty string when there is no time."""
        return f"{seconds(self.offset_ns)} s" if self.offset_ns is not None else ""

    def text(self) -> str:
        """``CODE at 78.372 s: detail`` on one line."""
        when = f" at {self.at}" if self.at else ""
        return f"{self.fault_code}{when}: {self.detail}"


@dataclass(frozen=True, slots=True)
class FormedCluster:
    """A cluster that formed during the run, active at the end or not."""

    cluster_id: str
    rule_id: str
    first_at_ns: int | None
    fault_codes: tuple[str, ...]


class Facts:
    """Confirmations, CONFIRMED stretches, final states, muting and clusters of one Result."""

    def __init__(self, result: Result) -> None:
        self.start_ns, self.end_ns = result.span()
        self.faults: dict[str, FaultSnapshot] = {f.fault_code: f for f in result.faults}
        self.confirmations: dict[str, list[int]] = {}
        self.stretches: dict[str, list[tuple[int, int, bool]]] = {}
        """Per code: (from, to, still CONFIRMED at the end) of every CONFIRMED stretch."""
        open_since: dict[str, int] = {}
        for transition in result.transitions:
            code, t_ns = transition.fault_code, transition.t_ns
            if transition.to_status == "CONFIRMED":
                self.confirmations.setdefault(code, []).append(t_ns)
                open_since.setdefault(code, t_ns)
            elif code in open_since:
                since = open_since.pop(code)
                self.stretches.setdefault(code, []).append((since, t_ns, False))
        for code, since in open_since.items():
            end = max(self.end_ns if self.end_ns is not None else since, since)
            self.stretches.setdefault(code, []).append((since, end, True))
        self.muted_by: dict[str, set[str]] = {}
        for muted in result.muted_faults:
            self.muted_by.setdefault(muted.fault_code, set()).add(muted.root_cause_code)
        self.clusters: dict[str, FormedCluster] = {
            c.cluster_id: FormedCluster(c.cluster_id, c.rule_id, c.first_at_ns, c.fault_codes)
            for c in result.clusters
        }
        seen: dict[str, list[str]] = {}
        for event in result.events:
            fault = event.fault
            if fault.muted and fault.root_cause_code is not None:
                self.muted_by.setdefault(fault.fault_code, set()).add(fault.root_cause_code)
            for cluster_id in fault.cluster_ids:
                _add_member(seen, cluster_id, fault.fault_code)
        for fault in result.faults:
            for cluster_id in fault.cluster_ids:
                _add_member(seen, cluster_id, fault.fault_code)
        for mute in result.retroactive_mutes:
            for code in mute.fault_codes:
                _add_member(seen, mute.cluster_id, code)
        for cluster_id, codes in seen.items():
            if cluster_id not in self.clusters:  # formed, but no longer active at the end
                rule_id = cluster_id.rsplit("_", 1)[0]  # upstream's ids: "<rule id>_<counter>"
                self.clusters[cluster_id] = FormedCluster(cluster_id, rule_id, None, tuple(codes))

    def offset(self, t_ns: int | None) -> int | None:
        if t_ns is None or self.start_ns is None:
            return None
        return t_ns - self.start_ns

    def offender(self, code: str, t_ns: int | None, detail: str) -> Offender:
        return Offender(code, t_ns, self.offset(t_ns), detail)

    def confirmed_codes(self) -> list[str]:
        """Codes that confirmed at least once, by first confirmation, then code."""
        return sorted(self.confirmations, key=lambda c: (self.confirmations[c][0], c))

    def at(self, t_ns: int) -> str:
        offset = self.offset(t_ns)
        return f"{seconds(offset)} s" if offset is not None else "?"


def _add_member(seen: dict[str, list[str]], cluster_id: str, code: str) -> None:
    codes = seen.setdefault(cluster_id, [])
    if code not in codes:
        codes.append(code)
