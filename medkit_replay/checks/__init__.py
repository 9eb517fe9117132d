"""Fault budgets: the budget file (model and strict parser) and the verdicts on a replay's Result.

``budget`` is the budget as plain values and ``budget_file`` reads a budget YAML into them;
``facts`` indexes a Result once and ``evaluate`` turns it and a budget into one Verdict per rule;
``terminal``, ``junit`` and ``github`` write verdicts out. The format is documented in
docs/budgets.md; ``budget.schema.json`` beside this file is its JSON Schema.
"""

from __future__ import annotations

from medkit_replay.checks.budget import Budget, Rule
from medkit_replay.checks.budget_file import load_budget, parse_budget
from medkit_replay.checks.evaluate import (
    CheckRun,
    Verdict,
    check_run,
    evaluate,
    failed_rules,
    nothing_replayed,
)
from medkit_replay.checks.facts import Offender

__all__ = [
    "Budget",
    "CheckRun",
    "Offender",
    "Rule",
    "Verdict",
    "check_run",
    "evaluate",
    "failed_rules",
    "load_budget",
    "nothing_replayed",
    "parse_budget",
]
