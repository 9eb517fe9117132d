"""The JSON report as the standard library writes it: the encoder the report had before it was
encoded in bulk, kept as the oracle its bytes are held to.

It renders ``to_report``'s dict: small sections indented by ``json.dumps``, the long record
lists one record per line through a C ``JSONEncoder`` with ``", "`` and ``": "``.
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING

from medkit_replay.outputs.json_report import to_report

if TYPE_CHECKING:
    from medkit_replay.result import Result

ROW_KEYS = frozenset({"events", "transitions", "reports", "clears", "near_misses"})
"""The report's long lists: one record per line."""

_ROW = json.JSONEncoder(ensure_ascii=True, separators=(", ", ": "), allow_nan=False)


def _dump(value: object, indent: str) -> str:
    text = json.dumps(value, indent=2, ensure_ascii=True, allow_nan=False)
    return text.replace("\n", "\n" + indent)


def stdlib_dumps(result: Result, row_keys: frozenset[str] = ROW_KEYS) -> str:
    """The whole report as the stdlib encoder writes it."""
    parts = ["{"]
    for number, (key, value) in enumerate(to_report(result).items()):
        parts.append(("," if number else "") + f"\n  {json.dumps(key)}: ")
        if key not in row_keys:
            parts.append(_dump(value, "  "))
            continue
        assert isinstance(value, list)
        rows = [_ROW.encode(item) for item in value]
        parts.append("[\n    " + ",\n    ".join(rows) + "\n  ]" if rows else "[]")
    parts.append("\n}\n")
    return "".join(parts)
