"""Debounce arithmetic of ros2_medkit's fault storage: band clamping, sanitising, the status rule.

Pure functions over integers and status strings; no state, no I/O, no clock.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import TYPE_CHECKING, TypeAlias

if TYPE_CHECKING:
    from collections.abc import Callable

    from medkit_replay.model import Status

DEFAULT_CONFIRMATION_THRESHOLD = -1
DEFAULT_HEALING_THRESHOLD = 3
INT32_MIN = -(2**31)
INT32_MAX = 2**31 - 1
_LATCHED = ("CONFIRMED", "HEALED")

if TYPE_CHECKING:
    StatusRule: TypeAlias = Callable[[int, "Status | None", "DebounceConfig"], "Status | None"]
    CounterStep: TypeAlias = Callable[[int, int, "DebounceConfig"], int]


@dataclass(frozen=True, slots=True, kw_only=True)
class DebounceConfig:
    """The per-report debounce band (fault-manager.md §1.2, §1.4).

    ``confirmation_threshold`` is negative, ``healing_threshold`` is >= 0 once sanitised.
    ``critical_immediate_confirm`` is always true in the node; only storage-level tests clear it.
    """

    confirmation_threshold: int = DEFAULT_CONFIRMATION_THRESHOLD
    healing_enabled: bool = False
    healing_threshold: int = DEFAULT_HEALING_THRESHOLD
    critical_immediate_confirm: bool = True


def sanitize(config: DebounceConfig) -> DebounceConfig:
    """Enforce ``confirmation_threshold < 0 <= healing_threshold`` as upstream's sanitiser does.

    An offending field is replaced by its default (-1 or 3), not negated.
    """
    conf = config.confirmation_threshold
    heal = config.healing_threshold
    if conf < 0 and heal >= 0:
        return config
    return DebounceConfig(
        confirmation_threshold=conf if conf < 0 else DEFAULT_CONFIRMATION_THRESHOLD,
        healing_enabled=config.healing_enabled,
        healing_threshold=heal if heal >= 0 else DEFAULT_HEALING_THRESHOLD,
        critical_immediate_confirm=config.critical_immediate_confirm,
    )


def is_valid(config: DebounceConfig) -> bool:
    """True when the config already satisfies the sanitiser's invariant."""
    return config.confirmation_threshold < 0 <= config.healing_threshold


def clamp(counter: int, config: DebounceConfig) -> int:
    """Clamp a debounce counter into ``[confirmation_threshold, healing_threshold]``."""
    if counter < config.confirmation_threshold:
        return config.confirmation_threshold
    if counter > config.healing_threshold:
        return config.healing_threshold
    return counter


def compute_status(
    counter: int,
    current: Status | None,
    config: DebounceConfig,
    confirm: bool = True,
    heal: bool = True,
    latch: bool = True,
) -> Status | None:
    """Upstream's status rule, with its CONFIRMED/HEALED latch and no flapping at zero.

    Returns ``current`` unchanged at counter 0 (None only when ``current`` is None). The
    switches are for releases before one rule served both storages (see :func:`status_rule`).
    """
    if confirm and counter <= config.confirmation_threshold:
        return "CONFIRMED"
    if heal and config.healing_enabled and counter >= config.healing_threshold:
        return "HEALED"
    if latch and current in _LATCHED:
        return current
    if counter < 0:
        return "PREFAILED"
    if counter > 0:
        return "PREPASSED"
    return current


def status_rule(*, confirm: bool, heal: bool, latch: bool) -> StatusRule:
    """The status rule a storage applies after one report, chosen once at construction.

    ``confirm`` and ``heal``: whether the rule looks at that threshold at all (0.6.0's SQLite
    storage checks only confirmation after a FAILED and only healing after a PASSED);
    ``latch``: CONFIRMED and HEALED hold until the opposite threshold.
    """
    if confirm and heal and latch:
        return compute_status
    return partial(compute_status, confirm=confirm, heal=heal, latch=latch)


def step_in_band(counter: int, delta: int, config: DebounceConfig) -> int:
    """The counter after a report (``delta`` -1 for FAILED, +1 for PASSED), clamped to the band.

    The stored counter is brought into the band first (it may have been left outside it by a
    report under another entity's band), then stepped, then clamped again.
    """
    low, high = config.confirmation_threshold, config.healing_threshold
    if counter < low:
        counter = low
    elif counter > high:
        counter = high
    counter += delta
    if counter < low:
        return low
    if counter > high:
        return high
    return counter


def step_saturating(counter: int, delta: int, config: DebounceConfig) -> int:
    """The counter after a report without a band: it only stops at the int32 bounds."""
    counter += delta
    if counter < INT32_MIN:
        return INT32_MIN
    if counter > INT32_MAX:
        return INT32_MAX
    return counter


def counter_step(*, in_band: bool) -> CounterStep:
    """How a report moves the counter: clamped to the band, or only saturating."""
    return step_in_band if in_band else step_saturating


def unchanged(config: DebounceConfig) -> DebounceConfig:
    """The config as written: a release without the sanitiser uses every value as it is."""
    return config
