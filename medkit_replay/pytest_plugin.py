"""pytest plugin for regression tests of recorded missions (the ``pytest11`` entry point).

Fixtures:

- ``replay_recording(inputs, configs=())``: replays a recording (or several merged, or a JSON-lines
  script) with ROS 2 parameter files and returns the :class:`~medkit_replay.result.Result`;
  cached per (inputs, configs) for the whole session.
- ``golden(result, name=None, *, time_tolerance=0.0)``: compares the result with a stored JSON
  report, by default ``goldens/<test module>/<test name>.json`` beside the test file.

Assertion helpers (import them from this module): :func:`assert_confirmed`,
:func:`assert_not_confirmed`, :func:`assert_status`, :func:`assert_within_budget` and
:func:`assert_matches_golden`. Their failures show the fault's timeline (status changes and
FaultEvents) or the diff with the golden report.

Option: ``--update-golden`` rewrites golden reports that differ (or are missing) instead of failing.

Loaded into every pytest session of an environment where medkit-replay is installed, so it does
nothing until one of its fixtures or helpers is used: no import of the replay, no output.

The replay's modules are imported once per process, also under pytester, whose in-process
sessions forget every module a session imported: each session gets the same module objects
back (see ``_KEPT``). Imported a second time, numpy refuses to load ("cannot load module more
than once per process") and our classes would exist twice; that once turned every recorded
definition into "unusable" and the replay of the next session into an empty one.
"""

from __future__ import annotations

import difflib
import itertools
import re
import sys
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from medkit_replay.model import NS_PER_SEC
from medkit_replay.text import seconds

if TYPE_CHECKING:
    from collections.abc import Iterator, Sequence
    from types import ModuleType

    from medkit_replay.model import FaultEvent, Transition
    from medkit_replay.result import Result

MAX_TIMELINE_ROWS = 40
"""Rows of a fault timeline shown in a failure (runs of ``fault_updated`` count as one)."""
MAX_FAULTS_SHOWN = 5
"""Timelines shown when several faults break one expectation."""
DIFF_WIDTH = 100
"""Columns the golden-report diff is laid out for in a failure message."""

PathLike = str | Path
Window = tuple[float | None, float | None]

_configs: list[pytest.Config] = []
"""Configs of the running pytest sessions, innermost last (pytester nests sessions)."""
_updated_key = pytest.StashKey[list[Path]]()
_KEPT: dict[str, ModuleType] = {}
"""Every module this plugin's replays, budgets and goldens brought into the process, by name:
put back into ``sys.modules`` when a session starts, so that none is ever imported twice."""


@contextmanager
def _keeping_modules() -> Iterator[None]:
    """Remember the modules imported inside the block (the replay's, numpy, rosbags...), after
    putting back those an earlier block imported (a pytester session may have dropped them)."""
    _restore_modules()
    before = set(sys.modules)
    try:
        yield
    finally:
        for name in set(sys.modules) - before:
            module = sys.modules.get(name)
            if module is not None:
                _KEPT.setdefault(name, module)


def _restore_modules() -> None:
    """Give ``sys.modules`` back the modules an earlier session imported and pytester dropped."""
    for name, module in _KEPT.items():
        sys.modules.setdefault(name, module)


# --- hooks ---------------------------------------------------------------------------------------


def pytest_addoption(parser: pytest.Parser) -> None:
    """Add ``--update-golden``."""
    group = parser.getgroup("medkit-replay", "medkit-replay regression tests")
    group.addoption(
        "--update-golden",
        action="store_true",
        default=False,
        dest="medkit_replay_update_golden",
        help="medkit-replay: write golden reports that differ or are missing instead of failing.",
    )


def pytest_configure(config: pytest.Config) -> None:
    """Remember the session's config (for the update flag of the module-level helpers), and
    hand it the replay's modules if an earlier session in this process imported them."""
    _restore_modules()
    config.stash[_updated_key] = []
    _configs.append(config)


def pytest_unconfigure(config: pytest.Config) -> None:
    """Forget the session's config."""
    if config in _configs:
        _configs.remove(config)


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    """List the golden reports this session wrote (only when it wrote any)."""
    updated = terminalreporter.config.stash.get(_updated_key, [])
    if not updated:
        return
    terminalreporter.section("medkit-replay golden reports written")
    for path in updated:
        terminalreporter.write_line(str(path))


def _update_requested() -> bool:
    if not _configs:
        return False
    return bool(_configs[-1].getoption("medkit_replay_update_golden"))


def _note_updated(path: Path) -> None:
    if _configs:
        _configs[-1].stash.setdefault(_updated_key, []).append(path)


# --- fixtures ------------------------------------------------------------------------------------


class RecordingReplayer:
    """Replays recordings, each (inputs, configs) once per session."""

    def __init__(self) -> None:
        self._cache: dict[tuple[tuple[str, ...], tuple[str, ...]], Result] = {}

    def __call__(
        self,
        inputs: PathLike | Sequence[PathLike],
        configs: PathLike | Sequence[PathLike] = (),
    ) -> Result:
        """Replay ``inputs`` (merged as one recording) with the parameter files ``configs``
        (later ones overriding earlier ones); a path alone stands for a list of one.

        Raises:
            medkit_replay.errors.MedkitReplayError: an input or config cannot be used.
        """
        paths = [inputs] if isinstance(inputs, str | Path) else list(inputs)
        files = [configs] if isinstance(configs, str | Path) else list(configs)
        key = (
            tuple(str(Path(p).resolve()) for p in paths),
            tuple(str(Path(c).resolve()) for c in files),
        )
        if key not in self._cache:  # replayed with the paths as given, as the report shows them
            with _keeping_modules():
                from medkit_replay.pipeline import replay  # noqa: PLC0415  # only when used

                self._cache[key] = replay(paths, files)
        return self._cache[key]


@pytest.fixture(scope="session")
def replay_recording() -> RecordingReplayer:
    """``replay_recording(inputs, configs=())`` -> Result, cached for the session."""
    return RecordingReplayer()


class Golden:
    """Compares results with golden reports kept beside a test file."""

    def __init__(self, directory: Path, default_name: str) -> None:
        self.directory = directory
        self.default_name = default_name

    def path(self, name: PathLike | None = None) -> Path:
        """Where a golden report lives: ``name`` relative to the goldens folder, or the test's
        default (``<test module>/<test name>.json``)."""
        return self.directory / (name if name is not None else self.default_name)

    def __call__(
        self, result: Result, name: PathLike | None = None, *, time_tolerance: float = 0.0
    ) -> None:
        """Assert that ``result`` matches the golden report (see :func:`assert_matches_golden`)."""
        __tracebackhide__ = True
        assert_matches_golden(result, self.path(name), time_tolerance=time_tolerance)


@pytest.fixture
def golden(request: pytest.FixtureRequest) -> Golden:
    """``golden(result, name=None, *, time_tolerance=0.0)``: compare with a golden report."""
    test_file = request.path
    name = re.sub(r"[^A-Za-z0-9_.-]+", "_", request.node.name).strip("_") or "golden"
    return Golden(test_file.parent / "goldens", f"{test_file.stem}/{name}.json")


# --- timelines -----------------------------------------------------------------------------------


def recording_start_ns(result: Result) -> int:
    """The recording's first log time (its inputs' starts, else the first message read); 0 when
    nothing was read. ``within`` windows are in seconds from here."""
    starts = [i.start_ns for i in result.inputs if i.start_ns is not None]
    if result.summary.start_ns is not None:
        starts.append(result.summary.start_ns)
    return min(starts, default=0)


@dataclass(slots=True)
class _Row:
    t_ns: int
    change: str = ""
    cause: str = ""
    source: str = ""
    event: str = ""
    mark: str = ""
    last_t_ns: int | None = None
    repeats: int = 1


def _clean(text: object) -> str:
    """Recorded text on one line, control characters escaped."""
    return re.sub(
        r"[\x00-\x1f\x7f-\x9f]",
        lambda m: " " if m.group() in "\n\r\t" else f"\\x{ord(m.group()):02x}",
        str(text),
    )


def _rows(
    transitions: Sequence[Transition], events: Sequence[FaultEvent], marked: set[int]
) -> list[_Row]:
    """One row per instant and status change; an event at the same instant shares its row."""
    items: list[tuple[int, int, Transition | None, FaultEvent | None]] = [
        (t.t_ns, 0, t, None) for t in transitions
    ]
    items += [(e.t_ns, 1, None, e) for e in events]
    items.sort(key=lambda item: (item[0], item[1]))
    rows: list[_Row] = []
    for t_ns, group in itertools.groupby(items, key=lambda item: item[0]):
        members = list(group)
        changes = [m[2] for m in members if m[2] is not None]
        published = [m[3] for m in members if m[3] is not None]
        for change, event in itertools.zip_longest(changes, published):
            row = _Row(t_ns)
            if change is not None:
                origin = change.from_status or "(new)"
                row.change = f"{origin} -> {change.to_status}"
                row.cause = change.cause
                row.source = _clean(change.source_id or "")
                row.mark = "!" if id(change) in marked else ""
            if event is not None:
                row.event = event.event_type
            rows.append(row)
    return _collapse(rows)


def _collapse(rows: list[_Row]) -> list[_Row]:
    """Runs of rows holding only a ``fault_updated`` event become one row."""
    collapsed: list[_Row] = []
    for row in rows:
        last = collapsed[-1] if collapsed else None
        if (
            last is not None
            and not row.change
            and not last.change
            and row.event == last.event == "fault_updated"
        ):
            last.repeats += 1
            last.last_t_ns = row.t_ns
            continue
        collapsed.append(row)
    return collapsed


def fault_timeline(result: Result, fault_code: str, *, marked: Sequence[Transition] = ()) -> str:
    """One fault's status changes and FaultEvents as a small text table, indented for a failure
    message (times in s from the recording's start); ``marked`` transitions get a ``!``."""
    origin = recording_start_ns(result)
    transitions = [t for t in result.transitions if t.fault_code == fault_code]
    events = [e for e in result.events if e.fault.fault_code == fault_code]
    head = (
        f"timeline of {_clean(fault_code)} (t in s from the recording's start): "
        f"{len(transitions)} status change(s), {len(events)} event(s)"
    )
    if not transitions and not events:
        return "  " + head
    rows = _rows(transitions, events, {id(t) for t in marked})
    table = [("", "t", "status change", "cause", "source", "event")]
    shown = rows
    if len(rows) > MAX_TIMELINE_ROWS:
        half = MAX_TIMELINE_ROWS // 2
        shown = [
            *rows[:half],
            _Row(0, change=f"... {len(rows) - 2 * half} rows ..."),
            *rows[-half:],
        ]
    for row in shown:
        if row.change.startswith("... "):
            table.append(("", "", row.change, "", "", ""))
            continue
        t = seconds(row.t_ns - origin)
        event = row.event
        if row.repeats > 1 and row.last_t_ns is not None:
            t += f"-{seconds(row.last_t_ns - origin)}"
            event += f" x{row.repeats}"
        table.append((row.mark, t, row.change, row.cause, row.source, event))
    widths = [max(len(line[i]) for line in table) for i in range(len(table[0]))]
    lines = ["  " + head]
    for line in table:
        cells = [line[0].ljust(widths[0]), line[1].rjust(widths[1])]
        cells += [cell.ljust(width) for cell, width in zip(line[2:], widths[2:], strict=True)]
        lines.append("    " + "  ".join(cells).rstrip())
    return "\n".join(lines)


# --- assertions ----------------------------------------------------------------------------------


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
    text = f"{expectation}\n  {_clean(fault_code)} was never reported in this run"
    if close:
        text += "; did you mean " + ", ".join(_clean(c) for c in close) + "?"
    listed = ", ".join(_clean(c) for c in codes[:20]) + (", ..." if len(codes) > 20 else "")
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
    expectation = f"expected {_clean(fault_code)} to be confirmed{_window_text(window)}"
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
    lines = [f"expected no fault matching {_clean(code_pattern)!r} to be confirmed"]
    lines[0] += _window_text(window)
    lines[0] += f"; {len(offending)} was" if len(offending) == 1 else f"; {len(offending)} were"
    for code, confirmations in offending.items():
        fault = result.fault(code)
        times = ", ".join(f"{seconds(t.t_ns - origin)} s" for t in confirmations)
        status = fault.status if fault is not None else "unknown"
        lines.append(f"  {_clean(code)}: confirmed at {times} (status at the end: {status})")
    for code, confirmations in list(offending.items())[:MAX_FAULTS_SHOWN]:
        lines.append(fault_timeline(result, code, marked=confirmations))
    if len(offending) > MAX_FAULTS_SHOWN:
        lines.append(f"({len(offending) - MAX_FAULTS_SHOWN} more timelines not shown)")
    raise AssertionError("\n".join(lines))


def assert_status(result: Result, fault_code: str, status: str) -> None:
    """Assert the fault's status at the end of the recording (``CONFIRMED``, ``HEALED``, ...)."""
    __tracebackhide__ = True
    expectation = f"expected {_clean(fault_code)} to end {status}"
    fault = result.fault(fault_code)
    if fault is None:
        raise AssertionError(_unknown(result, fault_code, expectation))
    if fault.status != status:
        changes = [t for t in result.transitions if t.fault_code == fault_code]
        raise AssertionError(
            f"{expectation}\n  it ended {fault.status}\n"
            + fault_timeline(result, fault_code, marked=changes[-1:])
        )


def assert_within_budget(result: Result, budget_path: PathLike) -> None:
    """Assert that the result keeps the fault budget in ``budget_path`` (the budget YAML of
    ``medkit-replay check``, docs/budgets.md). The failure message gives the verdict of every
    rule that failed, its offending faults, and their timelines.

    Raises:
        medkit_replay.errors.ConfigError: the budget file is missing or invalid.
    """
    __tracebackhide__ = True
    with _keeping_modules():
        from medkit_replay.checks import evaluate, load_budget  # noqa: PLC0415  # only when used

        budget = load_budget(budget_path)
        verdicts = evaluate(budget, result)
    failed = [v for v in verdicts if not v.passed]
    if not failed:
        return
    lines = [
        f"fault budget {_clean(budget.title)} exceeded: {len(failed)} of {len(verdicts)} "
        f"rule(s) failed ({_clean(budget_path)})"
    ]
    codes: list[str] = []
    for verdict in failed:
        rule = verdict.rule
        where = f" (line {rule.line})" if rule.line is not None else ""
        lines.append(
            f"  FAIL rule {rule.index}{where} {_clean(rule.name)}: {_clean(verdict.message)}"
        )
        for offender in verdict.offenders:
            lines.append(f"    - {_clean(offender.text())}")
            if offender.fault_code not in codes:
                codes.append(offender.fault_code)
    shown = [code for code in codes if result.fault(code) is not None][:MAX_FAULTS_SHOWN]
    for code in shown:
        lines.append(fault_timeline(result, code, marked=_confirmations(result, code)))
    if len(codes) > len(shown):
        lines.append(f"  ({len(codes) - len(shown)} more timeline(s) not shown)")
    raise AssertionError("\n".join(lines))


def assert_matches_golden(
    result: Result,
    path: PathLike,
    *,
    time_tolerance: float = 0.0,
    update: bool | None = None,
) -> None:
    """Assert that the result's report matches the golden JSON report at ``path`` (compared as
    ``medkit-replay diff`` compares, events and transitions within ``time_tolerance`` seconds).

    With ``update`` (by default: pytest's ``--update-golden``), a missing or differing golden is
    written from the result instead, and the assertion passes. The failure message is the diff.
    """
    __tracebackhide__ = True
    golden_path = Path(path)
    if update is None:
        update = _update_requested()
    if not golden_path.exists():
        if update:
            _write_golden(result, golden_path)
            return
        raise AssertionError(
            f"golden report {golden_path} does not exist\n"
            "  run pytest with --update-golden to write it from this run"
        )
    with _keeping_modules():
        from medkit_replay.diffing import diff_reports, read_report, render_diff, tolerance_ns  # noqa: PLC0415  # only when used
        from medkit_replay.outputs.json_report import to_report  # noqa: PLC0415

        diff = diff_reports(
            read_report(golden_path),
            to_report(result),
            time_tolerance_ns=tolerance_ns(time_tolerance),
            baseline_name=str(golden_path),
            current_name="this run",
        )
        shown = None if diff.equal else render_diff(diff, DIFF_WIDTH)
    if shown is None:
        return
    if update:
        _write_golden(result, golden_path)
        return
    raise AssertionError(
        "the run differs from its golden report\n"
        + shown
        + "\nrun pytest with --update-golden to accept this run as the new golden report"
    )


def _write_golden(result: Result, path: Path) -> None:
    """Write a golden report whole (a temporary file renamed into place)."""
    with _keeping_modules():
        from medkit_replay.outputs.atomic import atomic_text  # noqa: PLC0415
        from medkit_replay.outputs.json_report import write_json  # noqa: PLC0415

        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_text(path) as stream:
            write_json(result, stream)
    _note_updated(path)
