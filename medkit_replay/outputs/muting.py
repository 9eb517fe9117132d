"""What muting did to one fault, in words: which of its FaultEvents were withheld, which published.

Counted from the Result's own reports and events, so every output that explains muting (HTML,
``explain``, tables) says the same thing and never more than what the replay published.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from medkit_replay.model import EVENT_KINDS

if TYPE_CHECKING:
    from medkit_replay.model import MutedFault
    from medkit_replay.result import Result


@dataclass(frozen=True, slots=True, kw_only=True)
class MutedEvents:
    """One fault's FaultEvents by type: those correlation withheld and those published."""

    withheld: dict[str, int]
    published: dict[str, int]


NO_EVENTS = MutedEvents(withheld={}, published={})
"""A fault none of whose events were withheld or published."""


def event_counts(result: Result) -> dict[str, MutedEvents]:
    """Per fault code, its withheld and published FaultEvents counted by type (upstream's
    order), as the engine counted them (the spooled records are never read back for them)."""
    published, withheld = result.event_tally
    order: dict[str, int] = {kind: i for i, kind in enumerate(EVENT_KINDS)}

    def ordered(counts: dict[str, int]) -> dict[str, int]:
        return dict(sorted(counts.items(), key=lambda kv: (order.get(kv[0], len(order)), kv[0])))

    return {
        code: MutedEvents(
            withheld=ordered(withheld.get(code, {})), published=ordered(published.get(code, {}))
        )
        for code in sorted(withheld.keys() | published.keys())
    }


def _listed(counts: dict[str, int]) -> str:
    return ", ".join(f"{n:,} {kind}" for kind, n in counts.items())


def events_words(events: MutedEvents) -> str:
    """``withheld 2 fault_confirmed; published 3 fault_updated, 1 fault_cleared`` (or 'none')."""
    withheld = f"withheld {_listed(events.withheld)}" if events.withheld else "no event withheld"
    published = f"published {_listed(events.published)}" if events.published else "none published"
    return f"{withheld}; {published}"


def delay_words(muted: MutedFault, first_ms: int | None = None) -> str:
    """Upstream's ``delay_ms`` named for what it measures: the last mute, not the first (said
    too when known, from a trace)."""
    first = f"first muted {first_ms} ms, " if first_ms is not None else ""
    return f"{first}last muted {muted.delay_ms} ms after its root {muted.root_cause_code}"


def muting_sentence(events: MutedEvents, muted: MutedFault, first_ms: int | None = None) -> str:
    """The one sentence every output uses for a muted fault: which of its ``events`` were
    withheld, which published (from :func:`event_counts`), and which mute the delay measures;
    ``first_ms``: the first mute's delay, which only a trace knows (``explain``).

    E.g. ``FaultEvents: withheld 1 fault_confirmed; published 3 fault_updated, 1 fault_cleared;
    last muted 3496 ms after its root MOTOR_OVERCURRENT``.
    """
    return f"FaultEvents: {events_words(events)}; {delay_words(muted, first_ms)}"
