"""Which kind of medkit-replay input a YAML file looks like, told from its top-level shape.

Used to say where a file given in the wrong place belongs; parsing each kind stays with its reader.
"""

from __future__ import annotations

from typing import Final, Literal

from yaml.constructor import ConstructorError, SafeConstructor

from medkit_replay.errors import ConfigError
from medkit_replay.evidence.graph import PUBLISHED_KEYS, SUBSCRIBED_KEYS, is_node_info
from medkit_replay.yaml_bounds import compose_config

Kind = Literal["parameters", "correlation", "entity_thresholds", "snapshots", "budget", "graph"]
KINDS: Final[tuple[Kind, ...]] = (
    "parameters",
    "correlation",
    "entity_thresholds",
    "snapshots",
    "budget",
    "graph",
)

WHERE: Final[dict[Kind, str]] = {
    "parameters": "--config",
    "correlation": "fault_manager's correlation.config_file",
    "entity_thresholds": "fault_manager's entity_thresholds.config_file",
    "snapshots": "fault_manager's snapshots.config_file",
    "budget": "--budget (check, fleet, sweep)",
    "graph": "--graph (analyze, explain)",
}
"""Where each kind of file is given to medkit-replay."""

DESCRIBED: Final[dict[Kind, str]] = {
    "parameters": "a ROS 2 parameter file",
    "correlation": "a correlation file",
    "entity_thresholds": "an entity-thresholds file",
    "snapshots": "a snapshot config file",
    "budget": "a fault budget",
    "graph": "a node graph",
}

# The shapes, as each reader documents them (correlation_file.py, entity_thresholds_file.py,
# snapshots.py, checks/budget_file.py, evidence/graph.py).
_ENTITY_FIELDS = frozenset({"confirmation_threshold", "healing_enabled", "healing_threshold"})
_SNAPSHOT_KEYS = frozenset({"fault_specific", "patterns", "default_topics"})
# A budget's own top-level keys; its third, name, tells nothing.
_BUDGET_KEYS = frozenset({"version", "rules"})
_GRAPH_KEYS = frozenset(PUBLISHED_KEYS + SUBSCRIBED_KEYS)


def _holds_parameters(data: dict[object, object]) -> bool:
    """``node: {ros__parameters: ...}`` at any namespace depth."""
    for key, value in data.items():
        if key == "ros__parameters":
            return True
        if isinstance(value, dict) and _holds_parameters(value):
            return True
    return False


def _entries_with(data: dict[object, object], fields: frozenset[str]) -> bool:
    """Every value a map (or empty) of which some name one of ``fields`` and none another."""
    entries = [v for v in data.values() if v is not None]
    if not entries or not all(isinstance(v, dict) for v in entries):
        return False
    keys = {str(k) for v in entries if isinstance(v, dict) for k in v}
    return bool(keys & fields) and not keys & (_ENTITY_FIELDS | _GRAPH_KEYS) - fields


def guess_kind(data: object) -> Kind | None:
    """The kind of file a parsed YAML document looks like, or None when it looks like none.

    Only the top-level shape is looked at: a file of the right kind may still be invalid.
    """
    if not isinstance(data, dict) or not data:
        return None
    keys = {str(k) for k in data}
    if _holds_parameters(data):
        return "parameters"
    if isinstance(data.get("correlation"), dict):
        return "correlation"
    # One known top-level key is enough: a misspelt neighbour is then its reader's to name.
    if keys & _BUDGET_KEYS:
        return "budget"
    if keys & _SNAPSHOT_KEYS:
        return "snapshots"
    if _entries_with(data, _GRAPH_KEYS):
        return "graph"
    if _entries_with(data, _ENTITY_FIELDS):
        return "entity_thresholds"
    return None


def guess_text_kind(text: str, where: str) -> Kind | None:
    """The kind of file a text looks like: a ``ros2 node info`` graph, or a YAML document's
    kind (None when it is not YAML or looks like no kind)."""
    if is_node_info(text):
        return "graph"
    try:
        root = compose_config(text, where)
        data = None if root is None else SafeConstructor().construct_document(root)
    except (ConfigError, ConstructorError):
        return None
    return guess_kind(data)


def belongs(kind: Kind, given: str) -> str:
    """``this looks like a correlation file, not <given kind>: it belongs in fault_manager's
    correlation.config_file, not in <given>``, for a file given in the wrong place."""
    return f"this looks like {DESCRIBED[kind]}: it belongs in {WHERE[kind]}, not in {given}"
