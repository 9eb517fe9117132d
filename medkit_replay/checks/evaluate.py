"""Verdicts of a fault budget on one replay: one Verdict per rule, with the offending faults.

Pure: reads only the Result (transitions, faults, events, muting and clusters) and the Budget;
no I/O, no clock. The exact meaning of every rule is documented in docs/budgets.md.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from medkit_replay.checks.budget import (
    SEVERITIES,
    AllowConfirm,
    ExpectCluster,
    ExpectConfirmed,
    ExpectNotConfirmed,
    MaxConfirmed,
    MaxConfirmedDuration,
    MaxOccurrences,
    NeverConfirm,
    Pattern,
    ResolvedByEnd,
    matches_any,
    seconds_text,
)
from medkit_replay.checks.facts import Facts, Offender
from medkit_replay.model import strict_failure
from medkit_replay.releases import DEFAULT_RELEASE
from medkit_replay.text import seconds, severity_name

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Sequence

    from medkit_replay.checks.budget import Budget, Rule, RuleSpec
    from medkit_replay.checks.facts import FormedCluster
    from medkit_replay.model import Loss
    from medkit_replay.result import Result

RESOLVED = ("HEALED", "CLEARED")
"""Final statuses that count as healed or cleared by the end."""


@dataclass(frozen=True, slots=True)
class Verdict:
    """Whether one rule held on one run, in one line, and which faults broke it."""

    rule: Rule
    passed: bool
    message: str
    offenders: tuple[Offender, ...] = ()


@dataclass(frozen=True, slots=True)
class CheckRun:
    """A budget checked on one run (one input, or several merged as one recording)."""

    label: str
    inputs: tuple[str, ...]
    budget: Budget
    verdicts: tuple[Verdict, ...]
    warnings: tuple[str, ...] = ()
    error: str | None = None
    """Why the run was not checked (one line): its recording could not be replayed, or
    nothing in it reached the fault manager (``empty``); then it has no verdicts and fails."""
    empty: bool = False
    losses: tuple[Loss, ...] = ()
    """What damage cost, in total per input that lost anything (each also in ``warnings``)."""
    strict: bool = False
    """Damage fails the run (``--strict``)."""
    upstream_release: str = DEFAULT_RELEASE
    """The ros2_medkit release the run was replayed as (``medkit_replay.upstream_release``)."""

    @property
    def passed(self) -> bool:
        """The run was replayed, every rule held and (under ``--strict``) nothing was lost."""
        return self.error is None and not self.damage and all(v.passed for v in self.verdicts)

    @property
    def damage(self) -> tuple[str, ...]:
        """Under ``--strict``, why damage fails the run: one line per input read in part."""
        return tuple(strict_failure(loss) for loss in self.losses) if self.strict else ()

    @property
    def failures(self) -> tuple[Verdict, ...]:
        """The verdicts of the rules that did not hold."""
        return tuple(v for v in self.verdicts if not v.passed)


def check_run(
    budget: Budget, result: Result, inputs: Sequence[str], *, strict: bool = False
) -> CheckRun:
    """The budget's verdicts on a replay of ``inputs``, labelled for the outputs (``strict``:
    what damage cost fails the run); a replay that took nothing is a failed run saying what
    was missing (see :func:`nothing_replayed`)."""
    label = " + ".join(inputs)
    empty = nothing_replayed(budget, result)
    if empty is not None:
        return CheckRun(
            label=label,
            inputs=tuple(inputs),
            budget=budget,
            verdicts=(),
            warnings=result.warnings,
            error=f"{label}: {empty}",
            empty=True,
            losses=result.losses_by_input(),
            strict=strict,
            upstream_release=result.upstream_release,
        )
    return CheckRun(
        label=label,
        inputs=tuple(inputs),
        budget=budget,
        verdicts=evaluate(budget, result),
        warnings=result.warnings,
        losses=result.losses_by_input(),
        strict=strict,
        upstream_release=result.upstream_release,
    )


def nothing_replayed(budget: Budget, result: Result) -> str | None:
    """Why no budget holds on this replay: nothing in the recording reached a path that can
    raise a fault (no bridge saw its topic, no recorded call, nothing readable), in one line
    saying what was missing; None when something did, or the budget allows it."""
    consumed = result.consumed
    if budget.allow_empty or consumed is None or not consumed.empty:
        return None
    return consumed.nothing_replayed()


def failed_rules(budget: Budget, result: Result) -> tuple[str, ...]:
    """What fails the budget on one replay, as fleet and sweep rows list it: the line of
    :func:`nothing_replayed` alone, else the names of the rules that did not hold."""
    empty = nothing_replayed(budget, result)
    if empty is not None:
        return (empty,)
    return tuple(v.rule.name for v in evaluate(budget, result) if not v.passed)


def unreadable_run(
    budget: Budget, inputs: Sequence[str], error: str, release: str = DEFAULT_RELEASE
) -> CheckRun:
    """A run whose recording could not be replayed (as ``release``): no verdicts, failed,
    saying why."""
    return CheckRun(
        label=" + ".join(inputs),
        inputs=tuple(inputs),
        budget=budget,
        verdicts=(),
        error=error,
        upstream_release=release,
    )


def evaluate(budget: Budget, result: Result) -> tuple[Verdict, ...]:
    """One Verdict per rule of the budget, in the budget's order."""
    facts = Facts(result)
    return tuple(_verdict(rule, facts) for rule in budget.rules)


def _faults(count: int) -> str:
    return f"{count} fault" + ("" if count == 1 else "s")


def _patterns(patterns: Iterable[Pattern]) -> str:
    return ", ".join(str(p) for p in patterns)


def _held_unless(rule: Rule, offenders: list[Offender], broke: str, held: str) -> Verdict:
    """Failed, with its offenders in time order and '<N faults> ``broke``', when any fault broke
    the rule; else passed, saying ``held``."""
    if offenders:
        return Verdict(rule, False, f"{_faults(len(offenders))} {broke}", _sorted(offenders))
    return Verdict(rule, True, held)


def _sorted(offenders: Iterable[Offender]) -> tuple[Offender, ...]:
    return tuple(
        sorted(
            offenders,
            key=lambda o: (o.t_ns is None, o.t_ns if o.t_ns is not None else 0, o.fault_code),
        )
    )


# -- the rules ---------------------------------------------------------------------------------


def _severity_of(facts: Facts, code: str) -> int:
    fault = facts.faults.get(code)
    return fault.severity if fault is not None else 0


def _max_confirmed(rule: Rule, spec: MaxConfirmed, facts: Facts) -> Verdict:
    by_severity: dict[int, list[str]] = {}
    for code in facts.confirmed_codes():
        by_severity.setdefault(_severity_of(facts, code), []).append(code)
    over: list[str] = []
    within: list[str] = []
    offenders: list[Offender] = []
    for severity, limit in spec.limits:
        codes = by_severity.get(severity, [])
        name = SEVERITIES[severity]
        if len(codes) > limit:
            over.append(f"{name} {len(codes)} confirmed, at most {limit} allowed")
            offenders += [
                facts.offender(code, facts.confirmations[code][0], f"{name}, confirmed")
                for code in codes
            ]
        else:
            within.append(f"{name} {len(codes)} of at most {limit}")
    if over:
        return Verdict(rule, False, "; ".join(over), _sorted(offenders))
    return Verdict(rule, True, "confirmed: " + ", ".join(within))


def _never_confirm(rule: Rule, spec: NeverConfirm, facts: Facts) -> Verdict:
    offenders = []
    for code in facts.confirmed_codes():
        pattern = matches_any(code, spec.patterns)
        if pattern is not None:
            times = facts.confirmations[code]
            detail = f"confirmed ({pattern} must never confirm)"
            if len(times) > 1:
                detail = f"confirmed {len(times)} times ({pattern} must never confirm)"
            offenders.append(facts.offender(code, times[0], detail))
    held = f"no fault matching {_patterns(spec.patterns)} confirmed"
    return _held_unless(rule, offenders, "confirmed that must never confirm", held)


def _allow_confirm(rule: Rule, spec: AllowConfirm, facts: Facts) -> Verdict:
    confirmed = facts.confirmed_codes()
    offenders = [
        facts.offender(
            code,
            facts.confirmations[code][0],
            f"{severity_name(_severity_of(facts, code))}, confirmed but not allowed to",
        )
        for code in confirmed
        if matches_any(code, spec.patterns) is None
    ]
    held = f"{_faults(len(confirmed))} confirmed, all allowed"
    return _held_unless(rule, offenders, "confirmed that no allowed pattern matches", held)


def _max_occurrences(rule: Rule, spec: MaxOccurrences, facts: Facts) -> Verdict:
    offenders: list[Offender] = []
    highest: tuple[int, str] | None = None
    for pattern, limit in spec.limits:
        for code, fault in facts.faults.items():
            if not pattern.matches(code):
                continue
            count = fault.occurrence_count
            if count > limit:
                detail = f"{count} occurrences, at most {limit} allowed ({pattern})"
                offenders.append(facts.offender(code, fault.last_occurred_ns, detail))
            elif highest is None or count > highest[0]:
                highest = (count, code)
    held = (
        "no fault matching the patterns was reported"
        if highest is None
        else f"within limits; highest: {highest[1]} with {highest[0]} occurrence(s)"
    )
    return _held_unless(rule, offenders, "occurred more often than allowed", held)


def _longest(facts: Facts, code: str) -> tuple[int, int, bool] | None:
    stretches = facts.stretches.get(code)
    if not stretches:
        return None
    return max(stretches, key=lambda s: (s[1] - s[0], -s[0]))


def _max_duration(rule: Rule, spec: MaxConfirmedDuration, facts: Facts) -> Verdict:
    offenders: list[Offender] = []
    longest_seen: tuple[int, str] | None = None
    for pattern, limit in spec.limits:
        limit_ns = round(limit * 1e9)
        for code in facts.confirmed_codes():
            longest = _longest(facts, code) if pattern.matches(code) else None
            if longest is None:
                continue
            since, until, still = longest
            length = until - since
            if length > limit_ns:
                detail = (
                    f"CONFIRMED for {seconds(length)} s, at most {seconds_text(limit)} s "
                    f"allowed ({pattern})"
                )
                if still:
                    detail += "; still CONFIRMED at the end of the recording"
                else:
                    detail += f"; until {facts.at(until)}"
                offenders.append(facts.offender(code, since, detail))
            elif longest_seen is None or length > longest_seen[0]:
                longest_seen = (length, code)
    held = (
        "no fault matching the patterns confirmed"
        if longest_seen is None
        else f"within limits; longest: {longest_seen[1]} for {seconds(longest_seen[0])} s"
    )
    return _held_unless(rule, offenders, "stayed CONFIRMED longer than allowed", held)


def _resolved_by_end(rule: Rule, spec: ResolvedByEnd, facts: Facts) -> Verdict:
    offenders: list[Offender] = []
    checked = 0
    for code in facts.confirmed_codes():
        if matches_any(code, spec.patterns) is None:
            continue
        checked += 1
        fault = facts.faults.get(code)
        status = fault.status if fault is not None else "unknown"
        if status not in RESOLVED:
            last = facts.confirmations[code][-1]
            detail = f"confirmed, still {status} at the end"
            offenders.append(facts.offender(code, last, detail))
    held = (
        f"{_faults(checked)} confirmed, all healed or cleared by the end"
        if checked
        else f"no fault matching {_patterns(spec.patterns)} confirmed"
    )
    return _held_unless(rule, offenders, "not healed or cleared by the end", held)


def _in_window(facts: Facts, t_ns: int, spec: ExpectConfirmed | ExpectNotConfirmed) -> bool:
    if spec.between is None:
        return True
    offset = facts.offset(t_ns)
    return offset is not None and spec.between.holds(offset)


def _expect_confirmed(rule: Rule, spec: ExpectConfirmed, facts: Facts) -> Verdict:
    seen = [
        (t_ns, code)
        for code in facts.confirmed_codes()
        if spec.code.matches(code)
        for t_ns in facts.confirmations[code]
    ]
    seen.sort()
    inside = [(t, code) for t, code in seen if _in_window(facts, t, spec)]
    window = f" {spec.between}" if spec.between is not None else ""
    if not seen:
        return Verdict(rule, False, f"no fault matching {spec.code} confirmed")
    if not inside:
        offenders = [facts.offender(code, t, "confirmed outside the window") for t, code in seen]
        return Verdict(rule, False, f"{spec.code} confirmed, but not{window}", _sorted(offenders))
    if spec.muted_by is not None:
        muted_by = spec.muted_by
        hits = [
            (t, code)
            for t, code in inside
            if any(muted_by.matches(root) for root in facts.muted_by.get(code, ()))
        ]
        if not hits:
            offenders = [
                facts.offender(
                    code,
                    t,
                    "muted by " + ", ".join(sorted(facts.muted_by[code]))
                    if facts.muted_by.get(code)
                    else "never muted by a root cause",
                )
                for t, code in inside
            ]
            message = f"{spec.code} confirmed{window}, but not muted by {muted_by}"
            return Verdict(rule, False, message, _sorted(offenders))
        t_ns, code = hits[0]
        roots = ", ".join(sorted(r for r in facts.muted_by[code] if muted_by.matches(r)))
        return Verdict(rule, True, f"{code} confirmed at {facts.at(t_ns)}, muted by {roots}")
    t_ns, code = inside[0]
    return Verdict(rule, True, f"{code} confirmed at {facts.at(t_ns)}{window}")


def _expect_not_confirmed(rule: Rule, spec: ExpectNotConfirmed, facts: Facts) -> Verdict:
    window = f" {spec.between}" if spec.between is not None else ""
    offenders = [
        facts.offender(code, t_ns, "confirmed")
        for code in facts.confirmed_codes()
        if spec.code.matches(code)
        for t_ns in facts.confirmations[code]
        if _in_window(facts, t_ns, spec)
    ]
    if offenders:
        return Verdict(rule, False, f"{spec.code} confirmed{window}", _sorted(offenders))
    return Verdict(rule, True, f"no fault matching {spec.code} confirmed{window}")


def _expect_cluster(rule: Rule, spec: ExpectCluster, facts: Facts) -> Verdict:
    def wanted(cluster: FormedCluster) -> bool:
        if spec.rule is not None:
            return spec.rule.matches(cluster.rule_id)
        return spec.cluster is not None and spec.cluster.matches(cluster.cluster_id)

    ids = sorted(facts.clusters, key=lambda c: c.encode("utf-8"))
    formed = [facts.clusters[c] for c in ids if wanted(facts.clusters[c])]
    what = f"of rule {spec.rule}" if spec.rule is not None else f"matching {spec.cluster}"
    if not formed:
        others = ", ".join(ids) if ids else "none"
        return Verdict(rule, False, f"no cluster {what} formed (clusters formed: {others})")
    cluster = formed[0]
    when = f" at {facts.at(cluster.first_at_ns)}" if cluster.first_at_ns is not None else ""
    members = ", ".join(cluster.fault_codes)
    return Verdict(
        rule,
        True,
        f"{cluster.cluster_id} formed{when} (rule {cluster.rule_id}: {members})",
    )


_VERDICTS: dict[type[RuleSpec], Callable[[Rule, Any, Facts], Verdict]] = {
    MaxConfirmed: _max_confirmed,
    NeverConfirm: _never_confirm,
    AllowConfirm: _allow_confirm,
    MaxOccurrences: _max_occurrences,
    MaxConfirmedDuration: _max_duration,
    ResolvedByEnd: _resolved_by_end,
    ExpectConfirmed: _expect_confirmed,
    ExpectNotConfirmed: _expect_not_confirmed,
    ExpectCluster: _expect_cluster,
}
"""The verdict of each kind of rule, by the type of its spec."""


def _verdict(rule: Rule, facts: Facts) -> Verdict:
    return _VERDICTS[type(rule.spec)](rule, rule.spec, facts)
