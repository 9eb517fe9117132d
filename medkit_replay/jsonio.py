"""Strict JSON for untrusted text: a reader that refuses what is not strict JSON or cannot be held
safely, where in a text it refused, and values shown short; used by scripts and reports alike.
"""

from __future__ import annotations

import json
import math
import re
import sys
import traceback

# A script's numbers are int64 times and uint8 fields; a report's are int64 at most.
MAX_JSON_DIGITS = 40
_SHOWN = 60
# Reports nest about six levels, script lines two; the parser itself needs a few frames.
MAX_JSON_DEPTH = 64
# (two more with the object hook of a script line).
_PARSER_FRAMES = 5


class JsonRefusedError(ValueError):
    """JSON the strict reader refuses: NaN or Infinity, a number too long or out of the double
    range, a repeated key, nesting too deep for the parser, a lone surrogate."""


def _refuse_constant(name: str) -> object:
    raise JsonRefusedError(f"{name} is not JSON")


def _bounded_int(text: str) -> int:
    digits = len(text) - text.startswith("-")
    if digits > MAX_JSON_DIGITS:
        raise JsonRefusedError(f"a number of {digits:,} digits is too long")
    return int(text)


def _finite_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise JsonRefusedError(f"the number {shown(text)} is out of the double range")
    return value


def _unique_keys(pairs: list[tuple[str, object]]) -> dict[str, object]:
    result = dict(pairs)
    if len(result) != len(pairs):
        seen: set[str] = set()
        for key, _ in pairs:
            if key in seen:
                raise JsonRefusedError(f"the key {shown(key)} appears twice in one object")
            seen.add(key)
    return result


def _stack_depth() -> int:
    return sum(1 for _ in traceback.walk_stack(None))


def loads_strict(text: str, *, small: bool = False) -> object:
    """``json.loads`` that refuses what is not strict JSON or cannot be held safely.

    ``small`` (a script line) also refuses numbers past MAX_JSON_DIGITS digits and repeated
    keys, through per-value hooks too slow for a whole report; a report's numbers are bounded
    by Python's own limit on long integers instead, and its floats are always checked.

    Raises:
        json.JSONDecodeError: not JSON at all (with its position).
        JsonRefusedError: NaN/Infinity, a number too long or past the double range, nesting
            deeper than MAX_JSON_DEPTH, a repeated key (``small``).
    """
    # The parser counts its nesting against the interpreter's recursion limit: lowered for
    # the call, it refuses deep nesting at a fixed depth, cheaply, wherever it is called from.
    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(min(limit, _stack_depth() + MAX_JSON_DEPTH + _PARSER_FRAMES + 2 * small))
    try:
        return json.loads(
            text,
            parse_constant=_refuse_constant,
            parse_int=_bounded_int if small else None,
            parse_float=_finite_float,
            object_pairs_hook=_unique_keys if small else None,
        )
    except RecursionError:
        raise JsonRefusedError(f"the JSON nests deeper than {MAX_JSON_DEPTH} levels") from None
    except ValueError as err:
        if isinstance(err, json.JSONDecodeError | JsonRefusedError):
            raise
        # int() refuses more than sys.get_int_max_str_digits() digits.
        raise JsonRefusedError("a number is too long") from None
    finally:
        sys.setrecursionlimit(limit)


def unicode_problem(text: str) -> str | None:
    """What makes a decoded JSON string unfit for UTF-8 output (a lone surrogate), or None."""
    if text.isascii():
        return None
    try:
        text.encode("utf-8")
    except UnicodeEncodeError as err:
        return f"a lone surrogate \\u{ord(text[err.start]):04x} is not a Unicode character"
    return None


# Tokens outside strings that the strict reader can refuse, and strings (skipped whole).
_TOKEN = re.compile(
    r'"[^"\\]*(?:\\.[^"\\]*)*"|[\[{]|[\]}]|-?(?:NaN|Infinity)|-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?'
)
_SURROGATE_ESCAPE = re.compile(r"\\u[dD][89a-fA-F]")


def locate_refusal(text: str, max_digits: int = MAX_JSON_DIGITS) -> tuple[int | None, str | None]:
    """The line of the first thing in a parsed-or-refused JSON text the strict reader refuses,
    and what it is; (None, None) when there is none.

    For error messages only: walks the text token by token, so it runs once a refusal is
    known (or a lone surrogate is suspected), never on the way of a valid document.
    """
    depth = 0
    for match in _TOKEN.finditer(text):
        token = match.group()
        problem: str | None = None
        first = token[0]
        if first == '"':
            if _SURROGATE_ESCAPE.search(token) is not None:
                problem = unicode_problem(str(json.loads(token)))
        elif first in "[{":
            depth += 1
            if depth > MAX_JSON_DEPTH:
                problem = f"the JSON nests deeper than {MAX_JSON_DEPTH} levels"
        elif first in "]}":
            depth -= 1
        elif token.lstrip("-")[:1] in ("N", "I"):
            problem = f"{token} is not JSON"
        elif token.strip("-0123456789"):
            if not math.isfinite(float(token)):
                problem = f"the number {shown(token)} is out of the double range"
        elif len(token.lstrip("-")) > max_digits:
            problem = f"a number of {len(token.lstrip('-')):,} digits is too long"
        if problem is not None:
            return text.count("\n", 0, match.start()) + 1, problem
    return None, None


def shown(value: object) -> str:
    """A value for a message: short, one line, never the whole of a hostile value."""
    if isinstance(value, dict):
        return "an object"
    if isinstance(value, list):
        return "a list"
    text = ascii(value)
    return text if len(text) <= _SHOWN else f"{text[: _SHOWN - 3]}..."
