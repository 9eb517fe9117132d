"""Assertion helpers on a replay's Result: faults confirmed or not, final statuses, budgets.

Their failures say what was expected and what happened, with the faults' timelines.
"""

from __future__ import annotations

import difflib
import re
from typing import TYPE_CHECKING

from medkit_replay.model import NS_PER_SEC, strict_failure
from medkit_replay.pytest_plugin.session import empty_allowed, keeping_modules, strict_requested
from medkit_replay.pytest_plugin.timeline import clean, fault_timeline, recording_start_ns
from medkit_replay.text import seconds

if TYPE_CHECKING:
    from medkit_replay.model import Transition
    from medkit_replay.pytest_plugin.replays import PathLike
    from medkit_replay.result import Result

MAX_FAULTS_SHOWN = 5
"""Timelines shown when several faults break one expectation."""

Window = tuple[float | None, float | None]


def _window(within: Window | None) -> tuple[float | None, float | None]:
    if within is None:
        return None, None
    start, end = within
    if start is not None and end is not None and start > end:
        raise ValueError(f"within=({start}, {end}): the window ends before it starts")
    return start, end


def _in_window(t_ns: int, origin_ns: int, window: tuple[float | None, float | None]) -> bool:
    start, end = window
    t = t_ns - origin_ns
    if start is not None and t < round(start * NS_PER_SEC):
        return False
    return not (end is not None and t > round(end * NS_PER_SEC))


def _window_text(window: tuple[float | None, float | None]) -> str:
    start, end = window
    if start is None and end is None:
        return ""
    if start is None:
        return f" by {end:.3f} s"
    if end is None:
        return f" from {start:.3f} s on"
    return f" between {start:.3f} s and {end:.3f} s"


def _known_codes(result: Result) -> list[str]:
    codes = {f.fault_code for f in result.faults}
    codes |= {t.fault_code for t in result.transitions}
    return sorted(codes)


def _confirmations(result: Result, fault_code: str) -> list[Transition]:
    return [
        t for t in result.transitions if t.fault_code == fault_code and t.to_status == "CONFIRMED"
    ]


def _unknown(result: Result, fault_code: str, expectation: str) -> str:
    codes = _known_codes(result)
    close = difflib.get_close_matches(fault_code, codes, n=3)
    text = f"{expectation}\n  {clean(fault_code)} was never reported in this run"
    if close:
        text += "; did you mean " + ", ".join(clean(c) for c in close) + "?"
    listed = ", ".join(clean(c) for c in codes[:20]) + (", ..." if len(codes) > 20 else "")
    return text + f"\n  faults of this run: {listed or 'none'}"


def assert_confirmed(
    result: Result, fault_code: str, *, within: Window | None = None
) -> Transition:
    """Assert that ``fault_code`` was confirmed (a status change to CONFIRMED, muted or not),
    within ``within=(t1, t2)`` seconds from the recording's start when given (bounds included;
    ``None`` leaves a side open). Returns the first such change.

    The failure message shows the fault's timeline, its confirmations marked with ``!``.
    """
    __tracebackhide__ = True
    window = _window(within)
    origin = recording_start_ns(result)
    expectation = f"expected {clean(fault_code)} to be confirmed{_window_text(window)}"
    confirmations = _confirmations(result, fault_code)
    matching = [t for t in confirmations if _in_window(t.t_ns, origin, window)]
    if matching:
        return matching[0]
    if result.fault(fault_code) is None and not confirmations:
        raise AssertionError(_unknown(result, fault_code, expectation))
    fault = result.fault(fault_code)
    status = fault.status if fault is not None else "unknown"
    if confirmations:
        times = ", ".join(f"{seconds(t.t_ns - origin)} s" for t in confirmations)
        actual = f"it was confirmed at {times} (status at the end: {status})"
    else:
        actual = f"it was never confirmed (status at the end: {status})"
    raise AssertionError(
        f"{expectation}\n  {actual}\n" + fault_timeline(result, fault_code, marked=confirmations)
    )


def _glob(pattern: str) -> re.Pattern[str]:
    """A fault-code glob as budgets write them: ``*`` any run of characters, ``?`` one."""
    parts = (".*" if c == "*" else "." if c == "?" else re.escape(c) for c in pattern)
    return re.compile("".join(parts), re.DOTALL)


def assert_not_confirmed(
    result: Result, code_pattern: str, *, within: Window | None = None
) -> None:
    """Assert that no fault whose code matches the glob ``code_pattern`` (``*`` any run of
    characters, ``?`` one; case-sensitive, the whole code) was confirmed, muted or not (within
    ``within`` seconds from the recording's start when given).

    The failure message lists every offending fault and shows their timelines, the
    confirmations marked with ``!``.
    """
    __tracebackhide__ = True
    window = _window(within)
    origin = recording_start_ns(result)
    pattern = _glob(code_pattern)
    offending: dict[str, list[Transition]] = {}
    for transition in result.transitions:
        if (
            transition.to_status == "CONFIRMED"
            and pattern.fullmatch(transition.fault_code) is not None
            and _in_window(transition.t_ns, origin, window)
        ):
            offending.setdefault(transition.fault_code, []).append(transition)
    if not offending:
        return
    lines = [f"expected no fault matching {clean(code_pattern)!r} to be confirmed"]
    lines[0] += _window_text(window)
    lines[0] += f"; {len(offending)} was" if len(offending) == 1 else f"; {len(offending)} were"
    for code, confirmations in offending.items():
        fault = result.fault(code)
        times = ", ".join(f"{seconds(t.t_ns - origin)} s" for t in confirmations)
        status = fault.status if fault is not None else "unknown"
        lines.append(f"  {clean(code)}: confirmed at {times} (status at the end: {status})")
    for code, confirmations in list(offending.items())[:MAX_FAULTS_SHOWN]:
        lines.append(fault_timeline(result, code, marked=confirmations))
    if len(offending) > MAX_FAULTS_SHOWN:
        lines.append(f"({len(offending) - MAX_FAULTS_SHOWN} more timelines not shown)")
    raise AssertionError("\n".join(lines))


def assert_status(result: Result, fault_code: str, status: str) -> None:
    """Assert the fault's status at the end of the recording (``CONFIRMED``, ``HEALED``, ...)."""
    __tracebackhide__ = True
    expectation = f"expected {clean(fault_code)} to end {status}"
    fault = result.fault(fault_code)
    if fault is None:
        raise AssertionError(_unknown(result, fault_code, expectation))
    if fault.status != status:
        changes = [t for t in result.transitions if t.fault_code == fault_code]
        raise AssertionError(
            f"{expectation}\n  it ended {fault.status}\n"
            + fault_timeline(result, fault_code, marked=changes[-1:])
        )


def assert_within_budget(
    result: Result,
    budget_path: PathLike,
    *,
    allow_empty: bool | None = None,
    strict: bool | None = None,
) -> None:
    """Assert that the result keeps the fault budget in ``budget_path`` (the budget YAML of
    ``medkit-replay check``, docs/budgets.md). The failure message gives the verdict of every
    rule that failed, its offending faults, and their timelines. ``strict`` (default: pytest's
    ``--strict-replay``) fails a recording read only in part, as ``check --strict``.

    A replay in which nothing reached the fault manager fails, whatever the rules, with one
    line saying what was missing, unless ``allow_empty`` (None: the ``--allow-empty-replay``
    option of the pytest run).

    Raises:
        medkit_replay.errors.ConfigError: the budget file is missing or invalid.
    """
    __tracebackhide__ = True
    allowed = empty_allowed() if allow_empty is None else allow_empty
    with keeping_modules():
        from medkit_replay.checks import (  # noqa: PLC0415  # only when used
            evaluate,
            load_budget,
            nothing_replayed,
        )

        budget = load_budget(budget_path, allow_empty=allowed)
        empty = nothing_replayed(budget, result)
        if empty is not None:
            raise AssertionError(
                f"fault budget {clean(budget.title)} not checked ({clean(budget_path)}): "
                f"{clean(empty)}"
            )
        verdicts = evaluate(budget, result)
    failed = [v for v in verdicts if not v.passed]
    damage = strict_requested() if strict is None else strict
    damaged = [clean(strict_failure(x)) for x in result.losses_by_input()] if damage else []
    if not failed and not damaged:
        return
    if not failed:
        raise AssertionError("\n".join(["recording read only in part:", *damaged]))
    lines = [
        f"fault budget {clean(budget.title)} exceeded: {len(failed)} of {len(verdicts)} "
        f"rule(s) failed ({clean(budget_path)})",
        *damaged,
    ]
    codes: list[str] = []
    for verdict in failed:
        rule = verdict.rule
        where = f" (line {rule.line})" if rule.line is not None else ""
        lines.append(
            f"  FAIL rule {rule.index}{where} {clean(rule.name)}: {clean(verdict.message)}"
        )
        for offender in verdict.offenders:
            lines.append(f"    - {clean(offender.text())}")
            if offender.fault_code not in codes:
                codes.append(offender.fault_code)
    shown = [code for code in codes if result.fault(code) is not None][:MAX_FAULTS_SHOWN]
    for code in shown:
        lines.append(fault_timeline(result, code, marked=_confirmations(result, code)))
    if len(codes) > len(shown):
        lines.append(f"  ({len(codes) - len(shown)} more timeline(s) not shown)")
    raise AssertionError("\n".join(lines))
