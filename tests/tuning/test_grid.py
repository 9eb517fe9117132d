"""The sweep's grid: --vary specs typed as ROS parameters, their product, the variants' files."""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

from medkit_replay.config.params import load_parameters
from medkit_replay.config.unknown_keys import undeclared
from medkit_replay.errors import ConfigError
from medkit_replay.tuning import grid
from medkit_replay.tuning.grid import (
    check_names,
    make_grid,
    parse_vary,
    split_values,
    variant_config,
    variant_yaml,
)

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.releases import Release


def test_values_split_on_commas_outside_brackets_and_quotes() -> None:
    assert split_values("-1,-3, -5") == ["-1", "-3", "-5"]
    assert split_values("[a, b],'x,y',\"p,q\",") == ["[a, b]", "'x,y'", '"p,q"', ""]


def test_values_are_typed_as_in_a_parameter_file() -> None:
    vary = parse_vary("log_bridge.exclude_nodes=[a, b],[c]")
    assert vary.values == (["a", "b"], ["c"])
    assert parse_vary("fault_manager.confirmation_threshold=-1,-3").values == (-1, -3)
    assert parse_vary("fault_manager.auto_confirm_after_sec=0.0,5").values == (0.0, 5)
    assert parse_vary("medkit_replay.enable_log_bridge=true,'true'").values == (True, "true")
    assert parse_vary("fault_manager.confirmation_threshold=-1,-3").kind == "int"
    assert parse_vary("medkit_replay.enable_log_bridge=true,'true'").kind == "str"


def test_file_values_are_absolute_and_empty_is_off(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    vary = parse_vary("fault_manager.correlation.config_file=,rules/a.yaml")
    assert vary.values == ("", str(tmp_path / "rules" / "a.yaml"))
    assert vary.texts == ("", "rules/a.yaml")


def test_the_grid_is_the_product_first_vary_slowest() -> None:
    grid = make_grid(
        [
            parse_vary("fault_manager.confirmation_threshold=-1,-3"),
            parse_vary("fault_manager.healing_threshold=1,2,3"),
        ]
    )
    assert [v.id for v in grid] == [f"v{i:02d}" for i in range(1, 7)]
    assert [v.label for v in grid[:4]] == [
        "confirmation_threshold=-1 healing_threshold=1",
        "confirmation_threshold=-1 healing_threshold=2",
        "confirmation_threshold=-1 healing_threshold=3",
        "confirmation_threshold=-3 healing_threshold=1",
    ]


def test_a_variant_config_is_what_a_last_parameter_file_would_give(tmp_path: Path) -> None:
    base_file = tmp_path / "base.yaml"
    base_file.write_text("fault_manager:\n  ros__parameters:\n    healing_enabled: true\n")
    base = load_parameters([base_file])
    (variant,) = make_grid([parse_vary("fault_manager.healing_threshold=5")])
    config = variant_config(base, variant)
    assert config.manager.debounce.healing_threshold == 5
    assert config.manager.debounce.healing_enabled is True
    with_positive = make_grid([parse_vary("fault_manager.confirmation_threshold=3")])[0]
    warned = variant_config(base, with_positive)
    assert warned.manager.debounce.confirmation_threshold == -3
    assert any("is positive" in w for w in warned.warnings)


def test_an_unread_name_is_refused(tmp_path: Path) -> None:
    base = load_parameters([])
    varies = [parse_vary("fault_manager.healing_treshold=1")]
    with pytest.raises(
        ConfigError,
        match=r"--vary fault_manager.healing_treshold: fault_manager has no parameter "
        r"'healing_treshold' at ros2_medkit 0.7.0 \(did you mean 'healing_threshold'\?\)",
    ):
        check_names(base, varies, make_grid(varies))
    # Read only with a correlation file: refused without one.
    varies = [parse_vary("fault_manager.correlation.cleanup_interval_sec=1.0")]
    with pytest.raises(ConfigError, match="unused with this config"):
        check_names(base, varies, make_grid(varies))
    # Declared upstream but not modelled (it changes nothing in a replay): refused as unread.
    varies = [parse_vary("fault_manager.database_path=/tmp/faults.db")]
    with pytest.raises(ConfigError, match="fault_manager reads no parameter 'database_path'"):
        check_names(base, varies, make_grid(varies))


def test_an_undeclared_name_is_looked_up_once_per_release(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    looked: list[str] = []

    def counted(node: str, name: str, release: Release) -> tuple[str, str | None] | None:
        looked.append(release.name)
        return undeclared(node, name, release)

    monkeypatch.setattr(grid, "undeclared", counted)
    varies = [
        parse_vary("fault_manager.healing_treshold=1,2"),
        parse_vary("medkit_replay.upstream_release=0.6.0,0.7.0"),
    ]
    with pytest.raises(ConfigError, match=r"'healing_treshold' at ros2_medkit 0\.6\.0"):
        check_names(load_parameters([]), varies, make_grid(varies))
    assert looked == ["0.6.0", "0.7.0"]


def test_a_typo_in_a_varied_node_is_refused_with_the_node_meant() -> None:
    with pytest.raises(
        ConfigError, match=r"unknown node 'fault_manger' \(did you mean 'fault_manager'\?\)"
    ):
        parse_vary("fault_manger.healing_threshold=1")
    with pytest.raises(ConfigError, match=r"unknown node 'planner' \(known: fault_manager, "):
        parse_vary("planner.healing_threshold=1")


def test_a_name_only_another_release_reads_is_refused(tmp_path: Path) -> None:
    """Which parameters exist follows each variant's release: 0.6.0's diagnostic bridge and
    fault manager declare neither keyvalue_codes nor near_miss.max_per_fault."""
    old = tmp_path / "old.yaml"
    old.write_text('medkit_replay:\n  ros__parameters:\n    upstream_release: "0.6.0"\n')
    base = load_parameters([old])
    for key in ("diagnostic_bridge.keyvalue_codes=[id]", "fault_manager.near_miss.max_per_fault=5"):
        varies = [parse_vary(key)]
        with pytest.raises(ConfigError, match=r"declared from 0\.7\.0 on; 0\.6\.0 ignores it"):
            check_names(base, varies, make_grid(varies))
        check_names(load_parameters([]), varies, make_grid(varies))  # read at the newest
    # A grid that also varies the release reads the name in its 0.7.0 variants.
    varies = [
        parse_vary("medkit_replay.upstream_release=0.6.0,0.7.0"),
        parse_vary("diagnostic_bridge.keyvalue_codes=[id]"),
    ]
    check_names(base, varies, make_grid(varies))


def test_the_variant_file_reproduces_the_variant(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    rules = tmp_path / "rules.yaml"
    rules.write_text("correlation:\n  enabled: false\n")
    (variant,) = make_grid(
        [
            parse_vary("fault_manager.correlation.config_file=rules.yaml"),
            parse_vary("log_bridge.severity_floor=40"),
        ]
    )
    folder = tmp_path / "out" / "variants"
    folder.mkdir(parents=True)
    path = folder / "v01.yaml"
    path.write_text(variant_yaml(variant, folder))
    assert '    "correlation.config_file": "../../rules.yaml"' in path.read_text()
    params = load_parameters([path])
    assert params.node("log_bridge")["severity_floor"].value == 40
    named = params.node("fault_manager")["correlation.config_file"]
    assert (named.path.parent / str(named.value)).resolve() == rules


@pytest.mark.parametrize(
    "text", ["-3", "5.0", "1e-05", ".inf", "true", "'true'", "abc", "[a, b]", "[1, 2]", "- x"]
)
def test_a_variant_file_types_its_values_back_the_same(tmp_path: Path, text: str) -> None:
    from medkit_replay.tuning.grid import Setting, Variant  # noqa: PLC0415

    vary = parse_vary(f"log_bridge.some_value={text}")
    (value,) = vary.values
    variant = Variant(0, (Setting("log_bridge", "some_value", value, text),))
    path = tmp_path / "v01.yaml"
    path.write_text(variant_yaml(variant, tmp_path))
    assert load_parameters([path]).node("log_bridge")["some_value"].value == value
