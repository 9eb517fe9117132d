"""The fault budget (``version: 1``) as plain values: rules, fault-code patterns and windows.

A budget is a list of rules, each of one kind with its parameters and a name (given or derived
here from what it asks). ``budget_file`` reads a budget YAML into these; the format is
documented in docs/budgets.md.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.model import SEVERITY_NAMES
from medkit_replay.text import severity_name
from medkit_replay.wildcards import Wildcard, compile_wildcard

if TYPE_CHECKING:
    from collections.abc import Sequence

BUDGET_VERSION = 1
"""The only budget format version this release reads."""

SEVERITIES = SEVERITY_NAMES
"""Severity names in ros2_medkit_msgs/Fault's order (their index is the severity number)."""

KINDS = (
    "max_confirmed",
    "never_confirm",
    "allow_confirm",
    "max_occurrences",
    "max_confirmed_duration_sec",
    "resolved_by_end",
    "expect_confirmed",
    "expect_not_confirmed",
    "expect_cluster",
)
"""Every rule kind, in the order docs/budgets.md describes them."""

_MAX_SHOWN = 3
"""Patterns named in a default rule name before "+N more"."""


# -- the model -----------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Pattern:
    """A fault-code glob: ``*`` any run of characters (also none), ``?`` exactly one character.

    Every other character stands for itself (case-sensitive); the whole code must match.
    """

    text: str
    matcher: Wildcard = field(compare=False, repr=False)

    @classmethod
    def of(cls, text: str) -> Pattern:
        """Compile a glob."""
        return cls(text, compile_wildcard(text, one="?"))

    def matches(self, code: str) -> bool:
        """Whether the whole ``code`` matches."""
        return self.matcher.matches(code)

    def __str__(self) -> str:
        return self.text


def matches_any(code: str, patterns: Sequence[Pattern]) -> Pattern | None:
    """The first pattern matching ``code``, or None."""
    return next((p for p in patterns if p.matches(code)), None)


@dataclass(frozen=True, slots=True)
class Window:
    """A closed span of time in seconds from the recording's start: ``[start_sec, end_sec]``."""

    start_sec: float
    end_sec: float

    def holds(self, offset_ns: int) -> bool:
        """Whether an offset from the recording's start (ns) lies in the window (ends included)."""
        return round(self.start_sec * 1e9) <= offset_ns <= round(self.end_sec * 1e9)

    def __str__(self) -> str:
        return f"between {seconds_text(self.start_sec)} and {seconds_text(self.end_sec)} s"


@dataclass(frozen=True, slots=True)
class MaxConfirmed:
    """At most ``limit`` faults of a severity confirmed during the run; (severity, limit) pairs."""

    limits: tuple[tuple[int, int], ...]


@dataclass(frozen=True, slots=True)
class NeverConfirm:
    """No fault matching one of the patterns may confirm."""

    patterns: tuple[Pattern, ...]


@dataclass(frozen=True, slots=True)
class AllowConfirm:
    """Only faults matching one of the patterns may confirm."""

    patterns: tuple[Pattern, ...]


@dataclass(frozen=True, slots=True)
class MaxOccurrences:
    """A fault matching a pattern may reach at most that ``occurrence_count``."""

    limits: tuple[tuple[Pattern, int], ...]


@dataclass(frozen=True, slots=True)
class MaxConfirmedDuration:
    """A fault matching a pattern may stay CONFIRMED at most that many seconds at a stretch."""

    limits: tuple[tuple[Pattern, float], ...]


@dataclass(frozen=True, slots=True)
class ResolvedByEnd:
    """A fault matching a pattern that confirmed must be HEALED or CLEARED at the end."""

    patterns: tuple[Pattern, ...]


@dataclass(frozen=True, slots=True)
class ExpectConfirmed:
    """A fault matching ``code`` confirms (within ``between``; muted by ``muted_by``)."""

    code: Pattern
    between: Window | None = None
    muted_by: Pattern | None = None


@dataclass(frozen=True, slots=True)
class ExpectNotConfirmed:
    """No fault matching ``code`` confirms (within ``between``, when given)."""

    code: Pattern
    between: Window | None = None


@dataclass(frozen=True, slots=True)
class ExpectCluster:
    """A cluster forms whose rule id matches ``rule`` or whose cluster id matches ``cluster``."""

    rule: Pattern | None = None
    cluster: Pattern | None = None


RuleSpec = (
    MaxConfirmed
    | NeverConfirm
    | AllowConfirm
    | MaxOccurrences
    | MaxConfirmedDuration
    | ResolvedByEnd
    | ExpectConfirmed
    | ExpectNotConfirmed
    | ExpectCluster
)


@dataclass(frozen=True, slots=True)
class Rule:
    """One rule of a budget: its name (given or derived), kind, parameters and place."""

    name: str
    kind: str
    spec: RuleSpec
    index: int
    """1-based position in the budget's ``rules`` list."""
    line: int | None = None
    """1-based line of the rule in the budget file."""


@dataclass(frozen=True, slots=True)
class Budget:
    """A parsed budget file."""

    path: str
    rules: tuple[Rule, ...]
    name: str | None = None
    version: int = BUDGET_VERSION
    allow_empty: bool = False
    """Let a replay that took nothing hold the budget (``--allow-empty``; no key of the file)."""

    @property
    def title(self) -> str:
        """The budget's name, else its file name."""
        return self.name if self.name else Path(self.path).name


# -- text helpers shared with the verdicts ---------------------------------------------------


def seconds_text(value: float) -> str:
    """Seconds as written in a budget: ``5``, ``2.5``, ``0.125``."""
    if value == int(value):
        return str(int(value))
    return f"{value:.9f}".rstrip("0").rstrip(".")


def _listing(items: Sequence[object]) -> str:
    shown = ", ".join(str(i) for i in items[:_MAX_SHOWN])
    return shown + (f" +{len(items) - _MAX_SHOWN} more" if len(items) > _MAX_SHOWN else "")


def default_name(spec: RuleSpec) -> str:
    """A rule's name when the budget gives none: what it asks, in a few words."""
    match spec:
        case MaxConfirmed(limits=limits):
            return "most confirmed: " + ", ".join(f"{severity_name(s)} {n}" for s, n in limits)
        case NeverConfirm(patterns=patterns):
            return f"never confirmed: {_listing(patterns)}"
        case AllowConfirm(patterns=patterns):
            return f"only allowed codes confirm: {_listing(patterns)}"
        case MaxOccurrences(limits=limits):
            return "most occurrences: " + _listing([f"{p} {n}" for p, n in limits])
        case MaxConfirmedDuration(limits=limits):
            return "longest CONFIRMED: " + _listing([f"{p} {seconds_text(s)} s" for p, s in limits])
        case ResolvedByEnd(patterns=patterns):
            return f"healed or cleared by the end: {_listing(patterns)}"
        case ExpectConfirmed(code=code, between=between, muted_by=muted_by):
            text = f"{code} confirmed"
            text += f" {between}" if between is not None else ""
            return text + (f", muted by {muted_by}" if muted_by is not None else "")
        case ExpectNotConfirmed(code=code, between=between):
            return f"{code} not confirmed" + (f" {between}" if between is not None else "")
        case ExpectCluster(rule=rule, cluster=cluster):
            return (
                f"cluster of rule {rule} formed"
                if rule is not None
                else f"cluster {cluster} formed"
            )
    raise AssertionError(spec)  # pragma: no cover  # every kind is matched above
