"""The per-input jobs of ``suggest-rules``: each run's confirmations (to learn from), and each
run replayed with the proposed rules (to validate them).

Both never raise for the input's sake: the outcome's ``error`` says why (one line).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from medkit_replay.errors import MedkitReplayError
from medkit_replay.files import FileRefusedError
from medkit_replay.fleet.run import describe_error, opened_recording
from medkit_replay.pipeline import replay
from medkit_replay.text import one_line

if TYPE_CHECKING:
    from medkit_replay.result import Result


@dataclass(frozen=True, slots=True)
class Observed:
    """One run's confirmations, in the order they happened: ``(t_ns, fault_code)``."""

    label: str
    confirmations: tuple[tuple[int, str], ...] = ()
    error: str | None = None

    @property
    def ok(self) -> bool:
        """The input was replayed."""
        return self.error is None


@dataclass(frozen=True, slots=True)
class Checked:
    """One run replayed with the proposed rules.

    Attributes:
        muted_events: FaultEvents the rules withheld (muted symptoms' confirmations/updates).
        muted: ``(fault_code, root_cause_code, rule_id)`` muted at the end.
        rootless: those of ``muted`` whose root never confirmed in this run.
    """

    label: str
    muted_events: int = 0
    muted: tuple[tuple[str, str, str], ...] = ()
    rootless: tuple[tuple[str, str, str], ...] = ()
    error: str | None = None

    @property
    def ok(self) -> bool:
        """The input was replayed."""
        return self.error is None


def _replayed(path: str, configs: tuple[str, ...]) -> Result | str:
    """The replay's Result, or why there is none (one line)."""
    try:
        return replay([opened_recording(path)], list(configs))
    except MedkitReplayError as err:
        return one_line(err.render())
    except FileRefusedError as err:
        return f"{path}: {err}"
    except Exception as err:  # one input must not end the others
        return f"{path}: {describe_error(err)}"


def confirmations(result: Result) -> tuple[tuple[int, str], ...]:
    """Every entry into CONFIRMED, in order."""
    return tuple(
        (t.t_ns, t.fault_code)
        for t in result.transitions
        if t.to_status == "CONFIRMED" and t.from_status != "CONFIRMED"
    )


def observe(job: tuple[str, str], configs: tuple[str, ...]) -> Observed:
    """Replay one input (``(path, label)``) and keep its confirmations."""
    path, label = job
    result = _replayed(path, configs)
    if isinstance(result, str):
        return Observed(label, error=result.replace(path, label))
    return Observed(label, confirmations(result))


def check(job: tuple[str, str], configs: tuple[str, ...]) -> Checked:
    """Replay one input with the configs (the last one switching the proposed rules on)."""
    path, label = job
    result = _replayed(path, configs)
    if isinstance(result, str):
        return Checked(label, error=result.replace(path, label))
    confirmed = {code for _, code in confirmations(result)}
    muted = tuple((m.fault_code, m.root_cause_code, m.rule_id) for m in result.muted_faults)
    withheld = sum(1 for r in result.reports if r.withheld_event is not None)
    rootless = tuple(m for m in muted if m[1] not in confirmed)
    return Checked(label, withheld, muted, rootless)


def failed_observation(job: tuple[str, str], problem: str) -> Observed:
    """An input whose worker died or ran out of time."""
    return Observed(job[1], error=f"{job[1]}: {problem}")


def failed_check(job: tuple[str, str], problem: str) -> Checked:
    """An input whose worker died or ran out of time, when validating."""
    return Checked(job[1], error=f"{job[1]}: {problem}")
