"""Names upstream ignores are warned with file:line and the closest known name: node names near
a modelled node, parameters a node does not declare at the release modelled; the rest never."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from medkit_replay.cli import main
from medkit_replay.config.declared import DECLARED, ROS_PARAMETERS
from medkit_replay.config.params import KNOWN_NODES, load_parameters
from medkit_replay.config.release import release_of
from medkit_replay.config.replay_options import replay_options
from medkit_replay.config.unknown_keys import MAX_LISTED, unknown_keys
from medkit_replay.releases import RELEASES, release_named
from tests.config import declared_upstream

if TYPE_CHECKING:
    from medkit_replay.errors import ConfigWarning

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "nav2_mission.jsonl"


def found(tmp_path: Path, text: str, release: str = "0.7.0") -> list[ConfigWarning]:
    path = tmp_path / "params.yaml"
    path.write_text(text)
    return unknown_keys(load_parameters([path]), release_named(release))


def said(tmp_path: Path, text: str, release: str = "0.7.0") -> list[str]:
    return [str(k) for k in found(tmp_path, text, release)]


def test_a_node_name_near_a_modelled_node_is_warned_with_its_line(tmp_path: Path) -> None:
    text = (
        "fault_manager:\n  ros__parameters:\n    healing_enabled: true\n"
        "fault_manger:\n  ros__parameters:\n    confirmation_threshold: -3\n"
        "/robot1/diagnostics_bridge:\n  ros__parameters: {}\n"
    )
    (typo, namespaced) = found(tmp_path, text)
    path = tmp_path / "params.yaml"
    assert str(typo) == (
        f"{path}:4: node 'fault_manger' is not a node the replay models; "
        "did you mean 'fault_manager'?"
    )
    assert typo.suggestion == "fault_manager"
    assert (namespaced.line, namespaced.suggestion) == (7, "diagnostic_bridge")


@pytest.mark.parametrize(
    "node", ["controller_server", "diagnostic_aggregator", "medkit_gateway", "bt_navigator"]
)
def test_other_nodes_of_a_robot_are_left_alone(tmp_path: Path, node: str) -> None:
    assert said(tmp_path, f"{node}:\n  ros__parameters:\n    confirmaton_threshold: 1\n") == []


def test_wildcard_sections_are_for_every_node_and_not_checked(tmp_path: Path) -> None:
    text = "/**:\n  ros__parameters:\n    robot_radius: 0.3\n    use_sim_time: true\n"
    assert said(tmp_path, text) == []
    assert said(tmp_path, "fault_*:\n  ros__parameters:\n    robot_radius: 0.3\n") == []


@pytest.mark.parametrize("release", list(RELEASES))
def test_a_typo_in_a_parameter_names_the_release_and_the_name_meant(
    tmp_path: Path, release: str
) -> None:
    text = (
        "fault_manager:\n  ros__parameters:\n    confirmation_threshold: -1\n"
        "    confirmaton_threshold: -3\n"
        "log_bridge:\n  ros__parameters:\n    fault_reporter:\n      local_filtering:\n"
        "        enabled: false\n        default_treshold: 2\n"
    )
    path = tmp_path / "params.yaml"
    assert said(tmp_path, text, release) == [
        f"{path}:4: fault_manager has no parameter 'confirmaton_threshold' at ros2_medkit "
        f"{release} (did you mean 'confirmation_threshold'?); upstream ignores it",
        f"{path}:10: log_bridge has no parameter 'fault_reporter.local_filtering."
        f"default_treshold' at ros2_medkit {release} (did you mean "
        "'fault_reporter.local_filtering.default_threshold'?); upstream ignores it",
    ]


def test_a_name_near_nothing_is_warned_without_a_suggestion(tmp_path: Path) -> None:
    (unknown,) = found(tmp_path, "action_status_bridge:\n  ros__parameters:\n    zzz: 1\n")
    assert unknown.message == (
        "action_status_bridge has no parameter 'zzz' at ros2_medkit 0.7.0; upstream ignores it"
    )
    assert unknown.suggestion is None


def test_a_parameter_of_the_other_release_says_which_release_declares_it(
    tmp_path: Path,
) -> None:
    text = (
        "fault_manager:\n  ros__parameters:\n    near_miss: {max_per_fault: 5}\n"
        "    audit_log.enabled: true\n"
        "diagnostic_bridge:\n  ros__parameters:\n    keyvalue_codes: [id]\n"
    )
    path = tmp_path / "params.yaml"
    assert said(tmp_path, text, "0.6.0") == [
        f"{path}:3: fault_manager has no parameter 'near_miss.max_per_fault' at ros2_medkit "
        "0.6.0: it is declared from 0.7.0 on; 0.6.0 ignores it",
        f"{path}:4: fault_manager has no parameter 'audit_log.enabled' at ros2_medkit 0.6.0: "
        "it is declared from 0.7.0 on; 0.6.0 ignores it",
        f"{path}:7: diagnostic_bridge has no parameter 'keyvalue_codes' at ros2_medkit 0.6.0: "
        "it is declared from 0.7.0 on; 0.6.0 ignores it",
    ]
    assert said(tmp_path, text, "0.7.0") == []


@pytest.mark.parametrize("release", list(RELEASES))
def test_ros_and_declared_but_unmodelled_parameters_are_never_warned(
    tmp_path: Path, release: str
) -> None:
    text = (
        "fault_manager:\n  ros__parameters:\n    use_sim_time: true\n"
        "    start_type_description_service: false\n"
        "    qos_overrides:\n      /parameter_events:\n        publisher: {depth: 1000}\n"
        "    database_path: /var/lib/faults.db\n    storage_type: sqlite\n"
        "    snapshots:\n      capture_pool_size: 4\n      capture_queue_full_policy: drop\n"
        "      rosbag: {enabled: true, storage_path: /tmp/b, max_total_storage_mb: 9,"
        " max_buffer_mb: 9, qos_match: true}\n"
        "    correlation.cleanup_interval_sec: 1.0\n"
        "diagnostic_bridge:\n  ros__parameters:\n    use_sim_time: true\n"
        "    name_to_code: {motor_temp: MOTOR_OVERHEAT}\n"
        "action_status_bridge:\n  ros__parameters:\n"
        "    fault_reporter.local_filtering: {enabled: true, default_threshold: 2,"
        " default_window_sec: 5.0, bypass_severity: 3}\n"
        "medkit_replay:\n  ros__parameters:\n"
        f'    upstream_release: "{release}"\n    enable_log_bridge: true\n'
        "    action_sources: {navigate_to_pose: /bt_navigator}\n"
    )
    assert said(tmp_path, text, release) == []


def test_every_declared_parameter_of_every_release_is_quiet(tmp_path: Path) -> None:
    for release, nodes in DECLARED.items():
        for node, names in nodes.items():
            lines = "".join(f"    {n.replace('*', 'x')}: 1\n" for n in sorted(names))
            assert said(tmp_path, f"{node}:\n  ros__parameters:\n{lines}", release) == []


def test_the_replay_node_knows_only_its_own_parameters(tmp_path: Path) -> None:
    text = (
        "medkit_replay:\n  ros__parameters:\n    enable_log_bridges: true\n    use_sim_time: true\n"
    )
    path = tmp_path / "params.yaml"
    assert said(tmp_path, text) == [
        f"{path}:3: medkit_replay has no parameter 'enable_log_bridges' (did you mean "
        "'enable_log_bridge'?); the replay ignores it",
        f"{path}:4: medkit_replay has no parameter 'use_sim_time'; the replay ignores it",
    ]


def test_layered_files_are_each_warned_where_written(tmp_path: Path) -> None:
    first = tmp_path / "a.yaml"
    first.write_text("log_bridge:\n  ros__parameters:\n    severity_flor: 40\n")
    second = tmp_path / "b.yaml"
    second.write_text(
        "log_bridge:\n  ros__parameters:\n    rosout_topic: /r\n    severity_flor: 50\n"
    )
    params = load_parameters([first, second])
    assert [(k.path, k.line) for k in unknown_keys(params, release_of(params))] == [
        (str(first), 3),
        (str(second), 4),
    ]


def test_the_files_under_rules_and_examples_give_no_warning() -> None:
    configs = [
        p
        for folder in ("rules", "examples")
        for p in sorted((ROOT / folder).rglob("*.yaml"))
        if "ros__parameters" in p.read_text()
    ]
    assert len(configs) >= 3
    for path in configs:
        params = load_parameters([path])
        release = release_of(params)
        assert unknown_keys(params, release) == [], path
        _, warnings = replay_options(params, release)
        assert warnings == [], path


def test_the_replay_reports_them_and_runs_as_upstream_would(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    typo = tmp_path / "typo.yaml"
    typo.write_text(
        "fault_manger:\n  ros__parameters:\n    healing_enabled: true\n"
        "fault_manager:\n  ros__parameters:\n    confirmaton_threshold: -3\n"
    )
    assert main(["analyze", str(EXAMPLE), "--config", str(typo), "--json", "-", "--quiet"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["warnings"][:2] == [
        f"{typo}:1: node 'fault_manger' is not a node the replay models; "
        "did you mean 'fault_manager'?",
        f"{typo}:6: fault_manager has no parameter 'confirmaton_threshold' at ros2_medkit "
        "0.7.0 (did you mean 'confirmation_threshold'?); upstream ignores it",
    ]
    # Upstream's defaults stand: the same replay as with no config at all, bar the warnings.
    assert main(["analyze", str(EXAMPLE), "--json", "-", "--quiet"]) == 0
    plain = json.loads(capsys.readouterr().out)
    for key in ("faults", "events", "transitions"):
        assert report[key] == plain[key]


def test_the_table_covers_every_release_and_node() -> None:
    assert set(DECLARED) == set(RELEASES)
    for nodes in DECLARED.values():
        assert set(nodes) == set(KNOWN_NODES)
        assert nodes["fault_manager"] >= ROS_PARAMETERS
        assert not ROS_PARAMETERS & nodes["medkit_replay"]


def test_the_table_is_what_upstream_declares() -> None:
    """Regenerated from an upstream ros2_medkit checkout, when one is at hand."""
    git_dir = declared_upstream.mirror()
    if git_dir is None:
        pytest.skip(
            f"no upstream ros2_medkit git checkout at {declared_upstream.DEFAULT_MIRROR} "
            f"(set {declared_upstream.MIRROR_ENV}); the table cannot be compared"
        )
    assert declared_upstream.compare(git_dir) == []
    # The comparison can fail: a name the table lacks is found.
    names = declared_upstream.upstream_names(git_dir, "505bc2d5", "fault_manager")
    assert names["audit_log.fail_closed"].startswith(
        "src/ros2_medkit_fault_manager/src/fault_manager_node.cpp:"
    )
    assert "retry_period_sec" not in declared_upstream.upstream_names(
        git_dir, "bdcc4ed0", "action_status_bridge"
    )


def test_past_the_first_hundred_the_rest_are_counted(tmp_path: Path) -> None:
    names = "".join(f"    thresh_{n:04d}: 1\n" for n in range(MAX_LISTED + 250))
    listed = found(tmp_path, f"fault_manager:\n  ros__parameters:\n{names}")
    assert len(listed) == MAX_LISTED + 1
    assert listed[MAX_LISTED - 1].message.startswith("fault_manager has no parameter 'thresh_0099'")
    assert str(listed[-1]) == (
        f"{tmp_path / 'params.yaml'}:{MAX_LISTED + 3}: 250 more names upstream ignores from "
        f"here on (the first {MAX_LISTED} are listed)"
    )
