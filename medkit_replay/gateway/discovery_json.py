"""Bodies of the gateway's server and discovery routes, as ros2_medkit's handlers build them.

``GET /``, ``/version-info``, ``/health``, the entity lists, details and relationship collections,
following health_handlers.cpp, discovery_handlers.cpp and handler_context.cpp at 505bc2d5.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.gateway.entities import SINGULAR, Entities, Entity, Kind, validate_entity_id
from medkit_replay.gateway.errors import (
    ERR_ENTITY_NOT_FOUND,
    TYPE_NAMES,
    GatewayError,
    check_entity_id,
    entity_not_found,
    invalid_parameter,
    wrong_entity_type,
)
from medkit_replay.version import __version__

if TYPE_CHECKING:
    from collections.abc import Sequence

Body = dict[str, object]

API_BASE = "/api/v1"
SOVD_VERSION = "1.0.0"
"""core/version.hpp kSovdVersion."""
WARNING_SCHEMA_VERSION = 2
"""warning_codes.hpp kWarningSchemaVersion."""
SERVER_NAME = "medkit-replay"
"""What ``GET /`` and ``/version-info`` name: not the live gateway, a recording served."""

RELATIONS: dict[Kind, tuple[str, ...]] = {
    "areas": ("components", "subareas", "contains"),
    "components": ("subcomponents", "hosts", "depends-on"),
    "apps": ("is-located-on", "belongs-to", "depends-on"),
    "functions": ("hosts",),
}
"""Each kind's relationship sub-collections, in the order rest_server.cpp registers them."""


def _served_routes() -> tuple[str, ...]:
    routes = ["/health", "/", "/version-info", "/areas", "/apps", "/components", "/functions"]
    for kind, relations in RELATIONS.items():
        entity = f"/{kind}/{{{SINGULAR[kind]}_id}}"
        routes += [f"{entity}/faults", f"{entity}/faults/{{fault_code}}"]
        routes += [f"{entity}/bulk-data", f"{entity}/bulk-data/{{category_id}}"]
        routes.append(f"{entity}/bulk-data/{{category_id}}/{{file_id}}")
        routes += [f"{entity}/{relation}" for relation in relations]
        routes.append(entity)
    return (*routes, "/faults/stream", "/faults")


SERVED_ROUTES = _served_routes()
"""The GET routes served, below the API base, in rest_server.cpp's registration order."""


def root_body(routes: Sequence[str] = SERVED_ROUTES) -> Body:
    """``GET /`` (RootOverview): the served endpoints and what this server can do."""
    capabilities = {
        "discovery": True,
        "data_access": False,
        "operations": False,
        "async_actions": False,
        "configurations": False,
        "faults": True,
        "logs": False,
        "bulk_data": True,
        "cyclic_subscriptions": False,
        "locking": False,
        "triggers": False,
        "updates": False,
        "authentication": False,
        "tls": False,
        "scripts": False,
        "aggregation": False,
        "vendor_extensions": False,
    }
    return {
        "name": SERVER_NAME,
        "version": __version__,
        "api_base": API_BASE,
        "endpoints": [f"GET {API_BASE}{route}" for route in routes],
        "capabilities": capabilities,
    }


def version_info_body() -> Body:
    """``GET /version-info``: the SOVD version served, and medkit-replay as the vendor."""
    vendor = {"version": __version__, "name": SERVER_NAME}
    return {"items": [{"version": SOVD_VERSION, "base_uri": API_BASE, "vendor_info": vendor}]}


def health_body(timestamp_ns: int) -> Body:
    """``GET /health`` (HealthStatus) of a runtime-only gateway; ``timestamp_ns`` is the caller's
    choice of clock (nanoseconds since the epoch upstream)."""
    return {
        "status": "healthy",
        "timestamp": timestamp_ns,
        "discovery": {"mode": "runtime_only", "strategy": "runtime"},
        "warning_schema_version": WARNING_SCHEMA_VERSION,
        "warnings": [],
    }


# -- refusals ------------------------------------------------------------------------------


def route_entity(entities: Entities, kind: Kind, entity_id: str) -> Entity:
    """The entity a ``/{kind}/{id}...`` route addresses, refused as validate_entity_for_route
    refuses (handler_context.cpp): a bad id 400, an id of another kind 400, none 404.

    Raises:
        GatewayError: the refusal.
    """
    check_entity_id(entity_id)
    entity = entities.get(kind, entity_id)
    if entity is not None:
        return entity
    actual = entities.kind_of(entity_id)
    if actual is not None:
        raise wrong_entity_type(entity_id, kind, actual)
    raise entity_not_found(entity_id)


def relation_owner(entities: Entities, kind: Kind, entity_id: str) -> Entity:
    """The entity whose relationship sub-collection is asked for. Apps' go through
    route_entity; areas', components' and functions' validate the id and look only in
    their own collection (``Invalid area ID`` 400, ``Area not found`` 404).

    Raises:
        GatewayError: the refusal.
    """
    if kind == "apps":
        return route_entity(entities, kind, entity_id)
    singular = SINGULAR[kind]
    id_key = f"{singular}_id"
    problem = validate_entity_id(entity_id)
    if problem is not None:
        raise invalid_parameter(f"Invalid {singular} ID", {"details": problem, id_key: entity_id})
    entity = entities.get(kind, entity_id)
    if entity is None:
        message = f"{TYPE_NAMES[kind]} not found"
        raise GatewayError(404, ERR_ENTITY_NOT_FOUND, message, {id_key: entity_id})
    return entity


# -- list items ----------------------------------------------------------------------------


def _href(kind: Kind, entity_id: str) -> str:
    return f"{API_BASE}/{kind}/{entity_id}"


def _item(entity: Entity, *, described: bool = False) -> Body:
    item: Body = {
        "id": entity.id,
        "name": entity.display_name,
        "href": _href(entity.kind, entity.id),
        "type": SINGULAR[entity.kind],
    }
    if described and entity.description:
        item["description"] = entity.description
    return item


def _area_item(area: Entity, *, described: bool) -> Body:
    item = _item(area, described=described)
    if area.namespace:
        item["x-medkit"] = {"ros2": {"namespace": area.namespace}}
    return item


def _component_x(component: Entity, *, node: bool) -> Body:
    """A component item's x-medkit: ``ros2.node`` only in /components, which also reads fqn."""
    x: Body = {}
    ros2: Body = {}
    if node and component.fqn:
        ros2["node"] = component.fqn
    if component.namespace:
        ros2["namespace"] = component.namespace
    if ros2:
        x["ros2"] = ros2
    if component.source:
        x["source"] = component.source
    return x


def _component_item(component: Entity, *, described: bool, node: bool = False) -> Body:
    item = _item(component, described=described)
    item["x-medkit"] = _component_x(component, node=node)
    return item


def _app_x(app: Entity, *, node: bool = True, located: bool = False) -> Body:
    x: Body = {}
    if node and app.fqn:
        x["ros2"] = {"node": app.fqn}
    if app.source:
        x["source"] = app.source
    x["is_online"] = True  # every discovered app is a node seen on the graph
    if located and app.component:
        x["component_id"] = app.component
    return x


def _app_item(app: Entity, *, described: bool = False, located: bool = False) -> Body:
    item = _item(app, described=described)
    item["x-medkit"] = _app_x(app, located=located)
    return item


def _function_item(function: Entity) -> Body:
    item = _item(function, described=True)
    item["x-medkit"] = {"source": function.source} if function.source else {}
    return item


def _collection(items: list[Body], links: dict[str, str] | None = None) -> Body:
    body: Body = {"items": items, "x-medkit": {"total_count": len(items)}}
    if links is not None:
        body["_links"] = links
    return body


def list_body(entities: Entities, kind: Kind) -> Body:
    """``GET /areas``, ``/components``, ``/apps``, ``/functions``: top-level entities only
    (sub-areas and sub-components are listed under their parent)."""
    found = entities.list(kind)
    if kind == "areas":
        items = [_area_item(a, described=True) for a in found if not a.parent]
    elif kind == "components":
        items = [_component_item(c, described=True, node=True) for c in found if not c.parent]
    elif kind == "apps":
        items = [_app_item(a, described=True, located=True) for a in found]
    else:
        items = [_function_item(f) for f in found]
    return _collection(items)


# -- details -------------------------------------------------------------------------------

_RESOURCES = ("data", "operations", "configurations", "faults")
_TAIL = ("cyclic-subscriptions", "triggers")
_URIS: dict[Kind, tuple[str, ...]] = {
    "areas": ("subareas", "components", "contains", *_RESOURCES, "logs", "bulk-data", "triggers"),
    "components": ("status", *_RESOURCES, "subcomponents", "hosts", "logs", "bulk-data", *_TAIL),
    "apps": ("status", *_RESOURCES, "logs", "bulk-data", *_TAIL),
    "functions": ("hosts", *_RESOURCES, "logs", "bulk-data", "x-medkit-graph", *_TAIL),
}
"""The collection URIs every detail carries, in the handlers' order."""

_CAPABILITIES: dict[Kind, tuple[str, ...]] = {
    "areas": ("subareas", "contains", "faults", "bulk-data"),
    "components": ("faults", "subcomponents", "hosts", "bulk-data"),
    "apps": ("faults", "bulk-data"),
    "functions": ("hosts", "faults", "bulk-data"),
}
"""What each detail handler advertises before its conditional entries, less what no route
here serves (status, data, operations, configurations, logs, cyclic subscriptions, triggers):
upstream prunes a capability whose route would 404 (prune_plugin_unserved_capabilities)
rather than advertise a dead link."""


def _capabilities(entity: Entity, names: Sequence[str]) -> list[Body]:
    base = _href(entity.kind, entity.id)
    return [{"name": name, "href": f"{base}/{name}"} for name in names]


def detail_body(entities: Entities, entity: Entity) -> Body:
    """``GET /{kind}/{id}``: the entity with its collection URIs, capabilities and links."""
    base = _href(entity.kind, entity.id)
    body: Body = {
        "id": entity.id,
        # get_app alone shows the raw name; the others fall back to the id.
        "name": entity.name if entity.kind == "apps" else entity.display_name,
        "type": SINGULAR[entity.kind],
    }
    if entity.description:
        body["description"] = entity.description
    body.update({uri: f"{base}/{uri}" for uri in _URIS[entity.kind]})
    capabilities = list(_CAPABILITIES[entity.kind])
    links: Body = {"self": base, "collection": f"{API_BASE}/{entity.kind}"}
    x: Body
    if entity.kind == "areas":
        if entity.parent:
            links["parent"] = _href("areas", entity.parent)
        x = {"ros2": {"namespace": entity.namespace}} if entity.namespace else {}
        if entity.parent:
            x["parent_area_id"] = entity.parent
    elif entity.kind == "components":
        if entity.depends_on:
            body["depends-on"] = f"{base}/depends-on"
            capabilities.append("depends-on")
        if entity.area:
            body["belongs-to"] = _href("areas", entity.area)
            links["area"] = _href("areas", entity.area)
        if entity.parent:
            links["parent"] = _href("components", entity.parent)
        x = _component_x(entity, node=True)
        if entity.component_type:
            x["type"] = entity.component_type
        if entity.parent:
            x["parentComponentId"] = entity.parent
        if entity.depends_on:
            x["dependsOn"] = list(entity.depends_on)
        if entity.area:
            x["area"] = entity.area
        if entity.description:
            x["description"] = entity.description
    elif entity.kind == "apps":
        if entity.component:
            body["is-located-on"] = _href("components", entity.component)
            body["belongs-to"] = f"{base}/belongs-to"
            capabilities += ["is-located-on", "belongs-to"]
            links["is-located-on"] = _href("components", entity.component)
            links["belongs-to"] = f"{base}/belongs-to"
        if entity.depends_on:
            body["depends-on"] = f"{base}/depends-on"
            capabilities.append("depends-on")
            links["depends-on"] = [_href("apps", d) for d in entity.depends_on]
        x = _app_x(entity, located=True)
    else:
        if entity.depends_on:
            links["depends-on"] = [_href("functions", d) for d in entity.depends_on]
        x = {"source": entity.source} if entity.source else {}
        if entity.hosts:
            x["hosts"] = list(entity.hosts)
        if entity.description:
            x["description"] = entity.description
    body["capabilities"] = _capabilities(entity, capabilities)
    if entity.kind == "components":
        # Components repeat their capabilities in x-medkit, for tools reading only that block.
        x["capabilities"] = body["capabilities"]
    body["_links"] = links
    body["x-medkit"] = x
    return body


# -- relationship sub-collections ----------------------------------------------------------


def relation_body(entities: Entities, entity: Entity, relation: str) -> Body:
    """``GET /{kind}/{id}/{relation}`` for a relation in ``RELATIONS[entity.kind]``."""
    if relation not in RELATIONS[entity.kind]:
        raise ValueError(f"{entity.kind} have no {relation!r} collection")
    own = _href(entity.kind, entity.id)
    links = {"self": f"{own}/{relation}", SINGULAR[entity.kind]: own}
    items: list[Body]
    if (entity.kind, relation) == ("areas", "subareas"):
        items = [_area_item(a, described=False) for a in entities.subareas(entity.id)]
        links = {"self": f"{own}/subareas", "parent": own}
    elif (entity.kind, relation) == ("areas", "components"):
        items = [_component_item(c, described=True) for c in entities.components_in(entity.id)]
        return _collection(items)
    elif (entity.kind, relation) == ("areas", "contains"):
        found = entities.contained_components(entity.id)
        items = [_component_item(c, described=False) for c in found]
        links = {"self": f"{own}/contains", "area": own}
    elif (entity.kind, relation) == ("components", "subcomponents"):
        items = [_component_item(c, described=False) for c in entities.subcomponents(entity.id)]
        links = {"self": f"{own}/subcomponents", "parent": own}
    elif relation == "hosts":
        items = [_app_item(a) for a in _hosted_apps(entities, entity)]
    elif (entity.kind, relation) == ("apps", "is-located-on"):
        items = _located_on(entities, entity)
    elif (entity.kind, relation) == ("apps", "belongs-to"):
        items = _belongs_to(entities, entity)
    else:  # depends-on, of a component or an app
        items = [_dependency(entities, entity.kind, d) for d in entity.depends_on]
    return _collection(items, links)


def _hosted_apps(entities: Entities, entity: Entity) -> tuple[Entity, ...]:
    if entity.kind == "components":
        return entities.apps_on(entity.id)
    # A function's hosts as discovered; a host that is no app (an internal node filtered
    # after grouping) is skipped.
    apps = (entities.get("apps", host) for host in entity.hosts)
    return tuple(app for app in apps if app is not None)


def _located_on(entities: Entities, app: Entity) -> list[Body]:
    if not app.component:
        return []
    component = entities.get("components", app.component)
    if component is not None:
        return [_item(component)]
    item = _item(Entity(kind="components", id=app.component, name=app.component))
    item["x-medkit"] = {"missing": True}
    return [item]


def _belongs_to(entities: Entities, app: Entity) -> list[Body]:
    if not app.component:
        return []
    component = entities.get("components", app.component)
    if component is None:
        x = {"missing": True, "unresolved_component": app.component}
        return [{"id": "", "name": "<unknown area>", "href": "", "type": "area", "x-medkit": x}]
    if not component.area:
        return []
    area = entities.get("areas", component.area)
    item = _item(area or Entity(kind="areas", id=component.area, name=component.area))
    if area is None:
        item["x-medkit"] = {"missing": True}
    return [item]


def _dependency(entities: Entities, kind: Kind, dependency_id: str) -> Body:
    found = entities.get(kind, dependency_id)
    item = _item(found or Entity(kind=kind, id=dependency_id, name=dependency_id))
    if found is None:
        item["x-medkit"] = {"missing": True}
    elif kind == "apps":
        item["x-medkit"] = _app_x(found, node=False)
    else:
        item["x-medkit"] = {"source": found.source} if found.source else {}
    return item
