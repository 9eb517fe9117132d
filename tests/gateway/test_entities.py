"""The entity tree of a runtime-only gateway (505bc2d5), built from node names: ids, the host
component, namespace functions, the internal-node filter, untrusted names, fault scoping."""

from __future__ import annotations

import pytest

from medkit_replay.evidence.graph import NodeGraph
from medkit_replay.gateway.entities import (
    Entities,
    Entity,
    Kind,
    discover,
    sanitize_host_id,
    split_node_name,
    validate_entity_id,
)

ROBOT = (
    "/powertrain/motor_controller",
    "/chassis/motor_controller",
    "/motor_controller",
    "/bt_navigator",
    "/nav/planner/global_planner",
    "/nav/controller",
)


def ids(entities: Entities, kind: Kind) -> list[str]:
    return [e.id for e in entities.list(kind)]


def test_nodes_become_apps_on_one_host_component_and_no_areas() -> None:
    entities = discover(["/bt_navigator", "/nav/controller"], host="Robot-7.local")
    assert entities.list("areas") == ()
    (host,) = entities.list("components")
    assert (host.id, host.name, host.source, host.component_type) == (
        "robot-7_local",
        "Robot-7.local",
        "runtime",
        "Component",
    )
    assert host.description == "Unknown OS on unknown"
    navigator = entities.get("apps", "bt_navigator")
    assert navigator is not None
    assert (navigator.name, navigator.fqn, navigator.namespace) == (
        "bt_navigator",
        "/bt_navigator",
        "/",
    )
    assert (navigator.source, navigator.component) == ("heuristic", "robot-7_local")
    controller = entities.get("apps", "controller")
    assert controller is not None
    assert (controller.fqn, controller.namespace) == ("/nav/controller", "/nav")
    assert entities.apps_on("robot-7_local") == (navigator, controller)


def test_the_host_component_is_named_unknown_without_a_host() -> None:
    (host,) = discover([]).list("components")
    assert (host.id, host.name) == ("unknown", "unknown")
    assert discover([]).list("apps") == ()


def test_a_bare_name_in_several_namespaces_is_qualified_outside_the_root() -> None:
    entities = discover(ROBOT)
    assert ids(entities, "apps") == [
        "bt_navigator",
        "motor_controller",
        "chassis_motor_controller",
        "controller",
        "global_planner",
        "powertrain_motor_controller",
    ]
    nested = discover(["/a/b/node", "/c/node"])
    assert ids(nested, "apps") == ["a_b_node", "c_node"]
    app = nested.get("apps", "a_b_node")
    assert app is not None
    assert app.name == "node"


def test_functions_group_apps_by_first_namespace_segment_root_for_slash() -> None:
    entities = discover(ROBOT)
    functions = {f.id: f.hosts for f in entities.list("functions")}
    assert list(functions) == ["chassis", "nav", "powertrain", "root"]
    assert functions["nav"] == ("controller", "global_planner")
    assert functions["root"] == ("bt_navigator", "motor_controller")
    assert functions["powertrain"] == ("powertrain_motor_controller",)
    root = entities.get("functions", "root")
    assert root is not None
    assert (root.name, root.source) == ("root", "runtime")
    # a top-level namespace called root joins the root function, as upstream's map key does
    merged = discover(["/root/x", "/y"])
    assert [(f.id, f.hosts) for f in merged.list("functions")] == [("root", ("y", "x"))]


def test_internal_nodes_leave_the_apps_but_stay_listed_as_function_hosts() -> None:
    entities = discover(["/_param_client_node", "/tools/_hidden", "/teleop"])
    assert ids(entities, "apps") == ["teleop"]
    functions = {f.id: f.hosts for f in entities.list("functions")}
    assert functions == {"root": ("_param_client_node", "teleop"), "tools": ("_hidden",)}
    tools = entities.get("functions", "tools")
    assert tools is not None
    assert entities.fault_sources(tools) == frozenset()
    # the filter reads the app id: a qualified id no longer starts with "_"
    assert ids(discover(["/a/_x", "/b/_x"]), "apps") == ["a__x", "b__x"]


def test_graph_nodes_join_the_recorded_names() -> None:
    graph = NodeGraph(
        publishes={"/lidar_driver": frozenset({"/scan"})},
        subscribes={"/slam/mapper": frozenset({"/scan"}), "/lidar_driver": frozenset()},
    )
    entities = discover(["/bt_navigator"], graph)
    assert ids(entities, "apps") == ["bt_navigator", "lidar_driver", "mapper"]
    twice = discover(["/bt_navigator", "/bt_navigator"], NodeGraph())
    assert ids(twice, "apps") == ["bt_navigator"]


@pytest.mark.parametrize(
    "name",
    [
        "",
        "/",
        "motor_controller",  # not absolute
        "DIAG_HW_ID",
        "/ns/",
        "/ns//node",
        "//node",
        "/1node",
        "/ns/9node",
        "/9ns/node",
        "/ns/nöde",
        "/ns/no de",
        "/ns/node-1",
        "/ns/node\x00",
        "/ns/node/",
        "/" + "n" * 256,  # node name over 255
        "/" + "s" * 245 + "/node",  # namespace over 245
        "<script>alert(1)</script>",
        "/../etc/passwd",
    ],
)
def test_text_that_is_no_node_name_makes_no_app(name: str) -> None:
    entities = discover([name, "/teleop"])
    assert ids(entities, "apps") == ["teleop"]
    (host,) = entities.list("components")
    assert entities.fault_sources(host) == frozenset({"/teleop"})
    assert split_node_name(name) is None


def test_the_longest_valid_names_are_apps_and_ids_stay_addressable() -> None:
    node = "n" * 255
    namespace = "/" + "s" * 244
    assert split_node_name("/" + node) == ("/", node)
    assert split_node_name(namespace + "/x") == (namespace, "x")
    # Two namespaces share the bare name: the qualified id would pass 256 bytes, which no
    # route accepts, so that app is left out; the short one stays.
    short = "n" * 250
    entities = discover([f"{namespace}/{short}", f"/a/{short}", f"/b/{node}", f"/c/{node}"])
    assert ids(entities, "apps") == [f"a_{short}"]
    for app in entities.list("apps"):
        assert validate_entity_id(app.id) is None
    for function in entities.list("functions"):
        assert validate_entity_id(function.id) is None


def test_discovery_does_not_depend_on_the_order_names_come_in() -> None:
    forward = discover(ROBOT)
    backward = discover(reversed(ROBOT))
    for kind in ("components", "apps", "functions"):
        assert forward.list(kind) == backward.list(kind)


def test_fault_sources_of_apps_components_and_functions() -> None:
    entities = discover([*ROBOT, "/_daemon"])
    app = entities.get("apps", "chassis_motor_controller")
    assert app is not None
    assert entities.fault_sources(app) == frozenset({"/chassis/motor_controller"})
    (host,) = entities.list("components")
    assert entities.fault_sources(host) == frozenset(ROBOT)
    nav = entities.get("functions", "nav")
    assert nav is not None
    assert entities.fault_sources(nav) == frozenset(
        {"/nav/controller", "/nav/planner/global_planner"}
    )
    root = entities.get("functions", "root")
    assert root is not None
    assert entities.fault_sources(root) == frozenset({"/bt_navigator", "/motor_controller"})


def area_tree() -> Entities:
    """A tree with areas, sub-areas and a function hosting a component, which runtime discovery
    never makes but the scoping rules cover."""
    return Entities(
        [
            Entity(kind="areas", id="vehicle", name="Vehicle"),
            Entity(kind="areas", id="engine", name="", parent="vehicle"),
            Entity(kind="areas", id="cabin", name="Cabin", parent="vehicle"),
            Entity(kind="components", id="ecu", name="ECU", area="engine"),
            Entity(kind="components", id="hvac", name="HVAC", area="cabin"),
            Entity(kind="components", id="body", name="Body", area="vehicle"),
            Entity(kind="apps", id="inj", name="inj", fqn="/engine/inj", component="ecu"),
            Entity(kind="apps", id="fan", name="fan", fqn="/cabin/fan", component="hvac"),
            Entity(kind="apps", id="lock", name="lock", fqn="/body/lock", component="body"),
            Entity(kind="apps", id="loose", name="loose", fqn=""),
            Entity(kind="functions", id="comfort", name="Comfort", hosts=("hvac", "lock", "x")),
        ]
    )


def test_fault_sources_of_an_area_cover_its_descendants() -> None:
    tree = area_tree()
    vehicle = tree.get("areas", "vehicle")
    engine = tree.get("areas", "engine")
    comfort = tree.get("functions", "comfort")
    loose = tree.get("apps", "loose")
    assert vehicle is not None
    assert engine is not None
    assert comfort is not None
    assert loose is not None
    assert tree.fault_sources(vehicle) == frozenset({"/engine/inj", "/cabin/fan", "/body/lock"})
    assert tree.fault_sources(engine) == frozenset({"/engine/inj"})
    assert tree.fault_sources(comfort) == frozenset({"/cabin/fan", "/body/lock"})
    assert tree.fault_sources(loose) == frozenset()
    assert [c.id for c in tree.contained_components("vehicle")] == ["body", "hvac", "ecu"]
    assert [a.id for a in tree.subareas("vehicle")] == ["engine", "cabin"]


def test_a_repeated_id_keeps_its_first_place_and_its_last_fields() -> None:
    entities = Entities(
        [
            Entity(kind="apps", id="a", name="first"),
            Entity(kind="apps", id="b", name="b"),
            Entity(kind="apps", id="a", name="second"),
        ]
    )
    assert [(e.id, e.name) for e in entities.list("apps")] == [("a", "second"), ("b", "b")]


def test_kind_of_searches_components_apps_areas_functions() -> None:
    entities = Entities(
        [
            Entity(kind="functions", id="x", name="x"),
            Entity(kind="areas", id="x", name="x"),
            Entity(kind="apps", id="y", name="y"),
            Entity(kind="functions", id="y", name="y"),
        ]
    )
    assert entities.kind_of("x") == "areas"
    assert entities.kind_of("y") == "apps"
    assert entities.kind_of("z") is None


@pytest.mark.parametrize(
    ("entity_id", "problem"),
    [
        ("", "Entity ID cannot be empty"),
        ("a" * 257, "Entity ID too long (max 256 characters)"),
        ("é" * 129, "Entity ID too long (max 256 characters)"),  # 258 bytes
        ("a/b", "'/'"),
        ("a.b", "'.'"),
        ("a b", "' '"),
        ("a\x01", "'0x01'"),
        ("é", "'0xc3'"),
        ("..", "'.'"),
    ],
)
def test_ids_a_route_refuses(entity_id: str, problem: str) -> None:
    found = validate_entity_id(entity_id)
    assert found is not None
    assert problem in found
    if problem.startswith("'"):
        assert found == (
            f"Entity ID contains invalid character: {problem}. "
            "Only alphanumeric, underscore and hyphen are allowed"
        )


@pytest.mark.parametrize("entity_id", ["a", "A-b_9", "x" * 256, "_internal", "-"])
def test_ids_a_route_accepts(entity_id: str) -> None:
    assert validate_entity_id(entity_id) is None


@pytest.mark.parametrize(
    ("host", "expected"),
    [
        ("Robot-1.local", "robot-1_local"),
        ("my robot", "my_robot"),
        ("rob@t#1", "robt1"),
        ("!!!", "unknown_host"),
        ("ü", "unknown_host"),
        ("h" * 300, "h" * 256),
    ],
)
def test_host_names_as_component_ids(host: str, expected: str) -> None:
    assert sanitize_host_id(host) == expected
    assert validate_entity_id(sanitize_host_id(host)) is None
