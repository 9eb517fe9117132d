"""Debounce arithmetic of ros2_medkit's fault storage: band clamping, sanitising, the status rule.

Pure functions over integers and status strings; no state, no I/O, no clock.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from medkit_replay.model import Status

DEFAULT_CONFIRMATION_THRESHOLD = -1
DEFAULT_HEALING_THRESHOLD = 3


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


def compute_status(counter: int, current: Status | None, config: DebounceConfig) -> Status | None:
    """Upstream's status rule, with its CONFIRMED/HEALED latch and no flapping at zero.

    Returns ``current`` unchanged at counter 0 (None only when ``current`` is None).
    """
    if counter <= config.confirmation_threshold:
        return "CONFIRMED"
    if config.healing_enabled and counter >= config.healing_threshold:
        return "HEALED"
    if current in ("CONFIRMED", "HEALED"):
        return current
    if counter < 0:
        return "PREFAILED"
    if counter > 0:
        return "PREPASSED"
    return current
