"""Correlation configuration values and upstream's validation of them, with its exact messages.

Pure: parsed from YAML by medkit_replay.config; here only dataclasses and checks.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import TYPE_CHECKING, Literal, TypeVar

if TYPE_CHECKING:
    from collections.abc import Mapping

_V = TypeVar("_V")

Mode = Literal["hierarchical", "auto_cluster"]


class Representative(Enum):
    """How an auto-cluster picks the fault it shows."""

    FIRST = "first"
    MOST_RECENT = "most_recent"
    HIGHEST_SEVERITY = "highest_severity"


_MODES: dict[str, Mode] = {
    "hierarchical": "hierarchical",
    "auto_cluster": "auto_cluster",
    "autocluster": "auto_cluster",
    "cluster": "auto_cluster",
}
_REPRESENTATIVES = {
    "first": Representative.FIRST,
    "most_recent": Representative.MOST_RECENT,
    "mostrecent": Representative.MOST_RECENT,
    "recent": Representative.MOST_RECENT,
    "highest_severity": Representative.HIGHEST_SEVERITY,
    "highestseverity": Representative.HIGHEST_SEVERITY,
    "severity": Representative.HIGHEST_SEVERITY,
}


def string_to_mode(value: str) -> Mode:
    """Case-insensitive mode name; raises ValueError with upstream's text otherwise."""
    return _named(_MODES, value, "correlation mode", "hierarchical, auto_cluster")


def string_to_representative(value: str) -> Representative:
    """Case-insensitive representative name; raises ValueError with upstream's text otherwise."""
    return _named(_REPRESENTATIVES, value, "representative", "first, most_recent, highest_severity")


def _named(names: Mapping[str, _V], value: str, what: str, valid: str) -> _V:
    found = names.get(value.lower())
    if found is None:
        msg = f"Invalid {what}: {value}. Valid values: {valid}"
        raise ValueError(msg)
    return found


@dataclass(frozen=True, slots=True, kw_only=True)
class CorrelationRule:
    """One rule of either mode; fields of the other mode keep their defaults."""

    id: str
    name: str
    mode: Mode = "hierarchical"
    window_ms: int = 500
    root_cause_codes: tuple[str, ...] = ()
    symptom_pattern_ids: tuple[str, ...] = ()
    inline_symptom_codes: tuple[str, ...] = ()
    mute_symptoms: bool = True
    auto_clear_with_root: bool = True
    match_pattern_ids: tuple[str, ...] = ()
    min_count: int = 3
    show_as_single: bool = True
    representative: Representative = Representative.HIGHEST_SEVERITY


@dataclass(frozen=True, slots=True, kw_only=True)
class CorrelationConfig:
    """The ``correlation:`` section; ``patterns`` keeps ascending id order like a std::map."""

    enabled: bool = False
    default_window_ms: int = 500
    patterns: dict[str, tuple[str, ...]] = field(default_factory=dict)
    rules: tuple[CorrelationRule, ...] = ()


@dataclass(frozen=True, slots=True)
class ValidationResult:
    """Errors make a config unusable; warnings do not."""

    errors: tuple[str, ...]
    warnings: tuple[str, ...]

    @property
    def valid(self) -> bool:
        """True when there are no errors."""
        return not self.errors


def validate_config(config: CorrelationConfig) -> ValidationResult:
    """Upstream's validate_config: same checks, same order, same texts (correlation.md §3)."""
    if not config.enabled:
        return ValidationResult((), ())
    errors: list[str] = []
    warnings: list[str] = []
    for pattern_id in sorted(config.patterns):
        if not config.patterns[pattern_id]:
            warnings.append(f"Pattern '{pattern_id}' has no codes defined")
    seen: set[str] = set()
    for rule in config.rules:
        if rule.id in seen:
            errors.append(f"Duplicate rule ID: {rule.id}")
        seen.add(rule.id)
        if not rule.id:
            errors.append("Rule missing 'id' field")
        if rule.mode == "hierarchical":
            if not rule.root_cause_codes:
                errors.append(f"Hierarchical rule '{rule.id}' has no root_cause codes")
            errors.extend(
                f"Rule '{rule.id}' references unknown pattern: {pid}"
                for pid in rule.symptom_pattern_ids
                if pid not in config.patterns
            )
            if not rule.symptom_pattern_ids and not rule.inline_symptom_codes:
                warnings.append(f"Hierarchical rule '{rule.id}' has no symptoms defined")
        else:
            errors.extend(
                f"Rule '{rule.id}' references unknown pattern: {pid}"
                for pid in rule.match_pattern_ids
                if pid not in config.patterns
            )
            if not rule.match_pattern_ids:
                warnings.append(f"Auto-cluster rule '{rule.id}' has no match patterns defined")
            if rule.min_count == 0:
                errors.append(f"Rule '{rule.id}' has min_count=0, must be at least 1")
            elif rule.min_count == 1:
                warnings.append(
                    f"Rule '{rule.id}' has min_count < 2, which may cause false clusters"
                )
        if rule.window_ms == 0:
            errors.append(f"Rule '{rule.id}' has window_ms=0")
        elif rule.window_ms > 60000:
            warnings.append(f"Rule '{rule.id}' has window_ms > 60s, which may be too long")
    if not config.rules:
        warnings.append("Correlation is enabled but no rules are defined")
    return ValidationResult(tuple(errors), tuple(warnings))
