"""One run of a fleet: a recording replayed as ``analyze`` replays it, reduced to a small summary.

``run_one`` is the per-run function, the same in every executor: in this process or in worker
processes (``workers``), or on a Dask distributed cluster (``cluster``). It never raises for a
recording that cannot be replayed: the summary's ``error`` says why.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, replace
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING

from medkit_replay.errors import MedkitReplayError
from medkit_replay.files import FileRefusedError, check_regular
from medkit_replay.inputs import is_remote
from medkit_replay.inputs.recording import input_kind
from medkit_replay.model import Loss, total_loss
from medkit_replay.pipeline import replay
from medkit_replay.result import STATUSES
from medkit_replay.text import clip, one_line

if TYPE_CHECKING:
    from collections.abc import Sequence

    from medkit_replay.checks import Budget
    from medkit_replay.result import Result

TOP_CODES = 5
"""Codes listed per run, most FAILED reports first."""

KINDS = {"dir": "rosbag2", ".mcap": "mcap", ".db3": "db3", ".bag": "rosbag1", ".jsonl": "script"}
"""A run's ``kind`` by READERS key: a bag directory, a bare storage file, a ROS 1 bag, a script."""
KEPT_WARNINGS = 3
"""Warnings a run's summary keeps the text of (the first ones; ``warnings`` counts them all)."""
WARNING_CHARS = 300
"""A kept warning is cut here (an ellipsis and the count of characters left out end it)."""
MAX_ERROR_CHARS = 4000
"""A run's error is cut here (an ellipsis ends it): a message quoting a 10 MB field stays short."""


@dataclass(frozen=True, slots=True, kw_only=True)
class RunSummary:
    """What a fleet keeps of one run: small, plain, picklable.

    Attributes:
        path: the recording, as discovered.
        kind: ``rosbag2`` (a bag directory), ``mcap`` or ``db3`` (a bare file), ``rosbag1`` (a
            ROS 1 bag), ``script``.
        start_ns, end_ns: first and last log time of the recording (None when nothing was read).
        messages: messages the replay read (None when the run failed).
        faults_by_status: final status counts, every status of ``result.STATUSES`` in order.
        top_codes: ``(code, reports)`` of the codes with the most accepted FAILED reports,
            most first (then by code).
        confirmed: ``(code, t_ns)`` of every code that was ever CONFIRMED, with the time it was
            first confirmed, in that order.
        heals: ``(code, ns)`` for each CONFIRMED→HEALED transition: how long the fault had been
            CONFIRMED, in the order the heals happened.
        warnings: how many warnings the replay gave.
        first_warnings: the first KEPT_WARNINGS of them, each cut at WARNING_CHARS characters
            (for the terminal summary; not a column of the tables).
        budget: the budget verdict, ``pass`` or ``fail``; None when no budget was checked.
        budget_failures: the names of the budget's rules that did not hold, in budget order;
            or one line saying what was missing when nothing was replayed.
        error: why the run failed (one line), None when it did not.
        lost: what damage cost the recording, in total (None: nothing was lost); not a column
            of the tables, ``--strict`` fails the fleet on it.
        upstream_release: the ros2_medkit release the run was replayed as (None when the
            run failed).
    """

    path: str
    kind: str
    start_ns: int | None = None
    end_ns: int | None = None
    messages: int | None = None
    faults_by_status: tuple[tuple[str, int], ...] = ()
    top_codes: tuple[tuple[str, int], ...] = ()
    confirmed: tuple[tuple[str, int], ...] = ()
    heals: tuple[tuple[str, int], ...] = ()
    warnings: int = 0
    first_warnings: tuple[str, ...] = ()
    budget: str | None = None
    budget_failures: tuple[str, ...] = ()
    error: str | None = None
    lost: Loss | None = None
    upstream_release: str | None = None

    @property
    def ok(self) -> bool:
        """The recording was replayed."""
        return self.error is None

    @property
    def span_ns(self) -> int | None:
        """Bag time the recording covers (None when unknown)."""
        if self.start_ns is None or self.end_ns is None:
            return None
        return self.end_ns - self.start_ns


def opened_recording(path: Path | str) -> Path | str:
    """What a run replays for a recording it was handed: a URL as it is; a local path, once it
    is known not to be a FIFO or a device named like a recording (its reader would block).

    Raises:
        FileRefusedError: the local path is no regular file or folder.
    """
    if isinstance(path, str) and is_remote(path):
        return path
    recording = Path(path)
    if recording.exists() and not recording.is_dir():
        check_regular(recording)
    return recording


def run_kind(path: Path | str) -> str:
    """The ``kind`` of a run for a recording path or URL (see :class:`RunSummary`)."""
    if isinstance(path, str) and is_remote(path):
        kind = "dir" if path.endswith("/") else PurePosixPath(path).suffix.lower()
        if kind not in KINDS:
            kind = "dir"  # a prefix named without its "/"
    else:
        kind = input_kind(Path(path))
    return KINDS.get(kind, kind.lstrip(".") or "unknown")


def summarize(path: str, kind: str, result: Result) -> RunSummary:
    """Reduce a replay's result to a run summary."""
    summary = result.summary
    start_ns, end_ns = result.span()
    failed_reports: Counter[str] = Counter(
        r.fault_code for r in result.reports if r.accepted and r.event_type == "FAILED"
    )
    ranked = sorted(failed_reports.items(), key=lambda item: (-item[1], item[0]))
    first_confirmed: dict[str, int] = {}
    confirmed_since: dict[str, int] = {}
    heals: list[tuple[str, int]] = []
    for transition in result.transitions:
        code = transition.fault_code
        if transition.to_status == "CONFIRMED" and transition.from_status != "CONFIRMED":
            first_confirmed.setdefault(code, transition.t_ns)
            confirmed_since[code] = transition.t_ns
        elif transition.from_status == "CONFIRMED" and transition.to_status == "HEALED":
            since = confirmed_since.pop(code, None)
            if since is not None:
                heals.append((code, transition.t_ns - since))
    return RunSummary(
        path=path,
        kind=kind,
        start_ns=start_ns,
        end_ns=end_ns,
        messages=summary.messages_read,
        faults_by_status=tuple((s, summary.faults_by_status.get(s, 0)) for s in STATUSES),
        top_codes=tuple(ranked[:TOP_CODES]),
        confirmed=tuple(first_confirmed.items()),
        heals=tuple(heals),
        warnings=len(result.warnings),
        first_warnings=tuple(clip(w, WARNING_CHARS) for w in result.warnings[:KEPT_WARNINGS]),
        lost=total_loss(result.losses, path) if result.losses else None,
        upstream_release=result.upstream_release,
    )


def run_one(
    path: str | Path,
    configs: Sequence[str | Path] = (),
    budget: Budget | None = None,
    label: str | None = None,
) -> RunSummary:
    """Replay one recording with the configs, as ``analyze`` would, and summarize it.

    Args:
        path: the recording (any input ``analyze`` takes).
        configs: ROS 2 parameter files, later ones overriding earlier ones.
        budget: a fault budget (``medkit_replay.checks.load_budget``) to check the run
            against, as ``check`` does (``medkit_replay.checks.failed_rules``).
        label: how the summary names the recording, also in its error (default: ``path``);
            a cluster is sent absolute paths but reports the paths as they were found.

    Never raises for the recording's sake: an input or config problem, or any other exception
    of the replay, is the summary's ``error`` (one line).
    """
    shown = str(path) if label is None else label
    kind = "unknown"
    try:
        kind = run_kind(path)
        recording = opened_recording(path)
        result = replay([recording], list(configs))
        summary = summarize(shown, kind, result)
        if budget is not None:
            from medkit_replay.checks import failed_rules  # noqa: PLC0415  # only with a budget

            failures = failed_rules(budget, result)
            verdict = "fail" if failures else "pass"
            summary = replace(summary, budget=verdict, budget_failures=failures)
        problem = summary_problem(summary)
    except Exception as err:  # one recording must not end the fleet
        error = run_error(path, err)
    else:
        if problem is None:
            return summary
        error = f"{path}: {problem}"
    return RunSummary(path=shown, kind=kind, error=row_error(error, str(path), label))


def row_error(error: str, path: str, label: str | None, *, named_first: bool = False) -> str:
    """A run's error as its row holds it: on one line, the input called ``label`` (as it was
    given) where ``path`` stands, first when ``named_first``, cut to MAX_ERROR_CHARS."""
    error = one_line(error)
    if label is not None:
        error = error.replace(path, label)
    if named_first and label is not None and not error.startswith(label):
        error = f"{label}: {error}"
    if len(error) > MAX_ERROR_CHARS:
        error = error[: MAX_ERROR_CHARS - 1] + "…"
    return error


def run_error(path: Path | str, error: Exception) -> str:
    """Why one run (a fleet's recording, a sweep's input) failed: an input or config problem as
    the tool words it, a refused file or any other exception after the input's name."""
    if isinstance(error, MedkitReplayError):
        return error.render()
    if isinstance(error, FileRefusedError):
        return f"{path}: {error}"
    return f"{path}: {describe_error(error)}"


def describe_error(error: BaseException) -> str:
    """An exception on one line: its type, and its text when it has one."""
    try:
        text = one_line(error)
    except Exception:  # a text that cannot be made (a number too long to print)
        text = ""
    return f"{type(error).__name__}: {text}" if text else type(error).__name__


def _shown(value: object) -> str:
    if isinstance(value, int):
        return str(value) if value.bit_length() <= 128 else f"a {value.bit_length()}-bit number"
    return repr(value)[:40]


def _int64(value: object) -> bool:
    # Never ``value in range(...)``: for anything but an int that walks the whole range.
    return type(value) is int and -(2**63) <= value < 2**63


def summary_problem(summary: RunSummary) -> str | None:
    """Why the fleet table cannot hold a summary (a time at or past 2^63 ns, a time that is not
    an integer), or None; such a run is reported as failed rather than costing the report."""
    times = [summary.start_ns, summary.end_ns, *(t for _, t in summary.confirmed)]
    for t_ns in times:
        if t_ns is not None and not _int64(t_ns):
            return f"bag time {_shown(t_ns)} is out of range (an integer ns below 2^63 expected)"
    for _, ns in summary.heals:
        if not _int64(ns):
            return f"a heal after {_shown(ns)} ns is out of range"
    span = summary.span_ns if all(_int64(t) for t in times if t is not None) else None
    if span is not None and not _int64(span):
        return f"a recording spanning {span} ns is out of range"
    for name, count in (("messages", summary.messages), ("warnings", summary.warnings)):
        if count is not None and not _int64(count):
            return f"{name} count {_shown(count)} is out of range"
    return None


def failed_run(path: Path | str, error: BaseException | str) -> RunSummary:
    """A run that failed outside ``run_one`` (its worker died or ran out of time)."""
    problem = error if isinstance(error, str) else describe_error(error)
    return RunSummary(path=str(path), kind=run_kind(path), error=f"{path}: {problem}")
