"""The FaultReporter's LocalFilter: per-code sliding windows that gate reports before the manager.

Pure and clock-free: every call carries the bag time it happens at (fault-manager.md §2).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from medkit_replay.model import NS_PER_SEC


@dataclass(frozen=True, slots=True, kw_only=True)
class LocalFilterConfig:
    """``fault_reporter.local_filtering.*`` after upstream's validation."""

    enabled: bool = True
    default_threshold: int = 3
    default_window_sec: float = 10.0
    bypass_severity: int = 2

    def sanitized(self) -> LocalFilterConfig:
        """Threshold < 1 becomes 1, window <= 0 becomes 1.0 s, bypass is cast to uint8."""
        return LocalFilterConfig(
            enabled=self.enabled,
            default_threshold=max(self.default_threshold, 1),
            default_window_sec=self.default_window_sec if self.default_window_sec > 0 else 1.0,
            bypass_severity=self.bypass_severity & 0xFF,
        )


class LocalFilter:
    """Decide whether a reporter forwards a FAILED or PASSED report to the fault manager."""

    def __init__(self, config: LocalFilterConfig | None = None) -> None:
        self._failed: dict[str, deque[int]] = {}
        self._passed: dict[str, deque[int]] = {}
        self.set_config(config or LocalFilterConfig())

    @property
    def config(self) -> LocalFilterConfig:
        """The validated configuration in force."""
        return self._config

    def set_config(self, config: LocalFilterConfig) -> None:
        """Validate and apply a config; like upstream, this forgets all tracking state."""
        self._config = config.sanitized()
        self._window_ns = round(self._config.default_window_sec * NS_PER_SEC)
        self.reset_all()

    def should_forward(self, fault_code: str, severity: int, t_ns: int) -> bool:
        """FAILED path: severity bypass, else the sliding window threshold."""
        if not self._config.enabled:
            return True
        if severity >= self._config.bypass_severity:
            return True  # bypassed reports are not tracked
        return self._track(self._failed, fault_code, t_ns)

    def should_forward_passed(self, fault_code: str, t_ns: int) -> bool:
        """PASSED path: its own tracker, same threshold and window, no bypass."""
        if not self._config.enabled:
            return True
        # _track, inlined: this runs for every OK diagnostic status.
        times = self._passed.get(fault_code)
        if times is None:
            times = self._passed[fault_code] = deque()
        cutoff = t_ns - self._window_ns
        while times and times[0] < cutoff:
            times.popleft()
        times.append(t_ns)
        threshold = self._config.default_threshold
        if len(times) > threshold:
            times.popleft()
        return len(times) >= threshold

    def tracked(self, fault_code: str, *, passed: bool) -> int:
        """Reports of one code in its FAILED (or PASSED) window, as of the last decision."""
        times = (self._passed if passed else self._failed).get(fault_code)
        return len(times) if times is not None else 0

    def reset(self, fault_code: str) -> None:
        """Forget both trackers of one code."""
        self._failed.pop(fault_code, None)
        self._passed.pop(fault_code, None)

    def reset_all(self) -> None:
        """Forget every tracker."""
        self._failed.clear()
        self._passed.clear()

    def _track(self, trackers: dict[str, deque[int]], fault_code: str, t_ns: int) -> bool:
        times = trackers.get(fault_code)
        if times is None:
            times = trackers[fault_code] = deque()
        cutoff = t_ns - self._window_ns
        # Strictly older than the cutoff is dropped; exactly `window` old still counts.
        while times and times[0] < cutoff:
            times.popleft()
        times.append(t_ns)
        threshold = self._config.default_threshold
        if len(times) > threshold:
            # Only the count against the threshold matters; older entries beyond it are
            # redundant for the decision but keep the window semantics, so drop the oldest.
            times.popleft()
        return len(times) >= threshold
