"""Progress of one pass over a recording, told to a replay's ``progress`` callback.

Cheap to tick: the loop compares a message count with the next reporting point.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.model import Phase, Progress

if TYPE_CHECKING:
    from collections.abc import Callable

    from medkit_replay.inputs import Recording


class Meter:
    """Calls a progress callback every ``every`` messages of one pass (cheap to tick)."""

    __slots__ = ("callback", "end_ns", "every", "next_at", "phase", "start_ns")

    def __init__(
        self,
        callback: Callable[[Progress], None],
        phase: Phase,
        recording: Recording,
        every: int,
    ) -> None:
        self.callback = callback
        self.phase: Phase = phase
        span = recording.span
        self.start_ns: int | None = span[0] if span is not None else None
        self.end_ns: int | None = span[1] if span is not None else None
        self.every = max(every, 1)
        self.next_at = self.every
        callback(Progress(phase, 0, None, self.start_ns, self.end_ns))

    def tick(self, messages: int, t_ns: int) -> None:
        """Report; called by the loop when ``messages`` reaches ``next_at``."""
        self.next_at = messages + self.every
        self.callback(Progress(self.phase, messages, t_ns, self.start_ns, self.end_ns))

    def finish(self, messages: int, t_ns: int | None) -> None:
        """Report the end of the pass."""
        self.callback(Progress(self.phase, messages, t_ns, self.start_ns, self.end_ns, done=True))
