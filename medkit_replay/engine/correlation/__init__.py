"""Fault correlation as upstream's CorrelationEngine does it: rules, patterns, engine.

Pure: configuration values arrive parsed; times are bag-time nanoseconds.
"""

from __future__ import annotations

from medkit_replay.engine.correlation.engine import (
    CorrelationEngine,
    CorrelationResult,
    severity_name,
    severity_rank,
    trunc_ms,
)
from medkit_replay.engine.correlation.patterns import PatternMatcher, matches_any, matches_wildcard
from medkit_replay.engine.correlation.rules import (
    CorrelationConfig,
    CorrelationRule,
    Representative,
    ValidationResult,
    string_to_mode,
    string_to_representative,
    validate_config,
)

__all__ = [
    "CorrelationConfig",
    "CorrelationEngine",
    "CorrelationResult",
    "CorrelationRule",
    "PatternMatcher",
    "Representative",
    "ValidationResult",
    "matches_any",
    "matches_wildcard",
    "severity_name",
    "severity_rank",
    "string_to_mode",
    "string_to_representative",
    "trunc_ms",
    "validate_config",
]
