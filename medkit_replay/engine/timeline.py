"""Runs the fault manager's timers on bag time between messages (SEMANTICS.md §1).

Pure: ticks lie at t0 + k·period, t0 being the first message's time; due ticks run before a message.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.model import NS_PER_SEC, ClearRequest, ReportRequest

if TYPE_CHECKING:
    from medkit_replay.engine.manager import FaultManager

AUTO_CONFIRM_PERIOD_NS = NS_PER_SEC


def _first_tick_at_or_after(t_ns: int, t0_ns: int, period_ns: int) -> int:
    steps = -((t0_ns - t_ns) // period_ns)  # ceil((t - t0) / period)
    return t0_ns + max(steps, 0) * period_ns


class Timeline:
    """Feeds a FaultManager messages in bag-time order and runs its timers in between.

    Call :meth:`advance` with the time of every message read (whether or not it yields
    requests), then hand its requests to :meth:`apply`.
    """

    def __init__(self, manager: FaultManager) -> None:
        self.manager = manager
        self.t0_ns: int | None = None
        self.last_ns: int | None = None
        self._next_confirm_ns = 0
        self._next_cleanup_ns = 0
        self._cleanup_period_ns = manager.config.cleanup_interval_ns

    def advance(self, t_ns: int) -> None:
        """Run every timer tick due at or before ``t_ns``; ties run before the message."""
        if self.t0_ns is None:
            self.t0_ns = self.last_ns = t_ns
            self._next_confirm_ns = t_ns + AUTO_CONFIRM_PERIOD_NS
            self._next_cleanup_ns = t_ns + self._cleanup_period_ns
            return
        self.last_ns = t_ns
        if self.manager.config.auto_confirm_after_ns > 0 and self._next_confirm_ns <= t_ns:
            self._catch_up_auto_confirm(t_ns)
        if self.manager.correlation is not None and self._next_cleanup_ns <= t_ns:
            # Cleanup prunes more the later it runs: the last due tick subsumes earlier ones.
            last = self._last_tick_at_or_before(t_ns, self._cleanup_period_ns)
            self.manager.cleanup_tick(last)
            self._next_cleanup_ns = last + self._cleanup_period_ns

    def due_ns(self) -> int:
        """The earliest message time at which :meth:`advance` has more to do than noting it.

        Before that, ``advance(t)`` only sets ``last_ns = t``; a caller may do just that.
        """
        if self.t0_ns is None:
            return -(2**63)
        due = 2**63
        if self.manager.config.auto_confirm_after_ns > 0:
            due = self._next_confirm_ns
        if self.manager.correlation is not None:
            due = min(due, self._next_cleanup_ns)
        return due

    def apply(self, request: ReportRequest | ClearRequest) -> None:
        """Hand one request to the manager (after :meth:`advance` for its message)."""
        if isinstance(request, ReportRequest):
            self.manager.report(request)
        else:
            self.manager.clear(request)

    def _last_tick_at_or_before(self, t_ns: int, period_ns: int) -> int:
        assert self.t0_ns is not None
        return self.t0_ns + ((t_ns - self.t0_ns) // period_ns) * period_ns

    def _catch_up_auto_confirm(self, t_ns: int) -> None:
        """Apply every 1 s tick in [next, t_ns] at once.

        Between two messages only these ticks change state, and a tick only confirms
        PREFAILED faults, so each fault's confirming tick is the first one at or after
        ``last_failed + T``; transitions come out in tick order, then fault_code byte order.
        Only the faults due by the last tick are looked at (the storage keeps PREFAILED
        faults ordered by last FAILED time), not every fault.
        """
        assert self.t0_ns is not None
        last_tick = self._last_tick_at_or_before(t_ns, AUTO_CONFIRM_PERIOD_NS)
        after_ns = self.manager.config.auto_confirm_after_ns
        due: list[tuple[int, bytes, str]] = []
        # max(last_failed + T, next) <= last_tick holds iff last_failed + T <= last_tick,
        # since next <= last_tick here and last_tick lies on the tick grid.
        for fault in self.manager.storage.take_prefailed(last_tick - after_ns):
            tick = _first_tick_at_or_after(
                max(fault.last_failed_ns + after_ns, self._next_confirm_ns),
                self.t0_ns,
                AUTO_CONFIRM_PERIOD_NS,
            )
            due.append((tick, fault.fault_code.encode("utf-8"), fault.fault_code))
        due.sort()
        for tick, _, code in due:
            self.manager.confirm_by_timer(code, tick)
        self._next_confirm_ns = last_tick + AUTO_CONFIRM_PERIOD_NS
