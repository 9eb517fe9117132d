"""Freeze frames: the message each capture would have taken per topic, decoded and rendered.

Only the kept messages are decoded. Storage (the per-fault cap, clear, the retained freeze frame)
is replayed over the captures and clears in time order to say what the manager would still hold.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.captures import SnapshotCapture, SnapshotTopic
from medkit_replay.evidence.render import render
from medkit_replay.evidence.rules import evict_capture_sets
from medkit_replay.inputs.typestore import message_store
from medkit_replay.model import NS_PER_SEC

if TYPE_CHECKING:
    from medkit_replay.evidence.plan import Plan, PlannedCapture
    from medkit_replay.evidence.rules import SnapshotConfig
    from medkit_replay.evidence.source import EvidenceSource, RawMessage


def sample(
    capture: PlannedCapture, config: SnapshotConfig, source: EvidenceSource
) -> tuple[SnapshotTopic, ...]:
    """Each resolved topic's value, in resolution order; topics that yield nothing are left out.

    On demand: the first message in (tc, tc + timeout_sec]; from the background cache: the last
    one at or before tc. A message over ``max_message_size`` bytes is skipped unread.
    """
    timeout_ns = round(config.timeout_sec * NS_PER_SEC)
    taken: list[SnapshotTopic] = []
    for topic in capture.topics:
        info = source.topics.get(topic)
        if info is None:
            continue  # no publisher: upstream skips the topic
        message: RawMessage | None
        if capture.background:
            message = source.last(topic, capture.t_ns, config.max_message_size)
        else:
            message = source.first(topic, capture.t_ns, capture.t_ns + timeout_ns)
            if message is not None and len(message.data) > config.max_message_size:
                message = None
        if message is None:
            continue
        try:
            store = message_store(info.type, info.definition)
            decoded = store.deserialize_cdr(message.data, info.type)
            data = render(store, info.type, decoded)
        except ImportError:
            raise  # the environment, not the message
        except Exception:  # DefinitionError, rosbags' errors: upstream logs and skips the topic
            continue
        taken.append(
            SnapshotTopic(topic=topic, message_type=info.type, message_t_ns=message.t_ns, data=data)
        )
    return tuple(taken)


def freeze_frames(
    plan: Plan, config: SnapshotConfig, source: EvidenceSource, cut: list[int] | None = None
) -> tuple[SnapshotCapture, ...]:
    """Every capture with its values and what the live manager would hold of it at the end;
    ``cut``, if given, receives the ids of captures held only in part (0.6.0's row limit)."""
    sampled = {id(c): sample(c, config, source) for c in plan.captures}
    store = _store_set if config.snapshot_sets else _store_rows
    stored: dict[str, list[tuple[int, int]]] = {}  # fault code -> (capture id, rows)
    frame: dict[str, tuple[int, bool]] = {}  # fault code -> (capture id, holds values)
    for step in plan.steps:
        capture = step.capture
        if capture is None:
            if not config.retain_on_clear:
                stored.pop(step.fault_code, None)
            continue
        topics = sampled[id(capture)]
        code = capture.fault_code
        if topics:
            stored[code] = store(stored.get(code, []), capture.capture_id, len(topics), config)
            frame[code] = (capture.capture_id, True)
        elif not capture.entity_scoped and not frame.get(code, (0, False))[1]:
            frame[code] = (capture.capture_id, False)
    if not config.freeze_frame_row:
        frame = {}
    held = {capture_id for sets in stored.values() for capture_id, _ in sets}
    if cut is not None:
        rows = {capture_id: n for sets in stored.values() for capture_id, n in sets}
        cut += [
            c.capture_id
            for c in plan.captures
            if c.capture_id in rows and rows[c.capture_id] < len(sampled[id(c)])
        ]
    frames = {capture_id for capture_id, _ in frame.values()}
    return tuple(
        SnapshotCapture(
            fault_code=c.fault_code,
            capture_id=c.capture_id,
            t_ns=c.t_ns,
            retained=c.capture_id in held,
            freeze_frame=c.capture_id in frames,
            topics=sampled[id(c)],
        )
        for c in plan.captures
    )


def _store_set(
    sets: list[tuple[int, int]], capture_id: int, rows: int, config: SnapshotConfig
) -> list[tuple[int, int]]:
    """Store a capture as one set; ``max_per_fault`` evicts whole sets, oldest first."""
    sets = [*sets, (capture_id, rows)]
    gone = evict_capture_sets(sets, config.max_per_fault)
    return [s for s in sets if s[0] not in gone]


def _store_rows(
    sets: list[tuple[int, int]], capture_id: int, rows: int, config: SnapshotConfig
) -> list[tuple[int, int]]:
    """Store a capture row by row while the fault holds fewer than ``max_per_fault`` rows;
    later rows are refused (0.6.0: the first rows are kept, a capture may be cut short)."""
    cap = config.max_per_fault
    room = rows if cap <= 0 else min(rows, cap - sum(n for _, n in sets))
    return [*sets, (capture_id, room)] if room > 0 else sets
