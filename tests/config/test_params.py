"""ROS 2 parameter files: node keys, nesting, typing, merging, and errors with file:line."""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

from medkit_replay.config.fault_manager import fault_manager_config
from medkit_replay.config.params import load_parameters
from medkit_replay.errors import ConfigError

if TYPE_CHECKING:
    from pathlib import Path


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_nested_and_dotted_names_are_the_same_parameter(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        "a.yaml",
        """
fault_manager:
  ros__parameters:
    correlation: {cleanup_interval_sec: 2.0}
    near_miss.max_per_fault: 7
""",
    )
    params = load_parameters([path]).node("fault_manager")
    assert params["correlation.cleanup_interval_sec"].value == 2.0
    assert params["near_miss.max_per_fault"].value == 7
    assert params["near_miss.max_per_fault"].line == 5


def test_namespaced_and_wildcard_keys_apply_and_later_files_override(tmp_path: Path) -> None:
    first = write(
        tmp_path,
        "a.yaml",
        """
/**:
  ros__parameters: {healing_enabled: true}
/robot1/fault_manager:
  ros__parameters: {confirmation_threshold: -2, healing_threshold: 5}
robot1:
  diagnostic_bridge:
    ros__parameters: {auto_generate_codes: false}
""",
    )
    second = write(
        tmp_path,
        "b.yaml",
        """
fault_manager:
  ros__parameters: {healing_threshold: 1}
""",
    )
    params = load_parameters([first, second])
    fm = params.node("fault_manager")
    assert fm["healing_enabled"].value is True
    assert fm["confirmation_threshold"].value == -2
    assert fm["healing_threshold"].value == 1
    assert params.node("diagnostic_bridge")["auto_generate_codes"].value is False
    assert params.mentions("fault_manager") and not params.mentions("log_bridge")


def test_values_are_typed_as_ros2_types_them(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        "a.yaml",
        """
medkit_replay:
  ros__parameters:
    b: yes
    i: -3
    d: 1e3
    s: "5"
    l: [a, b]
""",
    )
    params = load_parameters([path]).node("medkit_replay")
    assert [params[k].value for k in "bidsl"] == [True, -3, 1000.0, "5", ["a", "b"]]


def test_upstream_sanitising_with_warnings(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        "a.yaml",
        """
fault_manager:
  ros__parameters:
    confirmation_threshold: 3
    healing_threshold: -2
    auto_confirm_after_sec: -1.0
    near_miss: {max_per_fault: -5}
""",
    )
    config, warnings = fault_manager_config(load_parameters([path]).node("fault_manager"))
    assert config.debounce.confirmation_threshold == -3
    assert config.debounce.healing_threshold == 2
    assert config.auto_confirm_after_ns == 0
    assert config.near_miss_bound == 200
    assert len(warnings) == 4


def test_defaults_without_config() -> None:
    config, warnings = fault_manager_config({})
    assert (
        config.debounce.confirmation_threshold,
        config.debounce.healing_enabled,
        config.debounce.healing_threshold,
    ) == (-1, False, 3)
    assert config.auto_confirm_after_ns == 0 and config.correlation is None
    assert warnings == []


@pytest.mark.parametrize(
    ("body", "line", "problem"),
    [
        ("    confirmation_threshold: -1.5\n", 4, "'confirmation_threshold' must be an integer"),
        ("    auto_confirm_after_sec: 10\n", 4, "write 10.0"),
        ("    healing_enabled: 1\n", 4, "'healing_enabled' must be a bool"),
    ],
)
def test_wrong_type_is_refused_as_the_node_would(
    tmp_path: Path, body: str, line: int, problem: str
) -> None:
    path = write(tmp_path, "a.yaml", "\nfault_manager:\n  ros__parameters:\n" + body)
    with pytest.raises(ConfigError) as info:
        fault_manager_config(load_parameters([path]).node("fault_manager"))
    assert info.value.path == str(path) and info.value.line == line
    assert problem in info.value.problem


def test_missing_and_invalid_files(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="config file not found"):
        load_parameters([tmp_path / "nope.yaml"])
    bad = write(tmp_path, "bad.yaml", "fault_manager:\n  ros__parameters: {a: [1, 2}\n")
    with pytest.raises(ConfigError) as info:
        load_parameters([bad])
    assert info.value.line == 2 and "invalid YAML" in info.value.problem
    scalar = write(tmp_path, "scalar.yaml", "just text\n")
    with pytest.raises(ConfigError, match="expected a ROS 2 parameter file"):
        load_parameters([scalar])
