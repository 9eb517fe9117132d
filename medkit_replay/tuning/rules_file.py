"""A suggestion written as a correlation file in upstream's schema (correlation.md §2), each rule
with its evidence as YAML comments; the file ``correlation.config_file`` may point at.

Pure text: codes are written as double-quoted YAML strings (JSON escapes), so a code can never
break the file's structure.
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING

from medkit_replay.tuning.suggest import rule_id

if TYPE_CHECKING:
    from medkit_replay.tuning.suggest import Suggestion


def _quoted(text: str) -> str:
    return json.dumps(text, ensure_ascii=True)


def _codes(codes: list[str] | tuple[str, ...]) -> str:
    return "[" + ", ".join(_quoted(c) for c in codes) + "]"


def rules_yaml(suggestion: Suggestion) -> str:
    """The correlation file (``enabled: true``, patterns for the bursts, the rules)."""
    s = suggestion
    lines = [
        "# Correlation rules proposed by medkit-replay suggest-rules (review before deploying).",
        f"# Learned from {s.runs:,} run(s): window {s.window_ms} ms, min support {s.min_support} "
        f"run(s), min confidence {s.min_confidence:g}.",
        "# support: runs the pattern was seen in; confidence: share of the runs where the later",
        "# code confirmed that the pattern explains (cascade: the root confirmed just before).",
        "correlation:",
        "  enabled: true",
        f"  default_window_ms: {s.window_ms}",
    ]
    used: set[str] = set()
    burst_ids = [rule_id("burst", burst.codes[0], used) for burst in s.bursts]
    if s.bursts:
        lines.append("  patterns:")
        for pattern, burst in zip(burst_ids, s.bursts, strict=True):
            lines += [f"    {pattern}:", f"      codes: {_codes(burst.codes)}"]
    else:
        lines.append("  patterns: {}")
    if not s.cascades and not s.bursts:
        lines.append("  rules: []  # nothing in these runs met the thresholds")
        return "\n".join(lines) + "\n"
    lines.append("  rules:")
    for cascade in s.cascades:
        worst = min(x.confidence for x in cascade.symptoms)
        lines += [
            f"    # {cascade.root} confirmed in {cascade.root_runs:,} run(s); each symptom "
            "confirmed after it within the window:",
        ]
        lines += [
            f"    #   {symptom.code}: support {symptom.support:,} run(s), confidence "
            f"{symptom.confidence:.2f} ({symptom.support:,}/{symptom.confirmed_runs:,}), "
            f"longest delay {symptom.max_delay_ms:,} ms"
            for symptom in cascade.symptoms
        ]
        lines += [
            f"    - id: {rule_id('cascade', cascade.root, used)}",
            f"      name: {_quoted(f'{cascade.root} drags its symptoms')}",
            "      mode: hierarchical",
            f"      root_cause: {{codes: {_codes([cascade.root])}}}",
            f"      symptoms: [{{codes: {_codes([x.code for x in cascade.symptoms])}}}]",
            f"      window_ms: {cascade.window_ms}  # support "
            f"{max(x.support for x in cascade.symptoms):,}, confidence {worst:.2f}",
            "      mute_symptoms: true",
            "      auto_clear_with_root: true",
        ]
    for pattern, burst in zip(burst_ids, s.bursts, strict=True):
        lines += [
            f"    # {len(burst.codes)} codes confirming together: support {burst.support:,} "
            f"run(s), confidence {burst.confidence:.2f}, widest gap {burst.spread_ms:,} ms",
            f"    - id: {pattern}",
            f"      name: {_quoted('Burst of ' + ', '.join(burst.codes))}",
            "      mode: auto_cluster",
            f"      match: [{{pattern: {pattern}}}]",
            "      min_count: 2",
            f"      window_ms: {burst.window_ms}  # support {burst.support:,}, confidence "
            f"{burst.confidence:.2f}",
            "      show_as_single: true",
            "      representative: highest_severity",
        ]
    return "\n".join(lines) + "\n"
