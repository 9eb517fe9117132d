"""``medkit-replay validate``: each kind of config file told and said, checked without a recording
by the replay's readers; one finding a line with file:line; exit 0 clean, 1 warnings, 2 unusable.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from medkit_replay.cli import main
from medkit_replay.config.referenced import FILE_PARAMETERS
from medkit_replay.config.validation import Finding, warning_findings
from medkit_replay.errors import ConfigWarning

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "nav2_mission.jsonl"

PARAMS = "fault_manager:\n  ros__parameters:\n    confirmation_threshold: -1\n"
CORRELATION = """\
correlation:
  enabled: true
  default_window_ms: 500
  patterns:
    drive: {codes: [WHEEL_*]}
  rules:
    - id: motor
      root_cause: {codes: [MOTOR_*]}
      symptoms: [{pattern: drive}]
"""
ENTITY = "/controller_server:\n  healing_threshold: 0\n"
SNAPSHOTS = "fault_specific:\n  ESTOP: [/cmd_vel]\ndefault_topics: [/diagnostics]\n"
BUDGET = "version: 1\nrules:\n  - never_confirm: [ESTOP*]\n"
GRAPH_YAML = "/controller_server:\n  publishers: [/cmd_vel]\n  subscribers: [/odom]\n"
GRAPH_INFO = "/controller_server\n  Publishers:\n    /cmd_vel: geometry_msgs/msg/Twist\n"

KINDS = {
    "parameters": ("params.yaml", PARAMS, "a ROS 2 parameter file (release 0.7.0)"),
    "correlation": ("correlation.yaml", CORRELATION, "a correlation file"),
    "entity_thresholds": ("entity.yaml", ENTITY, "an entity-thresholds file"),
    "snapshots": ("snapshots.yaml", SNAPSHOTS, "a snapshot config file"),
    "budget": ("budget.yaml", BUDGET, "a fault budget"),
    "graph": ("graph.yaml", GRAPH_YAML, "a node graph"),
}


def run(
    capsys: pytest.CaptureFixture[str], *args: str | Path
) -> tuple[int, str, list[dict[str, object]]]:
    """validate's exit status, its lines and, run again with --json, its records."""
    argv = ["validate", *map(str, args)]
    status = main(argv)
    out, err = capsys.readouterr()
    assert err == "", err
    assert main([*argv, "--json"]) == status
    records = json.loads(capsys.readouterr().out)
    assert isinstance(records, list)
    return status, out, records


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def problems(records: list[dict[str, object]]) -> list[tuple[object, ...]]:
    """(file name, line, severity, kind, suggestion) of the records that are not info."""
    return [
        (Path(str(r["file"])).name, r["line"], r["severity"], r["kind"], r["suggestion"])
        for r in records
        if r["severity"] != "info"
    ]


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_each_kind_is_told_from_its_content_and_said(
    kind: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    name, text, described = KINDS[kind]
    path = write(tmp_path, name.replace(".yaml", ".txt"), text)  # the name does not decide
    status, out, records = run(capsys, path)
    assert status == 0
    assert out == f"{path}: info: read as {described}\n"
    assert records == [
        {
            "file": str(path),
            "line": None,
            "severity": "info",
            "kind": kind,
            "message": f"read as {described}",
            "suggestion": None,
        }
    ]


def test_a_ros2_node_info_graph_is_a_graph(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    status, _, records = run(capsys, write(tmp_path, "graph.txt", GRAPH_INFO))
    assert status == 0
    assert [r["kind"] for r in records] == ["graph"]


def test_every_file_under_rules_validates_clean(capsys: pytest.CaptureFixture[str]) -> None:
    files = sorted((ROOT / "rules").rglob("*.yaml"))
    assert len(files) >= 7
    status, out, records = run(capsys, *files)
    assert status == 0, out
    assert problems(records) == []
    said = {Path(str(r["file"])).resolve() for r in records}
    assert said == {f.resolve() for f in files}  # each given file, and those they name


def test_the_example_configs_validate_clean(capsys: pytest.CaptureFixture[str]) -> None:
    files = [
        *sorted((ROOT / "examples").rglob("*.yaml")),
        ROOT / "examples/evidence/nav2_graph.txt",
    ]
    status, out, records = run(capsys, *files)
    assert status == 0, out
    assert [r["kind"] for r in records] == ["parameters", "parameters", "graph"]


def test_a_parameter_file_is_read_with_the_files_it_names(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    write(tmp_path, "correlation.yaml", CORRELATION.replace("default_window_ms", "windw_ms"))
    write(tmp_path, "entity.yaml", ENTITY.replace("healing_threshold", "healing_treshold"))
    write(tmp_path, "snapshots.yaml", SNAPSHOTS.replace("default_topics", "default_topic"))
    params = write(
        tmp_path,
        "params.yaml",
        PARAMS
        + "    correlation: {config_file: correlation.yaml}\n"
        + "    entity_thresholds.config_file: entity.yaml\n"
        + "    snapshots.config_file: snapshots.yaml\n",
    )
    status, out, records = run(capsys, params)
    assert status == 1
    assert f"{tmp_path / 'correlation.yaml'}: info: read as a correlation file (named by " in out
    assert problems(records) == [
        ("entity.yaml", 2, "warning", "entity_thresholds", "healing_threshold"),
        ("correlation.yaml", 3, "warning", "correlation", "default_window_ms"),
        ("snapshots.yaml", 3, "warning", "snapshots", "default_topics"),
    ]
    assert (
        f"{tmp_path / 'snapshots.yaml'}:3: warning: snapshot config file: unknown key "
        "'default_topic' (did you mean 'default_topics'?); upstream ignores it\n" in out
    )


@pytest.mark.parametrize(
    ("name", "text", "expected", "line"),
    [
        (
            "correlation.yaml",
            CORRELATION.replace("default_window_ms", "default_windw_ms"),
            "correlation: unknown key 'default_windw_ms' (did you mean 'default_window_ms'?); "
            "upstream ignores it",
            3,
        ),
        (
            "correlation.yaml",
            CORRELATION + "      min_count: 2\n",
            "rule 'motor' (hierarchical): 'min_count' is read only by auto_cluster rules; "
            "upstream ignores it here",
            10,
        ),
        (
            "entity.yaml",
            ENTITY + "  Healing_Enabled: true\n",
            "entity '/controller_server': unknown key 'Healing_Enabled' (did you mean "
            "'healing_enabled'?); upstream ignores it",
            3,
        ),
        (
            "params.yaml",
            PARAMS.replace("confirmation_threshold", "confirmaton_threshold"),
            "fault_manager has no parameter 'confirmaton_threshold' at ros2_medkit 0.7.0 "
            "(did you mean 'confirmation_threshold'?); upstream ignores it",
            3,
        ),
        (
            "params.yaml",
            PARAMS.replace("fault_manager", "fault_manger"),
            "node 'fault_manger' is not a node the replay models; did you mean 'fault_manager'?",
            1,
        ),
        (
            "params.yaml",
            PARAMS.replace("-1", "3"),
            "fault_manager: confirmation_threshold 3 is positive; using -3 (upstream negates it)",
            3,
        ),
        (
            "params.yaml",
            "log_bridge:\n  ros__parameters:\n    severity_floor: 99\n",
            "log_bridge: severity_floor=99 out of range [0,50], clamping",
            3,
        ),
        (
            "params.yaml",
            PARAMS + "    snapshots: {timeout_sec: -1.0}\n",
            "fault_manager: snapshots.timeout_sec -1.0 must be positive; using 1.0",
            4,
        ),
    ],
)
def test_a_warning_exits_1_with_file_line_and_suggestion(
    name: str,
    text: str,
    expected: str,
    line: int,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    path = write(tmp_path, name, text)
    status, out, records = run(capsys, path)
    assert status == 1
    assert out.splitlines()[1:] == [f"{path}:{line}: warning: {expected}"]
    (record,) = [r for r in records if r["severity"] == "warning"]
    assert (record["file"], record["line"], record["message"]) == (str(path), line, expected)
    meant = expected.split("did you mean '")[1:]
    assert record["suggestion"] == (meant[0].split("'", maxsplit=1)[0] if meant else None)


@pytest.mark.parametrize(
    ("name", "text", "expected"),
    [
        ("params.yaml", PARAMS + "  ros__parameters: [\n", ":5: error: invalid YAML: "),
        ("params.yaml", PARAMS.replace("-1", "[[1]]"), ":3: error: confirmation_threshold: "),
        ("params.yaml", PARAMS.replace("-1", "'x'"), ":3: error: fault_manager parameter "),
        (
            "budget.yaml",
            BUDGET + "  - max_confirmd: {ERROR: 0}\n",
            ":4: error: rule 2: unknown key 'max_confirmd' (did you mean 'max_confirmed'?)",
        ),
        ("correlation.yaml", CORRELATION + "      mode: auto-cluster\n", ":10: error: Failed"),
        ("graph.yaml", GRAPH_YAML + "  services: [/x]\n", ": error: node '/controller_server'"),
        ("scalar.yaml", "hello\n", ": error: looks like no file medkit-replay reads"),
        ("absent.yaml", None, ": error: file not found"),
    ],
)
def test_a_file_that_cannot_be_used_exits_2(
    name: str,
    text: str | None,
    expected: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    path = write(tmp_path, name, text) if text is not None else tmp_path / name
    status, out, records = run(capsys, path)
    assert status == 2
    assert f"{path}{expected}" in out, out
    assert [r["severity"] for r in records if r["severity"] != "info"] == ["error"]


def test_a_file_named_by_a_config_that_is_missing_is_unusable(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    params = write(tmp_path, "params.yaml", PARAMS + "    correlation.config_file: gone.yaml\n")
    status, out, _ = run(capsys, params)
    assert status == 2
    assert f"{tmp_path / 'gone.yaml'}: error: Correlation config file not found" in out


ZERO = "fault_manager:\n  ros__parameters:\n    confirmation_threshold: 0\n"
OLD = "medkit_replay:\n  ros__parameters:\n    upstream_release: '0.6.0'\n"


def test_release_checks_against_another_release(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """0.7.0 replaces a confirmation_threshold of 0 with -1; 0.6.0 keeps it, saying nothing."""
    newest = write(tmp_path, "params.yaml", ZERO)
    status, out, _ = run(capsys, newest)
    assert status == 1
    assert f"{newest}:3: warning: fault_manager: confirmation_threshold 0 is invalid" in out
    status, out, _ = run(capsys, newest, "--release", "0.6.0")
    assert (status, out) == (0, f"{newest}: info: read as a ROS 2 parameter file (release 0.6.0)\n")
    own = write(tmp_path, "old.yaml", ZERO + OLD)
    assert run(capsys, own)[:2] == (
        0,
        f"{own}: info: read as a ROS 2 parameter file (release 0.6.0)\n",
    )
    status, out, _ = run(capsys, own, "--release", "0.7.0")
    assert status == 1 and "(release 0.7.0)" in out and "is invalid; using -1" in out
    assert main(["validate", str(own), "--release", "9.9"]) == 2
    assert "not a release the replay models" in capsys.readouterr().err


def test_a_file_given_and_named_has_its_findings_once(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    correlation = write(tmp_path, "c.yaml", CORRELATION.replace("rules:", "rulez:"))
    params = write(tmp_path, "p.yaml", PARAMS + "    correlation.config_file: c.yaml\n")
    status, out, records = run(capsys, params, correlation)
    assert status == 1
    assert out.count("unknown key 'rulez'") == 1
    assert out.count("read as a correlation file") == 1  # where it is named
    assert len(problems(records)) == 2  # and: the pattern no rule uses


def test_a_file_named_by_a_config_given_is_read_as_that_kind(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A snapshot file whose only key is misspelt looks like no kind; named, it is known."""
    snapshots = write(tmp_path, "s.yaml", "default_topic: [/diagnostics]\n")
    params = write(tmp_path, "p.yaml", PARAMS + "    snapshots.config_file: s.yaml\n")
    status, out, records = run(capsys, snapshots, params)
    assert status == 1, out
    assert problems(records) == [("s.yaml", 1, "warning", "snapshots", "default_topics")]
    assert out.startswith(f"{params}: info: read as a ROS 2 parameter file (release 0.7.0)\n")
    assert f"{snapshots}: info: read as a snapshot config file (named by {params}:4)\n" in out


def test_a_plain_warning_is_about_the_file_read() -> None:
    """A reader's warning without fields is still a finding, about the file given."""
    found = warning_findings(
        ["fault_manager: something", ConfigWarning("other", path="b.yaml", line=2)],
        Path("a.yaml"),
        "parameters",
    )
    assert found == [
        Finding("a.yaml", None, "warning", "parameters", "fault_manager: something"),
        Finding("b.yaml", 2, "warning", "parameters", "other"),
    ]


def test_a_replay_warns_unknown_keys_of_the_files_a_config_names(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Every command reads them through the fault manager's config: analyze, say."""
    write(tmp_path, "entity.yaml", ENTITY.replace("healing_threshold", "healing_treshold"))
    params = write(tmp_path, "p.yaml", PARAMS + "    entity_thresholds.config_file: entity.yaml\n")
    assert main(["analyze", str(EXAMPLE), "--config", str(params), "--json", "-"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["warnings"] == [
        f"{tmp_path / 'entity.yaml'}:2: entity '/controller_server': unknown key "
        "'healing_treshold' (did you mean 'healing_threshold'?); upstream ignores it"
    ]


def test_keys_of_a_disabled_correlation_file_are_warned_whatever_it_holds(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Upstream reads nothing past ``enabled: false``: rules it would refuse refuse nothing."""
    path = write(
        tmp_path,
        "correlation.yaml",
        "correlation:\n  enabled: false\n  rules:\n    - hello\n    - {mode: bogus, x: 1}\n"
        "    - {id: a, mode: cluster, typo: 2}\n  patterns: {p: [A], q: {codez: [B]}}\n",
    )
    status, out, records = run(capsys, path)
    assert status == 1, out
    assert problems(records) == [
        ("correlation.yaml", 7, "warning", "correlation", "codes"),
        ("correlation.yaml", 6, "warning", "correlation", None),
        ("correlation.yaml", None, "warning", "correlation", None),
    ]
    assert "rule 'a' (auto_cluster): unknown key 'typo'" in out
    assert f"{path}: warning: Correlation explicitly disabled in config" in out


def test_an_empty_file_is_a_warning(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, "empty.yaml", "# nothing yet\n")
    assert run(capsys, path)[:2] == (1, f"{path}: warning: empty: it sets nothing\n")


def test_each_file_parameter_names_the_kind_of_file_it_holds() -> None:
    assert set(FILE_PARAMETERS.values()) <= set(KINDS)
    assert all(name == f"{kind}.config_file" for name, kind in FILE_PARAMETERS.items())
