"""A file of another kind given as --config says which kind it looks like and where it belongs;
guess_kind tells each kind of input from its top-level shape."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from medkit_replay.cli import main
from medkit_replay.config.kinds import KINDS, WHERE, guess_kind, guess_text_kind
from medkit_replay.config.params import load_parameters
from medkit_replay.errors import ConfigError

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "nav2_mission.jsonl"

SHAPES = {
    "parameters": "/robot1/fault_manager:\n  ros__parameters:\n    healing_enabled: true\n",
    "correlation": "correlation:\n  enabled: true\n  rules: []\n",
    "entity_thresholds": "/motor:\n  confirmation_threshold: 0\n/lidar:\n  healing_threshold: 1\n",
    "snapshots": "fault_specific:\n  MOTOR_OVERHEAT: [/motor/temp]\ndefault_topics: [/odom]\n",
    "budget": "version: 1\nname: ci\nrules:\n  - {name: n, max_confirmed: {ERROR: 0}}\n",
    "graph": "/driver:\n  publishers: [/odom]\n  subscribers: [/cmd_vel]\n",
}

SHIPPED = {
    "rules/nav2/fault_manager.yaml": "parameters",
    "rules/nav2/bridges.yaml": "parameters",
    "rules/nav2/correlation.yaml": "correlation",
    "rules/nav2/entity_thresholds.yaml": "entity_thresholds",
    "rules/budgets/nav2_mission_pass.yaml": "budget",
    "rules/budgets/nav2_mission_fail.yaml": "budget",
    "examples/evidence/nav2_graph.txt": "graph",
    "examples/evidence/capture.yaml": "parameters",
}


@pytest.mark.parametrize(("kind", "text"), SHAPES.items())
def test_each_kind_is_told_from_its_shape(kind: str, text: str) -> None:
    assert guess_kind(yaml.safe_load(text)) == kind
    assert guess_text_kind(text, "x.yaml") == kind


@pytest.mark.parametrize(
    ("text", "kind"),
    [
        ("version: 1\nrulez:\n  - max_confirmed: {ERROR: 0}\n", "budget"),
        ("rules: []\ntitle: typo of name\n", "budget"),
        ("default_topic: [/odom]\nfault_specific: {}\n", "snapshots"),
    ],
)
def test_one_known_key_is_enough_beside_a_typo(text: str, kind: str) -> None:
    """A misspelt key must not hide the file's kind: its reader then names the typo."""
    assert guess_kind(yaml.safe_load(text)) == kind


def test_a_name_alone_does_not_make_a_budget() -> None:
    """``name:`` is a budget key, but many files could have one: it tells no kind."""
    assert guess_kind({"name": "ci"}) is None


@pytest.mark.parametrize(("name", "kind"), SHIPPED.items())
def test_the_shipped_files_are_told_apart(name: str, kind: str) -> None:
    assert guess_text_kind((ROOT / name).read_text(), name) == kind


@pytest.mark.parametrize(
    "text",
    ["", "- a\n- b\n", "just text\n", "a: 1\nb: 2\n", "{unclosed: [\n", "/x:\n  talks: [/y]\n"],
)
def test_a_file_of_no_kind_is_none(text: str) -> None:
    assert guess_text_kind(text, "x.yaml") is None


def test_every_kind_has_a_place() -> None:
    assert set(WHERE) == set(KINDS) == set(SHAPES)


@pytest.mark.parametrize(
    ("kind", "belongs"),
    [
        ("correlation", "fault_manager's correlation.config_file"),
        ("entity_thresholds", "fault_manager's entity_thresholds.config_file"),
        ("snapshots", "fault_manager's snapshots.config_file"),
        ("budget", "--budget"),
        ("graph", "--graph"),
    ],
)
def test_a_wrong_kind_given_as_config_says_where_it_belongs(
    tmp_path: Path, kind: str, belongs: str
) -> None:
    path = tmp_path / "given.yaml"
    path.write_text(SHAPES[kind])
    with pytest.raises(ConfigError) as raised:
        load_parameters([path])
    message = str(raised.value)
    assert message.startswith(f"{path}:")
    assert f"it belongs in {belongs}" in message
    assert message.endswith("expected a node name holding ros__parameters)")


def test_node_info_text_given_as_config_is_a_graph(tmp_path: Path) -> None:
    path = tmp_path / "graph.txt"
    path.write_text((ROOT / "examples" / "evidence" / "nav2_graph.txt").read_text())
    with pytest.raises(ConfigError, match=r"looks like a node graph: it belongs in --graph"):
        load_parameters([path])


def test_a_file_of_no_kind_keeps_the_plain_message(tmp_path: Path) -> None:
    path = tmp_path / "odd.yaml"
    path.write_text("a: 1\n")
    with pytest.raises(ConfigError) as raised:
        load_parameters([path])
    assert str(raised.value) == f"{path}:1: a: expected a node name holding ros__parameters"


def test_the_command_line_says_it_in_one_line_and_exits_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    budget = ROOT / "rules" / "budgets" / "nav2_mission_pass.yaml"
    assert main(["analyze", str(EXAMPLE), "--config", str(budget), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "looks like a fault budget: it belongs in --budget" in err
