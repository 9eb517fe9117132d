"""The server and discovery bodies as the 505bc2d5 handlers build them: root, version-info,
health, entity lists, details, relationship collections, and the lookups' refusals."""

from __future__ import annotations

import re
from typing import TYPE_CHECKING, Any

import pytest

from medkit_replay.gateway.discovery_json import (
    RELATIONS,
    SERVED_ROUTES,
    detail_body,
    health_body,
    list_body,
    relation_body,
    relation_owner,
    root_body,
    route_entity,
    version_info_body,
)
from medkit_replay.gateway.entities import Entities, Entity, discover
from medkit_replay.gateway.errors import GatewayError
from medkit_replay.version import __version__

if TYPE_CHECKING:
    from collections.abc import Callable

NODES = ("/bt_navigator", "/nav/controller", "/nav/planner", "/_daemon")


def robot() -> Entities:
    return discover(NODES, host="robot-1")


def entity(entities: Entities, kind: str, entity_id: str) -> Entity:
    found = entities.get(kind, entity_id)  # type: ignore[arg-type]
    assert found is not None
    return found


def test_root_lists_the_served_get_routes_and_what_a_recording_can_do() -> None:
    body = root_body()
    assert (body["name"], body["version"], body["api_base"]) == (
        "medkit-replay",
        __version__,
        "/api/v1",
    )
    endpoints = body["endpoints"]
    assert isinstance(endpoints, list)
    assert endpoints[:4] == [
        "GET /api/v1/health",
        "GET /api/v1/",
        "GET /api/v1/version-info",
        "GET /api/v1/areas",
    ]
    assert endpoints[-2:] == ["GET /api/v1/faults/stream", "GET /api/v1/faults"]
    assert "GET /api/v1/apps/{app_id}/faults/{fault_code}" in endpoints
    assert "GET /api/v1/functions/{function_id}/hosts" in endpoints
    assert "GET /api/v1/components/{component_id}/bulk-data/{category_id}/{file_id}" in endpoints
    assert not [e for e in endpoints if re.search(r"/(data|operations|configurations|logs)", e)]
    assert len(endpoints) == len(set(endpoints)) == len(SERVED_ROUTES)
    capabilities = body["capabilities"]
    assert isinstance(capabilities, dict)
    assert sorted(k for k, v in capabilities.items() if v) == ["bulk_data", "discovery", "faults"]
    published = (
        "async_actions authentication bulk_data configurations cyclic_subscriptions data_access "
        "discovery faults locking logs operations scripts tls triggers updates vendor_extensions"
    )
    assert set(published.split()) <= set(capabilities)
    assert root_body(["/x"])["endpoints"] == ["GET /api/v1/x"]


def test_version_info_names_medkit_replay_in_the_published_shape() -> None:
    assert version_info_body() == {
        "items": [
            {
                "version": "1.0.0",
                "base_uri": "/api/v1",
                "vendor_info": {"version": __version__, "name": "medkit-replay"},
            }
        ]
    }


def test_health_of_a_runtime_only_gateway() -> None:
    assert health_body(1_700_000_000_123_456_789) == {
        "status": "healthy",
        "timestamp": 1_700_000_000_123_456_789,
        "discovery": {"mode": "runtime_only", "strategy": "runtime"},
        "warning_schema_version": 2,
        "warnings": [],
    }


def test_entity_lists() -> None:
    entities = robot()
    assert list_body(entities, "areas") == {"items": [], "x-medkit": {"total_count": 0}}
    assert list_body(entities, "components") == {
        "items": [
            {
                "id": "robot-1",
                "name": "robot-1",
                "href": "/api/v1/components/robot-1",
                "type": "component",
                "description": "Unknown OS on unknown",
                "x-medkit": {"source": "runtime"},
            }
        ],
        "x-medkit": {"total_count": 1},
    }
    apps = list_body(entities, "apps")
    assert apps["x-medkit"] == {"total_count": 3}
    assert apps["items"] == [
        {
            "id": node.rsplit("/", 1)[1],
            "name": node.rsplit("/", 1)[1],
            "href": f"/api/v1/apps/{node.rsplit('/', 1)[1]}",
            "type": "app",
            "x-medkit": {
                "ros2": {"node": node},
                "source": "heuristic",
                "is_online": True,
                "component_id": "robot-1",
            },
        }
        for node in ("/bt_navigator", "/nav/controller", "/nav/planner")
    ]
    assert list_body(entities, "functions") == {
        "items": [
            {
                "id": fid,
                "name": fid,
                "href": f"/api/v1/functions/{fid}",
                "type": "function",
                "x-medkit": {"source": "runtime"},
            }
            for fid in ("nav", "root")
        ],
        "x-medkit": {"total_count": 2},
    }


def test_lists_leave_sub_areas_and_sub_components_to_their_parents() -> None:
    entities = Entities(
        [
            Entity(kind="areas", id="vehicle", name="Vehicle", namespace="/vehicle"),
            Entity(kind="areas", id="engine", name="", parent="vehicle"),
            Entity(kind="components", id="ecu", name="ECU", fqn="/ecu", namespace="/e"),
            Entity(kind="components", id="sensor", name="", parent="ecu"),
        ]
    )
    assert list_body(entities, "areas")["items"] == [
        {
            "id": "vehicle",
            "name": "Vehicle",
            "href": "/api/v1/areas/vehicle",
            "type": "area",
            "x-medkit": {"ros2": {"namespace": "/vehicle"}},
        }
    ]
    assert list_body(entities, "components")["items"] == [
        {
            "id": "ecu",
            "name": "ECU",
            "href": "/api/v1/components/ecu",
            "type": "component",
            "x-medkit": {"ros2": {"node": "/ecu", "namespace": "/e"}},
        }
    ]


def test_app_detail() -> None:
    entities = robot()
    body = detail_body(entities, entity(entities, "apps", "controller"))
    base = "/api/v1/apps/controller"
    assert body == {
        "id": "controller",
        "name": "controller",
        "type": "app",
        "status": f"{base}/status",
        "data": f"{base}/data",
        "operations": f"{base}/operations",
        "configurations": f"{base}/configurations",
        "faults": f"{base}/faults",
        "logs": f"{base}/logs",
        "bulk-data": f"{base}/bulk-data",
        "cyclic-subscriptions": f"{base}/cyclic-subscriptions",
        "triggers": f"{base}/triggers",
        "is-located-on": "/api/v1/components/robot-1",
        "belongs-to": f"{base}/belongs-to",
        "capabilities": [
            {"name": "faults", "href": f"{base}/faults"},
            {"name": "bulk-data", "href": f"{base}/bulk-data"},
            {"name": "is-located-on", "href": f"{base}/is-located-on"},
            {"name": "belongs-to", "href": f"{base}/belongs-to"},
        ],
        "_links": {
            "self": base,
            "collection": "/api/v1/apps",
            "is-located-on": "/api/v1/components/robot-1",
            "belongs-to": f"{base}/belongs-to",
        },
        "x-medkit": {
            "ros2": {"node": "/nav/controller"},
            "source": "heuristic",
            "is_online": True,
            "component_id": "robot-1",
        },
    }


def test_component_detail_repeats_its_capabilities_in_x_medkit() -> None:
    entities = robot()
    body = detail_body(entities, entity(entities, "components", "robot-1"))
    base = "/api/v1/components/robot-1"
    uris = {key: value for key, value in body.items() if value == f"{base}/{key}"}
    assert list(uris) == [
        "status",
        "data",
        "operations",
        "configurations",
        "faults",
        "subcomponents",
        "hosts",
        "logs",
        "bulk-data",
        "cyclic-subscriptions",
        "triggers",
    ]
    capabilities = [
        {"name": name, "href": f"{base}/{name}"}
        for name in ("faults", "subcomponents", "hosts", "bulk-data")
    ]
    assert body == {
        "id": "robot-1",
        "name": "robot-1",
        "type": "component",
        "description": "Unknown OS on unknown",
        **uris,
        "capabilities": capabilities,
        "_links": {"self": base, "collection": "/api/v1/components"},
        "x-medkit": {
            "source": "runtime",
            "type": "Component",
            "description": "Unknown OS on unknown",
            "capabilities": capabilities,
        },
    }


def test_function_detail_shows_its_hosts_as_discovered() -> None:
    entities = robot()
    body = detail_body(entities, entity(entities, "functions", "root"))
    base = "/api/v1/functions/root"
    assert body["x-medkit"] == {"source": "runtime", "hosts": ["_daemon", "bt_navigator"]}
    assert body["x-medkit-graph"] == f"{base}/x-medkit-graph"
    assert body["hosts"] == f"{base}/hosts"
    assert body["capabilities"] == [
        {"name": n, "href": f"{base}/{n}"} for n in ("hosts", "faults", "bulk-data")
    ]
    assert body["_links"] == {"self": base, "collection": "/api/v1/functions"}


def tree() -> Entities:
    return Entities(
        [
            Entity(kind="areas", id="vehicle", name="Vehicle", namespace="/vehicle"),
            Entity(kind="areas", id="engine", name="", parent="vehicle", namespace="/engine"),
            Entity(kind="components", id="ecu", name="ECU", area="engine", namespace="/e"),
            Entity(kind="components", id="body", name="", area="vehicle", description="B"),
            Entity(kind="components", id="door", name="Door", parent="body", depends_on=("ecu",)),
            Entity(kind="components", id="lamp", name="Lamp", area="gone", depends_on=("ecu", "x")),
            Entity(kind="apps", id="inj", name="inj", fqn="/e/inj", component="ecu"),
            Entity(kind="apps", id="orphan", name="orphan", component="nowhere"),
            Entity(kind="apps", id="lit", name="lit", component="lamp", depends_on=("inj", "y")),
            Entity(kind="functions", id="drive", name="", hosts=("inj", "ecu"), description="D"),
        ]
    )


def test_area_detail_and_its_collections() -> None:
    entities = tree()
    engine = entity(entities, "areas", "engine")
    body = detail_body(entities, engine)
    base = "/api/v1/areas/engine"
    assert body["name"] == "engine"
    assert body["subareas"] == f"{base}/subareas"
    assert body["components"] == f"{base}/components"
    assert [c["name"] for c in body["capabilities"]] == [  # type: ignore[attr-defined]
        "subareas",
        "contains",
        "faults",
        "bulk-data",
    ]
    assert body["_links"] == {
        "self": base,
        "collection": "/api/v1/areas",
        "parent": "/api/v1/areas/vehicle",
    }
    assert body["x-medkit"] == {"ros2": {"namespace": "/engine"}, "parent_area_id": "vehicle"}
    vehicle = entity(entities, "areas", "vehicle")
    assert relation_body(entities, vehicle, "subareas") == {
        "items": [
            {
                "id": "engine",
                "name": "engine",
                "href": base,
                "type": "area",
                "x-medkit": {"ros2": {"namespace": "/engine"}},
            }
        ],
        "x-medkit": {"total_count": 1},
        "_links": {
            "self": "/api/v1/areas/vehicle/subareas",
            "parent": "/api/v1/areas/vehicle",
        },
    }
    # area components: own components only, with descriptions, and no _links
    assert relation_body(entities, vehicle, "components") == {
        "items": [
            {
                "id": "body",
                "name": "body",
                "href": "/api/v1/components/body",
                "type": "component",
                "description": "B",
                "x-medkit": {},
            }
        ],
        "x-medkit": {"total_count": 1},
    }
    contains = relation_body(entities, vehicle, "contains")
    assert [i["id"] for i in contains["items"]] == ["body", "ecu"]  # type: ignore[attr-defined]
    assert contains["items"][1] == {  # type: ignore[index]
        "id": "ecu",
        "name": "ECU",
        "href": "/api/v1/components/ecu",
        "type": "component",
        "x-medkit": {"ros2": {"namespace": "/e"}},
    }
    assert contains["_links"] == {
        "self": "/api/v1/areas/vehicle/contains",
        "area": "/api/v1/areas/vehicle",
    }


def test_component_collections() -> None:
    entities = tree()
    body = entity(entities, "components", "body")
    assert relation_body(entities, body, "subcomponents")["items"] == [
        {
            "id": "door",
            "name": "Door",
            "href": "/api/v1/components/door",
            "type": "component",
            "x-medkit": {},
        }
    ]
    ecu = entity(entities, "components", "ecu")
    hosts = relation_body(entities, ecu, "hosts")
    assert hosts == {
        "items": [
            {
                "id": "inj",
                "name": "inj",
                "href": "/api/v1/apps/inj",
                "type": "app",
                "x-medkit": {"ros2": {"node": "/e/inj"}, "is_online": True},
            }
        ],
        "x-medkit": {"total_count": 1},
        "_links": {
            "self": "/api/v1/components/ecu/hosts",
            "component": "/api/v1/components/ecu",
        },
    }
    lamp = entity(entities, "components", "lamp")
    assert relation_body(entities, lamp, "depends-on")["items"] == [
        {"id": "ecu", "name": "ECU", "href": "/api/v1/components/ecu", "type": "component"}
        | {"x-medkit": {}},
        {
            "id": "x",
            "name": "x",
            "href": "/api/v1/components/x",
            "type": "component",
            "x-medkit": {"missing": True},
        },
    ]
    detail = detail_body(entities, lamp)
    assert detail["depends-on"] == "/api/v1/components/lamp/depends-on"
    assert detail["belongs-to"] == "/api/v1/areas/gone"
    assert detail["_links"] == {
        "self": "/api/v1/components/lamp",
        "collection": "/api/v1/components",
        "area": "/api/v1/areas/gone",
    }
    assert detail["x-medkit"]["dependsOn"] == ["ecu", "x"]  # type: ignore[index]
    assert detail["x-medkit"]["area"] == "gone"  # type: ignore[index]


def test_app_collections_and_broken_references() -> None:
    entities = tree()
    inj = entity(entities, "apps", "inj")
    assert relation_body(entities, inj, "is-located-on") == {
        "items": [
            {"id": "ecu", "name": "ECU", "href": "/api/v1/components/ecu", "type": "component"}
        ],
        "x-medkit": {"total_count": 1},
        "_links": {"self": "/api/v1/apps/inj/is-located-on", "app": "/api/v1/apps/inj"},
    }
    assert relation_body(entities, inj, "belongs-to")["items"] == [
        {"id": "engine", "name": "engine", "href": "/api/v1/areas/engine", "type": "area"}
    ]
    orphan = entity(entities, "apps", "orphan")
    assert relation_body(entities, orphan, "is-located-on")["items"] == [
        {
            "id": "nowhere",
            "name": "nowhere",
            "href": "/api/v1/components/nowhere",
            "type": "component",
            "x-medkit": {"missing": True},
        }
    ]
    assert relation_body(entities, orphan, "belongs-to")["items"] == [
        {
            "id": "",
            "name": "<unknown area>",
            "href": "",
            "type": "area",
            "x-medkit": {"missing": True, "unresolved_component": "nowhere"},
        }
    ]
    lit = entity(entities, "apps", "lit")
    assert relation_body(entities, lit, "belongs-to")["items"] == [
        {
            "id": "gone",
            "name": "gone",
            "href": "/api/v1/areas/gone",
            "type": "area",
            "x-medkit": {"missing": True},
        }
    ]
    assert relation_body(entities, lit, "depends-on")["items"] == [
        {
            "id": "inj",
            "name": "inj",
            "href": "/api/v1/apps/inj",
            "type": "app",
            "x-medkit": {"is_online": True},
        },
        {
            "id": "y",
            "name": "y",
            "href": "/api/v1/apps/y",
            "type": "app",
            "x-medkit": {"missing": True},
        },
    ]
    detail = detail_body(entities, lit)
    assert detail["_links"]["depends-on"] == [  # type: ignore[index]
        "/api/v1/apps/inj",
        "/api/v1/apps/y",
    ]
    assert [c["name"] for c in detail["capabilities"]] == [  # type: ignore[attr-defined]
        "faults",
        "bulk-data",
        "is-located-on",
        "belongs-to",
        "depends-on",
    ]


def test_runtime_apps_belong_to_no_area_and_depend_on_nothing() -> None:
    entities = robot()
    app = entity(entities, "apps", "planner")
    assert relation_body(entities, app, "belongs-to")["items"] == []
    assert relation_body(entities, app, "depends-on")["items"] == []
    assert relation_body(entities, app, "is-located-on")["x-medkit"] == {"total_count": 1}


def test_function_hosts_skip_hosts_that_are_no_app() -> None:
    entities = robot()
    root = entity(entities, "functions", "root")
    body = relation_body(entities, root, "hosts")
    assert [i["id"] for i in body["items"]] == ["bt_navigator"]  # type: ignore[attr-defined]
    assert body["_links"] == {
        "self": "/api/v1/functions/root/hosts",
        "function": "/api/v1/functions/root",
    }
    drive = entity(tree(), "functions", "drive")
    detail = detail_body(tree(), drive)
    assert detail["name"] == "drive"
    assert detail["description"] == "D"
    assert detail["x-medkit"] == {"hosts": ["inj", "ecu"], "description": "D"}


def test_an_unknown_relation_is_a_programming_error() -> None:
    entities = robot()
    with pytest.raises(ValueError, match="apps have no 'hosts' collection"):
        relation_body(entities, entity(entities, "apps", "planner"), "hosts")


def test_every_advertised_capability_is_a_served_route() -> None:
    templates = [re.sub(r"\{[a-z_]+\}", "[^/]+", route) for route in SERVED_ROUTES]
    for entities in (robot(), tree()):
        for kind in RELATIONS:
            for found in entities.list(kind):
                body = detail_body(entities, found)
                for capability in body["capabilities"]:  # type: ignore[attr-defined]
                    path = capability["href"].removeprefix("/api/v1")
                    assert any(re.fullmatch(t, path) for t in templates), path


def refused(look: Callable[..., object], *args: Any) -> tuple[object, ...]:
    with pytest.raises(GatewayError) as caught:
        look(*args)
    err = caught.value
    return (err.status, err.error_code, err.message, err.parameters)


def test_routes_refuse_bad_ids_other_kinds_and_unknown_entities() -> None:
    entities = robot()
    assert route_entity(entities, "apps", "planner") == entity(entities, "apps", "planner")
    assert refused(route_entity, entities, "apps", "a/b") == (
        400,
        "invalid-parameter",
        "Invalid entity ID",
        {
            "details": "Entity ID contains invalid character: '/'. "
            "Only alphanumeric, underscore and hyphen are allowed",
            "entity_id": "a/b",
        },
    )
    assert refused(route_entity, entities, "functions", "robot-1") == (
        400,
        "invalid-parameter",
        "Invalid entity type for route: expected Function, got Component",
        {"entity_id": "robot-1", "expected_type": "Function", "actual_type": "Component"},
    )
    assert refused(route_entity, entities, "areas", "nav") == (
        400,
        "invalid-parameter",
        "Invalid entity type for route: expected Area, got Function",
        {"entity_id": "nav", "expected_type": "Area", "actual_type": "Function"},
    )
    assert refused(route_entity, entities, "apps", "ghost") == (
        404,
        "entity-not-found",
        "Entity not found",
        {"entity_id": "ghost"},
    )
    # an internal node is not an app, whatever a function's hosts say
    assert refused(route_entity, entities, "apps", "_daemon") == (
        404,
        "entity-not-found",
        "Entity not found",
        {"entity_id": "_daemon"},
    )


def test_relationship_owners_are_looked_up_as_each_handler_does() -> None:
    entities = robot()
    assert refused(relation_owner, entities, "areas", "") == (
        400,
        "invalid-parameter",
        "Invalid area ID",
        {"details": "Entity ID cannot be empty", "area_id": ""},
    )
    # no wrong-kind check here: a function id under /components is simply not found
    assert refused(relation_owner, entities, "components", "nav") == (
        404,
        "entity-not-found",
        "Component not found",
        {"component_id": "nav"},
    )
    assert refused(relation_owner, entities, "functions", "ghost") == (
        404,
        "entity-not-found",
        "Function not found",
        {"function_id": "ghost"},
    )
    assert relation_owner(entities, "functions", "nav") == entity(entities, "functions", "nav")
    # apps validate as their detail route does
    assert refused(relation_owner, entities, "apps", "nav") == refused(
        route_entity, entities, "apps", "nav"
    )
