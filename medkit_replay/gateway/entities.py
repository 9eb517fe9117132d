"""The SOVD entity tree ros2_medkit's gateway builds by runtime discovery, from ROS node names.

Runtime-only discovery at 505bc2d5 makes no areas, one host component, an app per node and a
function per top-level namespace; ``Entities.fault_sources`` is the fault handlers' scoping.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

if TYPE_CHECKING:
    from collections.abc import Iterable, Sequence

    from medkit_replay.evidence.graph import NodeGraph

Kind = Literal["areas", "components", "apps", "functions"]
KINDS: tuple[Kind, ...] = ("areas", "components", "apps", "functions")

SINGULAR: dict[Kind, str] = {
    "areas": "area",
    "components": "component",
    "apps": "app",
    "functions": "function",
}
"""The entity type discriminator the bodies carry (``type``), and the route's id parameter stem."""

MAX_ENTITY_ID = 256
"""entity_validation.cpp: the longest id a route accepts, in bytes."""
MAX_NODE_NAME = 255
"""rmw: RMW_NODE_NAME_MAX_NAME_LENGTH."""
MAX_NAMESPACE = 245
"""rmw: RMW_NAMESPACE_MAX_LENGTH, the topic name limit (255 - 8) less 2."""

UNKNOWN_HOST = "unknown"
"""host_info_provider.cpp: the host name when gethostname() fails; a recording names no host."""
HOST_DESCRIPTION = "Unknown OS on unknown"
"""host_info_provider.cpp: ``<os> on <arch>`` with neither readable, as for a recording."""
ROOT_FUNCTION = "root"
"""ros2_runtime_introspection.cpp extract_area_from_namespace: the function of ``/``."""

_ROS_TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_ID_BYTES = frozenset(b"abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-")


@dataclass(frozen=True, slots=True)
class Entity:
    """One area, component, app or function, with the fields the discovery handlers read.

    ``namespace`` is an app's node namespace; upstream's ``namespace_path`` for areas and
    components (empty for the host component). ``fqn`` is an app's bound node name. ``parent``
    is an area's parent area or a component's parent component; ``area`` a component's area;
    ``component`` an app's host component; ``hosts`` a function's host ids as discovered.
    """

    kind: Kind
    id: str
    name: str
    namespace: str = ""
    fqn: str = ""
    source: str = ""
    description: str = ""
    component_type: str = ""
    parent: str = ""
    area: str = ""
    component: str = ""
    hosts: tuple[str, ...] = ()
    depends_on: tuple[str, ...] = ()

    @property
    def display_name(self) -> str:
        """The name the list and detail handlers show: the id when the name is empty."""
        return self.name or self.id


class Entities:
    """The discovered entities by kind, in cache order, with the cache's relationship queries."""

    def __init__(self, entities: Iterable[Entity] = ()) -> None:
        # A repeated id keeps its first position and the last payload, as the entity cache's
        # reconcile does (thread_safe_entity_cache.cpp).
        self._by_kind: dict[Kind, dict[str, Entity]] = {kind: {} for kind in KINDS}
        for entity in entities:
            self._by_kind[entity.kind][entity.id] = entity

    def list(self, kind: Kind) -> Sequence[Entity]:
        """Every entity of ``kind`` (sub-areas and sub-components included)."""
        return tuple(self._by_kind[kind].values())

    def get(self, kind: Kind, entity_id: str) -> Entity | None:
        """The entity of ``kind`` with ``entity_id``, or None."""
        return self._by_kind[kind].get(entity_id)

    def kind_of(self, entity_id: str) -> Kind | None:
        """The first collection holding ``entity_id``, searched as get_entity_info does
        without a route type: components, apps, areas, functions (handler_context.cpp)."""
        for kind in ("components", "apps", "areas", "functions"):
            if entity_id in self._by_kind[kind]:
                return kind
        return None

    def subareas(self, area_id: str) -> tuple[Entity, ...]:
        """Areas whose parent is ``area_id``."""
        return tuple(a for a in self._by_kind["areas"].values() if a.parent == area_id)

    def components_in(self, area_id: str) -> tuple[Entity, ...]:
        """Components placed in ``area_id`` itself."""
        return tuple(c for c in self._by_kind["components"].values() if c.area == area_id)

    def contained_components(self, area_id: str) -> tuple[Entity, ...]:
        """Components of ``area_id`` and of every descendant area, in the order the
        contains handler walks them (a stack: an area's own components, then its subareas')."""
        found: list[Entity] = []
        pending = [area_id]
        visited: set[str] = set()
        while pending:
            current = pending.pop()
            if current in visited:
                continue
            visited.add(current)
            found.extend(self.components_in(current))
            pending.extend(a.id for a in self.subareas(current))
        return tuple(found)

    def subcomponents(self, component_id: str) -> tuple[Entity, ...]:
        """Components whose parent is ``component_id``."""
        return tuple(c for c in self._by_kind["components"].values() if c.parent == component_id)

    def apps_on(self, component_id: str) -> tuple[Entity, ...]:
        """Apps located on ``component_id`` (the component's hosts)."""
        return tuple(a for a in self._by_kind["apps"].values() if a.component == component_id)

    def fault_sources(self, entity: Entity) -> frozenset[str]:
        """The reporting-source FQNs whose faults belong to ``entity`` (fault_scope.cpp).

        An app owns its node's FQN; a component its apps'; an area its own and its
        descendants' components'; a function its host apps' (or host components').
        A fault is the entity's when every reporting source equals one of these or lies
        under one (``fqn + "/"``), which is filter_faults_by_sources' business.
        """
        found: set[str] = set()
        if entity.kind == "apps":
            self._add_app(entity.id, found)
        elif entity.kind == "components":
            self._add_component(entity.id, found)
        elif entity.kind == "areas":
            for component in self.contained_components(entity.id):
                self._add_component(component.id, found)
        else:
            for host in entity.hosts:
                if host in self._by_kind["apps"]:
                    self._add_app(host, found)
                elif host in self._by_kind["components"]:
                    self._add_component(host, found)
        return frozenset(found)

    def _add_app(self, app_id: str, found: set[str]) -> None:
        app = self._by_kind["apps"].get(app_id)
        if app is not None and app.fqn:
            found.add(app.fqn)

    def _add_component(self, component_id: str, found: set[str]) -> None:
        # Runtime discovery makes no external components, so a component never owns its own id.
        for app in self.apps_on(component_id):
            self._add_app(app.id, found)


def validate_entity_id(entity_id: str) -> str | None:
    """Why a route refuses ``entity_id`` (entity_validation.cpp), or None when it accepts it.

    Counted and checked over UTF-8 bytes, as the C++ string is.
    """
    raw = entity_id.encode("utf-8", "surrogatepass")
    if not raw:
        return "Entity ID cannot be empty"
    if len(raw) > MAX_ENTITY_ID:
        return f"Entity ID too long (max {MAX_ENTITY_ID} characters)"
    for byte in raw:
        if byte not in _ID_BYTES:
            shown = chr(byte) if 32 <= byte <= 126 else f"0x{byte:02x}"
            return (
                f"Entity ID contains invalid character: '{shown}'. "
                "Only alphanumeric, underscore and hyphen are allowed"
            )
    return None


def split_node_name(name: str) -> tuple[str, str] | None:
    """``(namespace, node)`` of a valid fully qualified ROS 2 node name, else None.

    rmw's rules: an absolute namespace of tokens that are letters, digits and underscores
    not starting with a digit (at most 245 characters), and a node name of the same
    alphabet (at most 255). Anything else cannot be a node on a live graph.
    """
    if not name.startswith("/"):
        return None
    cut = name.rfind("/")
    namespace, node = name[:cut] or "/", name[cut + 1 :]
    if not _ROS_TOKEN.match(node) or len(node) > MAX_NODE_NAME:
        return None
    if len(namespace) > MAX_NAMESPACE:
        return None
    if cut and not all(_ROS_TOKEN.match(token) for token in name[1:cut].split("/")):
        return None
    return namespace, node


def sanitize_host_id(host: str) -> str:
    """A host name as the host component's id (host_info_provider.cpp sanitize_entity_id):
    ``.`` and space become ``_``, letters are lowered, other characters dropped."""
    kept = []
    for char in host:
        if char in ". ":
            kept.append("_")
        elif char.isascii() and (char.isalnum() or char in "_-"):
            kept.append(char.lower())
    return "".join(kept)[:MAX_ENTITY_ID] or "unknown_host"


def function_of_namespace(namespace: str) -> str:
    """The runtime function a namespace belongs to: its first segment, ``root`` for ``/``."""
    if namespace in ("", "/"):
        return ROOT_FUNCTION
    return namespace.removeprefix("/").split("/", 1)[0]


def discover(
    node_names: Iterable[str], graph: NodeGraph | None = None, *, host: str = UNKNOWN_HOST
) -> Entities:
    """The entities a runtime-only gateway would discover with these nodes on the graph.

    ``node_names`` and the graph's nodes are joined; a name that is not a valid ROS 2 node
    FQN is skipped (a live graph holds none, so no app owns such a source and its faults
    show only in the global list). Defaults of 505bc2d5 apply: create_functions_from_namespaces,
    default_component.enabled and filter_internal_nodes are on.
    """
    names = set(node_names)
    if graph is not None:
        names.update(graph.publishes, graph.subscribes)
    nodes = sorted(parts for name in names if (parts := split_node_name(name)) is not None)
    spaces: dict[str, set[str]] = {}
    for namespace, node in nodes:
        spaces.setdefault(node, set()).add(namespace)
    component = Entity(
        kind="components",
        id=sanitize_host_id(host),
        name=host,
        source="runtime",
        description=HOST_DESCRIPTION,
        component_type="Component",
    )
    apps: list[Entity] = []
    for namespace, node in nodes:
        app_id = node
        if len(spaces[node]) > 1 and namespace != "/":
            # ros2_runtime_introspection.cpp: a bare name in several namespaces is qualified.
            app_id = namespace[1:].replace("/", "_") + "_" + node
        if validate_entity_id(app_id) is not None:
            continue  # longer than any route accepts: no client could address it
        fqn = namespace.rstrip("/") + "/" + node
        apps.append(
            Entity(
                kind="apps",
                id=app_id,
                name=node,
                namespace=namespace,
                fqn=fqn,
                source="heuristic",
                component=component.id,
            )
        )
    # Functions group every app, internal nodes included; the internal filter runs after
    # (gateway_node.cpp refresh_cache), so a function may list a host no longer in /apps.
    grouped: dict[str, list[str]] = {}
    for app in apps:
        grouped.setdefault(function_of_namespace(app.namespace), []).append(app.id)
    functions = [
        Entity(kind="functions", id=fid, name=fid, source="runtime", hosts=tuple(hosts))
        for fid, hosts in sorted(grouped.items(), key=lambda item: item[0].encode())
    ]
    kept = [app for app in apps if not app.id.startswith("_")]
    return Entities([component, *kept, *functions])
