"""JSON-lines scripts (cli-and-report.md §4): ReportFault and ClearFault requests with bag times.

Parses and checks every line with the strict JSON reader (jsonio); a bad line is an InputError
naming the file and line.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import IO, TYPE_CHECKING

from medkit_replay.errors import InputError
from medkit_replay.files import FileRefusedError, open_regular
from medkit_replay.jsonio import JsonRefusedError, loads_strict, shown, unicode_problem
from medkit_replay.model import ClearRequest, ReportRequest

if TYPE_CHECKING:
    from collections.abc import Iterator
    from pathlib import Path

MAX_LINE_BYTES = 1 << 20
T_NS_LIMIT = 1 << 63
_EVENT_TYPES = {"FAILED": 0, "PASSED": 1}
_REPORT_KEYS = {"t_ns", "op", "fault_code", "event_type", "severity", "description", "source_id"}
_CLEAR_KEYS = {"t_ns", "op", "fault_code", "skip_correlation_auto_clear"}
_UINT8_MAX = 255


@dataclass(frozen=True, slots=True)
class ScriptLine:
    """One request of a script and the line it came from."""

    line: int
    request: ReportRequest | ClearRequest


def _int_field(
    obj: dict[str, object],
    key: str,
    where: tuple[str, int],
    *,
    default: int | None = None,
    maximum: int | None = None,
) -> int:
    value = obj.get(key, default)
    if value is None:
        raise InputError(f"missing {key!r}", path=where[0], line=where[1])
    if isinstance(value, bool) or not isinstance(value, int):
        raise InputError(
            f"{key!r} must be an integer, got {shown(value)}", path=where[0], line=where[1]
        )
    if maximum is None and value >= T_NS_LIMIT:
        raise InputError(
            f"{key!r} must be below 2^63 (int64 nanoseconds), got {shown(value)}",
            path=where[0],
            line=where[1],
        )
    if value < 0 or (maximum is not None and value > maximum):
        bound = f"0..{maximum}" if maximum is not None else ">= 0"
        raise InputError(
            f"{key!r} must be in {bound}, got {shown(value)}", path=where[0], line=where[1]
        )
    return value


def _str_field(
    obj: dict[str, object], key: str, where: tuple[str, int], default: str | None = None
) -> str:
    value = obj.get(key, default)
    if value is None:
        raise InputError(f"missing {key!r}", path=where[0], line=where[1])
    if not isinstance(value, str):
        raise InputError(
            f"{key!r} must be a string, got {shown(value)}", path=where[0], line=where[1]
        )
    problem = unicode_problem(value)
    if problem is not None:
        raise InputError(f"{key!r}: {problem}", path=where[0], line=where[1])
    return value


def parse_line(obj: dict[str, object], where: tuple[str, int]) -> ReportRequest | ClearRequest:
    """Turn one decoded script object into a request; raises InputError on any problem."""
    op = obj.get("op")
    t_ns = _int_field(obj, "t_ns", where)
    code = _str_field(obj, "fault_code", where)
    if op == "report":
        unknown = sorted(set(obj) - _REPORT_KEYS)
        if unknown:
            raise InputError(
                f"unknown key(s) {_keys(unknown)} for op 'report'", path=where[0], line=where[1]
            )
        raw_event = obj.get("event_type")
        if isinstance(raw_event, str):
            if raw_event not in _EVENT_TYPES:
                raise InputError(
                    f"'event_type' must be FAILED, PASSED or 0..255, got {shown(raw_event)}",
                    path=where[0],
                    line=where[1],
                )
            event_type = _EVENT_TYPES[raw_event]
        else:
            event_type = _int_field(obj, "event_type", where, maximum=_UINT8_MAX)
        return ReportRequest(
            t_ns=t_ns,
            fault_code=code,
            event_type=event_type,
            severity=_int_field(obj, "severity", where, default=0, maximum=_UINT8_MAX),
            description=_str_field(obj, "description", where, ""),
            source_id=_str_field(obj, "source_id", where),
            origin="script",
        )
    if op == "clear":
        unknown = sorted(set(obj) - _CLEAR_KEYS)
        if unknown:
            raise InputError(
                f"unknown key(s) {_keys(unknown)} for op 'clear'", path=where[0], line=where[1]
            )
        skip = obj.get("skip_correlation_auto_clear", False)
        if not isinstance(skip, bool):
            raise InputError(
                f"'skip_correlation_auto_clear' must be true or false, got {shown(skip)}",
                path=where[0],
                line=where[1],
            )
        return ClearRequest(
            t_ns=t_ns, fault_code=code, skip_correlation_auto_clear=skip, origin="script"
        )
    raise InputError(
        f"unknown op {shown(op)} (expected 'report' or 'clear')", path=where[0], line=where[1]
    )


def _keys(keys: list[str]) -> str:
    """Unknown keys for a message: the first few, each cut short."""
    listed = ", ".join(shown(key) for key in keys[:5])
    return f"[{listed}{', ...' if len(keys) > 5 else ''}]"


def iter_script(stream: IO[bytes], path: str) -> Iterator[ScriptLine]:
    """Yield each request of a script in file order; times must not decrease."""
    last_t: int | None = None
    for number, raw in enumerate(iter(lambda: stream.readline(MAX_LINE_BYTES + 1), b""), 1):
        if len(raw) > MAX_LINE_BYTES:
            raise InputError(f"line longer than {MAX_LINE_BYTES} bytes", path=path, line=number)
        try:
            text = raw.decode("utf-8").strip()
        except UnicodeDecodeError:
            raise InputError("line is not UTF-8", path=path, line=number) from None
        if not text or text.startswith("#"):
            continue
        try:
            obj = loads_strict(text, small=True)
        except json.JSONDecodeError as err:
            raise InputError(
                f"invalid JSON: {err.msg} (column {err.colno})", path=path, line=number
            ) from None
        except JsonRefusedError as err:
            raise InputError(f"invalid JSON: {err}", path=path, line=number) from None
        if not isinstance(obj, dict):
            raise InputError("expected a JSON object", path=path, line=number)
        request = parse_line(obj, (path, number))
        if last_t is not None and request.t_ns < last_t:
            raise InputError(
                f"t_ns {request.t_ns} is earlier than the previous line's "
                f"{last_t}; script times must not decrease",
                path=path,
                line=number,
            )
        last_t = request.t_ns
        yield ScriptLine(number, request)


def open_script(path: Path) -> Iterator[ScriptLine]:
    """Read a script file lazily, read-only."""
    try:
        stream = open_regular(path)
    except FileRefusedError as err:
        raise InputError(f"cannot open script: {err}", path=str(path)) from None
    except OSError as err:
        raise InputError(f"cannot open script: {err.strerror}", path=str(path)) from None
    with stream:
        yield from iter_script(stream, str(path))
