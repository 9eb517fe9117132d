"""Upstream's capture settings (``snapshots.*``, ``snapshots.rosbag.*``) and the pure rules that
pick topics from them: freeze-frame resolution order, entity scope, the black box's subscribe set.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Iterable

    from medkit_replay.evidence.graph import NodeGraph

ENTITY_TOPIC_CAP = 16
"""Upstream's bound on entity-default freeze-frame topics (the first 16 in name order)."""
ATTACHED_FAULT_CAP = 32
"""Faults confirming in one post-roll that get their own row for the shared recording."""
ALWAYS_SKIPPED = ("/rosout", "/parameter_events")
SENSOR_SEGMENTS = ("/image", "/points", "/depth", "/compressed")


@dataclass(frozen=True, slots=True, kw_only=True)
class RosbagConfig:
    """``snapshots.rosbag.*`` with upstream's defaults (fault-manager.md §3.3)."""

    enabled: bool = False
    duration_sec: float = 5.0
    duration_after_sec: float = 1.0
    topics: str = "entity"
    include_topics: tuple[str, ...] = ()
    exclude_topics: tuple[str, ...] = ()
    exclude_sensor_topics: bool = True
    lazy_start: bool = False
    format: str = "mcap"
    max_bag_size_mb: int = 50
    max_bags_per_fault: int = 1
    auto_cleanup: bool = True
    bag_history: bool = True
    """max_bags_per_fault is a parameter (False: one recording per fault, replaced by the next)."""
    post_roll_sharing: bool = True
    """A fault confirmed during another's post-roll joins it (False: it gets no recording)."""
    post_roll_only: bool = True
    """Nothing buffered but a post-roll to come still makes a recording (False: none)."""
    cleanup_in_post_roll: bool = True
    """A fault cleared during its own post-roll gets no row (False: its row is stored)."""

    @property
    def keeps_history(self) -> bool:
        """A cap other than 1 is a history someone configured: acknowledging keeps it."""
        return self.max_bags_per_fault != 1


@dataclass(frozen=True, slots=True, kw_only=True)
class SnapshotConfig:
    """``snapshots.*`` with upstream's defaults; ``patterns`` keeps upstream's sorted order."""

    enabled: bool = True
    background_capture: bool = False
    timeout_sec: float = 1.0
    max_message_size: int = 65536
    default_topics: tuple[str, ...] = ()
    entity_default: bool = True
    fault_specific: dict[str, tuple[str, ...]] = field(default_factory=dict)
    patterns: tuple[tuple[str, tuple[str, ...]], ...] = ()
    recapture_cooldown_sec: float = 60.0
    retain_on_clear: bool = False
    max_per_fault: int = 10
    freeze_frame_row: bool = True
    """A capture also writes the fault's compact freeze frame (Release.freeze_frame_row)."""
    snapshot_sets: bool = True
    """max_per_fault evicts whole capture sets, oldest first (False: a fault's first
    max_per_fault rows are kept and later ones refused; Release.snapshot_sets)."""
    rosbag: RosbagConfig = field(default_factory=RosbagConfig)

    @property
    def captures(self) -> bool:
        """Upstream builds its capture pool (and so runs the cooldown) for either capture."""
        return self.enabled or self.rosbag.enabled

    def configured_topics(self) -> list[str]:
        """Every topic named by fault_specific, patterns and default_topics, in name order."""
        named = set(self.default_topics)
        for topics in self.fault_specific.values():
            named.update(topics)
        for _, topics in self.patterns:
            named.update(topics)
        return sorted(named)


@dataclass(frozen=True, slots=True)
class Resolution:
    """The freeze-frame topics of one fault code and where they came from."""

    topics: tuple[str, ...]
    source: str  # fault_specific, pattern, default_topics, entity_default, none
    explicit: bool


def resolve_configured(config: SnapshotConfig, fault_code: str) -> Resolution:
    """fault_specific (exact) > first fully-matching pattern (sorted) > default_topics.

    A code or pattern listed with no topics is an explicit opt-out: no fallback follows.
    Patterns that do not compile were dropped when the config was read.
    """
    if fault_code in config.fault_specific:
        return Resolution(config.fault_specific[fault_code], "fault_specific", True)
    for pattern, topics in config.patterns:
        if re.fullmatch(pattern, fault_code):
            return Resolution(topics, "pattern", True)
    if config.default_topics:
        return Resolution(config.default_topics, "default_topics", True)
    return Resolution((), "none", False)


def node_key(source: str, *, ros_only: bool) -> str | None:
    """A reporting source as a node's full name, or None when it names no ROS node.

    The freeze frame only matches ``/``-rooted names (plugin ids are skipped); the black box
    treats a bare id as a node in the root namespace, as upstream's two resolvers differ.
    """
    if ros_only and (len(source) < 2 or not source.startswith("/")):
        return None
    slash = source.rfind("/")
    name = source[slash + 1 :]
    if not name:
        return None
    namespace = "/" if slash <= 0 else source[:slash]
    return (namespace.rstrip("/") or "") + "/" + name


def entity_snapshot_topics(graph: NodeGraph, sources: Iterable[str]) -> tuple[str, ...]:
    """Topics the reporting node(s) publish, minus /rosout and /parameter_events, first 16."""
    nodes = {key for s in sources if (key := node_key(s, ros_only=True)) is not None}
    topics = sorted({t for node in nodes for t in graph.published(node) if t not in ALWAYS_SKIPPED})
    return tuple(topics[:ENTITY_TOPIC_CAP])


def entity_rosbag_topics(
    graph: NodeGraph, sources: Iterable[str], subscribed: Iterable[str]
) -> set[str]:
    """Topics the reporting node(s) publish or subscribe, plus /tf and /tf_static when any,
    kept to what the black box subscribed; empty means upstream writes the whole buffer."""
    nodes = {key for s in sources if (key := node_key(s, ros_only=False)) is not None}
    topics = {t for node in nodes for t in (*graph.published(node), *graph.subscribed(node))}
    if topics:
        topics |= {"/tf", "/tf_static"}
    return topics & set(subscribed)


def is_sensor_topic(topic: str) -> bool:
    """Upstream's high-bandwidth test: the name contains one of the sensor segments."""
    return any(segment in topic for segment in SENSOR_SEGMENTS)


def subscribed_topics(config: SnapshotConfig, recorded: Iterable[str]) -> list[str]:
    """The black box's subscribe set, from the topics the recording holds (upstream's graph).

    ``config`` reuses the freeze-frame topics; ``all``/``auto``/``entity`` take every topic
    but internal and (by default) sensor ones; ``explicit`` only ``include_topics``; anything
    else is a comma-separated list. Then include_topics are added, exclude_topics removed.
    """
    rosbag = config.rosbag
    mode = rosbag.topics
    chosen: set[str] = set()
    if mode == "config":
        chosen.update(config.configured_topics())
    elif mode in ("all", "auto", "entity"):
        for topic in recorded:
            if any(internal in topic for internal in ALWAYS_SKIPPED):
                continue
            if rosbag.exclude_sensor_topics and is_sensor_topic(topic):
                continue
            chosen.add(topic)
    elif mode != "explicit":
        chosen.update(part.strip(" \t") for part in mode.split(","))
        chosen.discard("")
    chosen.update(rosbag.include_topics)
    chosen.difference_update(rosbag.exclude_topics)
    return sorted(chosen)


def evict_capture_sets(rows: list[tuple[int, int]], cap: int) -> set[int]:
    """The capture ids ``max_per_fault`` evicts from one fault's (capture_id, row count) sets.

    Whole sets go, oldest first, until the rows fit; the newest set always stays.
    """
    if cap <= 0 or not rows:
        return set()
    newest = max(capture_id for capture_id, _ in rows)
    kept = sorted(rows)
    evicted: set[int] = set()
    while sum(count for _, count in kept) > cap:
        oldest = next((entry for entry in kept if entry[0] != newest), None)
        if oldest is None:
            break
        kept.remove(oldest)
        evicted.add(oldest[0])
    return evicted


def recording_name(fault_code: str, t_ns: int) -> str:
    """Upstream's folder name ``fault_<CODE>_<ms>``, made safe as one path component.

    Anything but letters, digits, ``_``, ``-`` and ``.`` becomes ``_`` so a fault code can
    never name a parent directory or a path outside the evidence folder.
    """
    safe = re.sub(r"[^A-Za-z0-9_.-]", "_", fault_code).replace("..", "__")
    return f"fault_{safe}_{t_ns // 1_000_000}"
