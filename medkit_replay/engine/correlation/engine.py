"""Upstream's CorrelationEngine on bag time: root-cause windows, muting, auto-clusters, clears.

Pure and clock-free: every call carries its bag time in ns (correlation.md §5-§8).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from medkit_replay.engine.correlation.patterns import PatternMatcher, matches_any
from medkit_replay.engine.correlation.rules import (
    CorrelationConfig,
    CorrelationRule,
    Representative,
)
from medkit_replay.model import NS_PER_MS, Cluster, MutedFault

CORRELATION_SEVERITIES = {0: "INFO", 1: "WARNING", 2: "ERROR", 3: "CRITICAL"}
"""Upstream's severity_to_string: the spelling its correlation engine and ClusterInfo use."""
_RANKS = {"CRITICAL": 3, "3": 3, "ERROR": 2, "2": 2, "WARN": 1, "WARNING": 1, "1": 1}


def severity_name(severity: int) -> str:
    """The string the fault manager passes to the engine for a request severity."""
    return CORRELATION_SEVERITIES.get(severity, "UNKNOWN")


def severity_rank(severity: str) -> int:
    """Case-sensitive rank; unknown strings rank as INFO."""
    return _RANKS.get(severity, 0)


def _expiry_ns(t_ns: int, window_ms: int) -> int:
    """First instant at which an entry made at ``t_ns`` is outside its window."""
    return t_ns + (window_ms + 1) * NS_PER_MS


def trunc_ms(delta_ns: int) -> int:
    """Whole milliseconds of a duration, truncated toward zero like a chrono duration_cast."""
    return delta_ns // NS_PER_MS if delta_ns >= 0 else -((-delta_ns) // NS_PER_MS)


@dataclass(frozen=True, slots=True, kw_only=True)
class CorrelationResult:
    """What process_fault returns; only ``should_mute`` changes the node's behaviour."""

    should_mute: bool = False
    is_root_cause: bool = False
    root_cause_code: str = ""
    rule_id: str = ""
    delay_ms: int = 0
    cluster_id: str = ""
    retroactive_mute_codes: tuple[str, ...] = ()


@dataclass(frozen=True, slots=True)
class _CodeRoles:
    """What the rules make of one code; pattern matching is pure, so it is done once per code."""

    symptom_of: frozenset[str]
    root_rule: CorrelationRule | None
    cluster_rule: CorrelationRule | None


@dataclass(slots=True)
class _PendingRoot:
    code: str
    rule_id: str
    t_ns: int
    window_ms: int


@dataclass(slots=True)
class _PendingCluster:
    data: Cluster
    t_first_ns: int
    codes: list[str]
    severities: dict[str, str] = field(default_factory=dict)


class CorrelationEngine:
    """One engine for the whole replay, fed FAILED reports and clears in bag-time order."""

    def __init__(self, config: CorrelationConfig) -> None:
        self.config = config
        self._matcher = PatternMatcher(config.patterns)
        self._rules = {rule.id: rule for rule in config.rules}
        self._pending_roots: list[_PendingRoot] = []
        self._root_to_symptoms: dict[str, list[str]] = {}
        self._muted: dict[str, MutedFault] = {}
        self._pending_clusters: dict[str, _PendingCluster] = {}
        self._active_clusters: dict[str, Cluster] = {}
        self._fault_to_cluster: dict[str, str] = {}
        self._cluster_counter = 0
        # Derived indexes, kept in step with the state above; they change no result.
        self._clusters_of_code: dict[str, set[str]] = {}
        self._roles: dict[str, _CodeRoles] = {}
        self._next_root_expiry_ns: int | None = None

    # -- reports ---------------------------------------------------------------------------

    def process_fault(self, code: str, severity: str, t_ns: int) -> CorrelationResult:
        """Correlate one accepted FAILED report; precedence symptom, root, cluster (§6)."""
        self._prune_roots(t_ns)
        roles = self._roles_of(code)
        if roles.symptom_of:
            symptom = self._match_symptom(code, t_ns, roles.symptom_of)
            if symptom is not None:
                return symptom
        rule = roles.root_rule
        if rule is not None:
            self._pending_roots.append(_PendingRoot(code, rule.id, t_ns, rule.window_ms))
            self._root_to_symptoms[code] = []
            expiry = _expiry_ns(t_ns, rule.window_ms)
            if self._next_root_expiry_ns is None or expiry < self._next_root_expiry_ns:
                self._next_root_expiry_ns = expiry
            return CorrelationResult(is_root_cause=True, rule_id=rule.id)
        if roles.cluster_rule is not None:
            return self._cluster(roles.cluster_rule, code, severity, t_ns)
        return CorrelationResult()

    def _roles_of(self, code: str) -> _CodeRoles:
        roles = self._roles.get(code)
        if roles is None:
            hierarchical = [r for r in self.config.rules if r.mode == "hierarchical"]
            roles = _CodeRoles(
                symptom_of=frozenset(r.id for r in hierarchical if self._is_symptom(r, code)),
                root_rule=next(
                    (r for r in hierarchical if matches_any(code, r.root_cause_codes)), None
                ),
                cluster_rule=next(
                    (
                        r
                        for r in self.config.rules
                        if r.mode == "auto_cluster"
                        and any(self._matcher.matches(code, pid) for pid in r.match_pattern_ids)
                    ),
                    None,
                ),
            )
            self._roles[code] = roles
        return roles

    def _match_symptom(
        self, code: str, t_ns: int, symptom_of: frozenset[str]
    ) -> CorrelationResult | None:
        for entry in self._pending_roots:
            if entry.rule_id not in symptom_of:
                continue
            rule = self._rules[entry.rule_id]
            elapsed = trunc_ms(t_ns - entry.t_ns)
            if elapsed > rule.window_ms:
                continue
            delay_ms = elapsed % 2**32  # uint32 on the wire: a negative delay wraps (X15)
            symptoms = self._root_to_symptoms.setdefault(entry.code, [])
            if code not in symptoms:
                symptoms.append(code)
            if rule.mute_symptoms:
                self._muted[code] = MutedFault(
                    fault_code=code, root_cause_code=entry.code, rule_id=rule.id, delay_ms=delay_ms
                )
            return CorrelationResult(
                should_mute=rule.mute_symptoms,
                root_cause_code=entry.code,
                rule_id=rule.id,
                delay_ms=delay_ms,
            )
        return None

    def _is_symptom(self, rule: CorrelationRule, code: str) -> bool:
        return any(
            self._matcher.matches(code, pid) for pid in rule.symptom_pattern_ids
        ) or matches_any(code, rule.inline_symptom_codes)

    def _cluster(
        self, rule: CorrelationRule, code: str, severity: str, t_ns: int
    ) -> CorrelationResult:
        pending = self._pending_clusters.get(rule.id)
        if pending is not None and trunc_ms(t_ns - pending.t_first_ns) > rule.window_ms:
            # The window is fixed from the first member; the active copy (if any) stays.
            del self._pending_clusters[rule.id]
            pending = None
        if pending is None:
            self._cluster_counter += 1
            cluster_id = f"{rule.id}_{self._cluster_counter}"
            data = Cluster(
                cluster_id=cluster_id,
                rule_id=rule.id,
                rule_name=rule.name,
                label=rule.name,
                representative_code=code,
                representative_severity=severity,
                fault_codes=(code,),
                count=1,
                first_at_ns=t_ns,
                last_at_ns=t_ns,
            )
            self._pending_clusters[rule.id] = _PendingCluster(data, t_ns, [code], {code: severity})
            self._fault_to_cluster[code] = cluster_id
            return CorrelationResult(cluster_id=cluster_id)

        cluster_id = pending.data.cluster_id
        if code in pending.severities:
            mute = (
                rule.show_as_single
                and code != pending.data.representative_code
                and len(pending.codes) >= rule.min_count
            )
            return CorrelationResult(should_mute=mute, cluster_id=cluster_id)

        pending.codes.append(code)
        pending.severities[code] = severity
        rep_code = pending.data.representative_code
        rep_severity = pending.data.representative_severity
        if rule.representative is Representative.MOST_RECENT or (
            rule.representative is Representative.HIGHEST_SEVERITY
            and severity_rank(severity) > severity_rank(rep_severity)
        ):
            rep_code, rep_severity = code, severity
        pending.data = replace(
            pending.data,
            representative_code=rep_code,
            representative_severity=rep_severity,
            fault_codes=tuple(pending.codes),
            count=len(pending.codes),
            last_at_ns=t_ns,
        )
        self._fault_to_cluster[code] = cluster_id
        if len(pending.codes) < rule.min_count:
            return CorrelationResult(cluster_id=cluster_id)
        retro: tuple[str, ...] = ()
        if cluster_id not in self._active_clusters and rule.show_as_single:
            retro = tuple(c for c in pending.codes if c not in (rep_code, code))
        self._set_active(pending.data)
        return CorrelationResult(
            should_mute=rule.show_as_single and code != rep_code,
            cluster_id=cluster_id,
            retroactive_mute_codes=retro,
        )

    # -- clears ----------------------------------------------------------------------------

    def process_clear(self, code: str) -> list[str]:
        """Forget ``code`` as root, symptom and cluster member; return symptoms to auto-clear."""
        auto_cleared: list[str] = []
        symptoms = self._root_to_symptoms.pop(code, None)
        if symptoms is not None:
            if any(
                rule.mode == "hierarchical"
                and rule.auto_clear_with_root
                and matches_any(code, rule.root_cause_codes)
                for rule in self.config.rules
            ):
                auto_cleared = list(symptoms)
            for symptom in symptoms:
                self._muted.pop(symptom, None)
        self._pending_roots = [entry for entry in self._pending_roots if entry.code != code]
        cluster_id = self._fault_to_cluster.pop(code, None)
        if cluster_id is not None:
            self._remove_from_clusters(code, cluster_id)
        self._muted.pop(code, None)
        return auto_cleared

    def _remove_from_clusters(self, code: str, cluster_id: str) -> None:
        pending = next(
            (p for p in self._pending_clusters.values() if p.data.cluster_id == cluster_id), None
        )
        if pending is not None and code in pending.severities:
            pending.codes.remove(code)
            del pending.severities[code]
            if not pending.codes:
                del self._pending_clusters[pending.data.rule_id]
                pending = None
            else:
                data = replace(
                    pending.data, fault_codes=tuple(pending.codes), count=len(pending.codes)
                )
                if data.representative_code == code:
                    new_rep = self._reassign(pending)
                    data = replace(
                        data,
                        representative_code=new_rep,
                        representative_severity=pending.severities[new_rep],
                    )
                pending.data = data
        active = self._active_clusters.get(cluster_id)
        if active is None:
            return
        codes = tuple(c for c in active.fault_codes if c != code)
        if not codes:
            self._set_active(None, cluster_id)
            return
        active = replace(active, fault_codes=codes, count=len(codes))
        if active.representative_code == code and pending is not None:
            active = replace(
                active,
                representative_code=pending.data.representative_code,
                representative_severity=pending.data.representative_severity,
            )
        # Without a pending twin the representative keeps naming the cleared code (Q9).
        self._set_active(active)

    def _set_active(self, cluster: Cluster | None, cluster_id: str = "") -> None:
        """Write (or with None, delete) an active cluster and keep the code index in step."""
        cid = cluster.cluster_id if cluster is not None else cluster_id
        old = self._active_clusters.pop(cid, None)
        if old is not None:
            for member in old.fault_codes:
                ids = self._clusters_of_code[member]
                ids.discard(cid)
                if not ids:
                    del self._clusters_of_code[member]
        if cluster is not None:
            self._active_clusters[cid] = cluster
            for member in cluster.fault_codes:
                self._clusters_of_code.setdefault(member, set()).add(cid)

    def _reassign(self, pending: _PendingCluster) -> str:
        rule = self._rules[pending.data.rule_id]
        if rule.representative is Representative.FIRST:
            return pending.codes[0]
        if rule.representative is Representative.MOST_RECENT:
            return pending.codes[-1]
        best = pending.codes[0]
        for candidate in pending.codes[1:]:
            if severity_rank(pending.severities[candidate]) > severity_rank(
                pending.severities[best]
            ):
                best = candidate
        return best

    # -- timer -----------------------------------------------------------------------------

    def cleanup_expired(self, now_ns: int) -> None:
        """The cleanup timer: prune roots; drop expired pending clusters (§8)."""
        self._prune_roots(now_ns)
        for rule_id, pending in list(self._pending_clusters.items()):
            rule = self._rules[rule_id]
            if trunc_ms(now_ns - pending.t_first_ns) > rule.window_ms:
                if pending.data.cluster_id not in self._active_clusters:
                    for member in pending.codes:
                        self._fault_to_cluster.pop(member, None)
                del self._pending_clusters[rule_id]

    def _prune_roots(self, now_ns: int) -> None:
        # Only rebuild the list once the earliest entry can have expired.
        if self._next_root_expiry_ns is None or now_ns < self._next_root_expiry_ns:
            return
        self._pending_roots = [
            entry
            for entry in self._pending_roots
            if trunc_ms(now_ns - entry.t_ns) <= entry.window_ms
        ]
        self._next_root_expiry_ns = min(
            (_expiry_ns(e.t_ns, e.window_ms) for e in self._pending_roots), default=None
        )

    # -- queries ---------------------------------------------------------------------------

    def muted_faults(self) -> list[MutedFault]:
        """Muted symptoms in fault_code byte order."""
        return [self._muted[c] for c in sorted(self._muted, key=lambda c: c.encode("utf-8"))]

    def muted_entry(self, code: str) -> MutedFault | None:
        """The muted entry of one code, if it is a muted symptom."""
        return self._muted.get(code)

    def clusters(self) -> list[Cluster]:
        """Active clusters in cluster_id byte order."""
        ids = sorted(self._active_clusters, key=lambda c: c.encode("utf-8"))
        return [self._active_clusters[c] for c in ids]

    def cluster_ids_of(self, code: str) -> tuple[str, ...]:
        """Ids of the active clusters listing ``code``, in byte order."""
        ids = self._clusters_of_code.get(code)
        if not ids:
            return ()
        return tuple(sorted(ids, key=lambda c: c.encode("utf-8")))

    def cluster_rule_of(self, code: str) -> CorrelationRule | None:
        """The auto-cluster rule a code would join (the first whose patterns match it)."""
        return self._roles_of(code).cluster_rule

    @property
    def muted_count(self) -> int:
        """Entries in the muted map (cluster mutes never count)."""
        return len(self._muted)

    @property
    def cluster_count(self) -> int:
        """Active clusters (pending ones never count)."""
        return len(self._active_clusters)
