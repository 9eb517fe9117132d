"""What an input skipped while decoding and restoring time order, said once at its end.

Messages that cannot be decoded (per topic) and messages too far out of time order: each a
warning with its loss, worded the same for every kind of input.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.model import Loss

if TYPE_CHECKING:
    from medkit_replay.inputs.source import Warn


def report_skipped(
    warn: Warn, failures: dict[str, tuple[int, int, int, str]], late: tuple[int, int]
) -> None:
    """Warn of ``failures`` (by topic: count, first and last log time, first reason) and of
    ``late`` messages (count, first log time)."""
    for topic, (count, first, last, reason) in sorted(failures.items()):
        warn(
            f"{count} messages on {topic} cannot be decoded and were skipped "
            f"(first at t={first}: {reason})",
            Loss(messages=count, start_ns=first, end_ns=last),
        )
    if late[0]:
        warn(
            f"{late[0]} messages are stored too far out of time order to be "
            f"replayed in order and were skipped (first at t={late[1]})",
            Loss(messages=late[0]),
        )
