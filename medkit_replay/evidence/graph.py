"""The robot's node graph (which node publishes and subscribes which topic), read from --graph.

A recording holds no node names; entity-scoped capture needs them. Two forms: a YAML map
``node: {publishers: [...], subscribers: [...]}``, or the concatenated ``ros2 node info`` text.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from yaml.constructor import ConstructorError, SafeConstructor

from medkit_replay.errors import ConfigError
from medkit_replay.files import read_limited_text
from medkit_replay.yaml_bounds import compose_config

if TYPE_CHECKING:
    from pathlib import Path

PUBLISHED_KEYS = ("publishers", "publishes", "published", "pub")
SUBSCRIBED_KEYS = ("subscribers", "subscribes", "subscribed", "sub")
_INFO_SECTIONS = {"Publishers:": "pub", "Subscribers:": "sub"}


@dataclass(frozen=True, slots=True)
class NodeGraph:
    """Node full name -> the topics it publishes and subscribes."""

    publishes: dict[str, frozenset[str]] = field(default_factory=dict)
    subscribes: dict[str, frozenset[str]] = field(default_factory=dict)

    def published(self, node: str) -> frozenset[str]:
        """Topics ``node`` publishes (none for a node the graph does not know)."""
        return self.publishes.get(node, frozenset())

    def subscribed(self, node: str) -> frozenset[str]:
        """Topics ``node`` subscribes to."""
        return self.subscribes.get(node, frozenset())


def load_graph(path: Path) -> NodeGraph:
    """Read a node graph file in either form.

    Raises:
        ConfigError: unreadable, or neither form, naming the file (and line).
    """
    try:
        text = read_limited_text(path)
    except (OSError, UnicodeDecodeError) as err:
        raise ConfigError(f"cannot read the node graph: {err}", path=str(path)) from None
    if is_node_info(text):
        return _from_node_info(text, str(path))
    return _from_yaml(text, str(path))


def is_node_info(text: str) -> bool:
    """Whether a graph file is ``ros2 node info`` text: its first line a node name, no colon."""
    first = next((line for line in text.splitlines() if line.strip()), "")
    return first.startswith("/") and not first.rstrip().endswith(":")


def _from_node_info(text: str, path: str) -> NodeGraph:
    """Parse ``ros2 node info`` blocks: a node name at column 0, then indented sections."""
    pubs: dict[str, set[str]] = {}
    subs: dict[str, set[str]] = {}
    node: str | None = None
    section: str | None = None
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        if not line[0].isspace():
            name = line.strip()
            if not name.startswith("/"):
                raise ConfigError(
                    f"expected a node name (/ns/node), found {name[:60]!r}", path=path, line=number
                )
            node, section = name, None
            pubs.setdefault(node, set())
            subs.setdefault(node, set())
            continue
        stripped = line.strip()
        if stripped.endswith(":") and not stripped.startswith("/"):
            section = _INFO_SECTIONS.get(stripped)
            continue
        if node is None:
            raise ConfigError("a topic line before any node name", path=path, line=number)
        if section is not None and stripped.startswith("/"):
            topic = stripped.split(":", 1)[0].strip()
            (pubs if section == "pub" else subs)[node].add(topic)
    return _graph(pubs, subs)


def _topics(value: object, path: str, node: str) -> set[str]:
    if value is None:
        return set()
    if isinstance(value, dict):
        value = list(value)
    if not isinstance(value, list) or not all(isinstance(t, str) for t in value):
        raise ConfigError(f"node {node!r}: topics must be a list of names", path=path)
    return set(value)


def _from_yaml(text: str, path: str) -> NodeGraph:
    root = compose_config(text, path)
    if root is None:
        return NodeGraph()
    try:
        data = SafeConstructor().construct_document(root)
    except ConstructorError as err:
        raise ConfigError(f"invalid YAML: {err.problem}", path=path) from None
    if not isinstance(data, dict):
        raise ConfigError(
            "a node graph is a map of node name -> {publishers: [...], subscribers: [...]} "
            "or the text of `ros2 node info` for every node",
            path=path,
            line=root.start_mark.line + 1,
        )
    pubs: dict[str, set[str]] = {}
    subs: dict[str, set[str]] = {}
    for node, entry in data.items():
        name = str(node)
        if not name.startswith("/"):
            name = "/" + name
        if not isinstance(entry, dict):
            raise ConfigError(f"node {name!r}: expected publishers/subscribers", path=path)
        unknown = [k for k in entry if k not in PUBLISHED_KEYS + SUBSCRIBED_KEYS]
        if unknown:
            raise ConfigError(f"node {name!r}: unknown key {unknown[0]!r}", path=path)
        pubs[name] = set().union(
            *(_topics(entry[k], path, name) for k in PUBLISHED_KEYS if k in entry)
        )
        subs[name] = set().union(
            *(_topics(entry[k], path, name) for k in SUBSCRIBED_KEYS if k in entry)
        )
    return _graph(pubs, subs)


def _graph(pubs: dict[str, set[str]], subs: dict[str, set[str]]) -> NodeGraph:
    return NodeGraph(
        {n: frozenset(t) for n, t in pubs.items()}, {n: frozenset(t) for n, t in subs.items()}
    )
