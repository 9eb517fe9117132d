"""``upstream_release`` in a config file reaches the three bridges the pipeline builds: one file,
read at 0.6.0 and at 0.7.0, gives the bridges of each release (docs/releases.md)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

from medkit_replay.config.params import load_parameters
from medkit_replay.config.release import release_of
from medkit_replay.config.replay_options import replay_options
from medkit_replay.errors import ConfigError
from medkit_replay.model import EventType
from medkit_replay.pipeline.routing import Router
from tests.bridges.messages import (
    ABORTED,
    ERROR,
    SUCCEEDED,
    arr,
    diag,
    diag_array,
    log,
    status_topic,
)

if TYPE_CHECKING:
    from pathlib import Path

LOG_ERROR = 40
CONFIG = """\
medkit_replay:
  ros__parameters:
    upstream_release: "{release}"
diagnostic_bridge:
  ros__parameters:
    keyvalue_codes: ["code"]
    use_hardware_id_as_source_id: true
    max_tracked_sources: 0
log_bridge:
  ros__parameters:
    report_cooldown_sec: -1.0
    severity_floor: 4294967336
action_status_bridge:
  ros__parameters:
    aborted_severity: 4294967297
    retry_period_sec: -1.0
"""


def router_at(tmp_path: Path, release: str) -> tuple[Router, list[str]]:
    path = tmp_path / f"{release}.yaml"
    path.write_text(CONFIG.format(release=release))
    params = load_parameters([path])
    options, warnings = replay_options(params, release_of(params))
    return Router(options), warnings


def test_one_config_gives_each_release_its_bridges(tmp_path: Path) -> None:
    old, old_warnings = router_at(tmp_path, "0.6.0")
    new, new_warnings = router_at(tmp_path, "0.7.0")
    # 0.6.0 reads none of the 0.7.0 parameters: each is said to be ignored, nothing more.
    ignored = [w.split(" has no parameter ")[1].split(" ")[0] for w in old_warnings]
    assert ignored == [
        "'keyvalue_codes'",
        "'use_hardware_id_as_source_id'",
        "'max_tracked_sources'",
        "'retry_period_sec'",
    ]
    assert all(w.endswith("declared from 0.7.0 on; 0.6.0 ignores it") for w in old_warnings)
    assert len(new_warnings) == 5  # bound, cooldown, floor, severity, retry period

    motor = diag("/motor", ERROR, "hot", hardware_id="/motor_driver", values={"code": "MF"})
    [a] = old.diagnostic.on_message(1, "/diagnostics", diag_array(motor))
    [b] = new.diagnostic.on_message(1, "/diagnostics", diag_array(motor))
    assert (a.fault_code, a.source_id) == ("MOTOR", "/diagnostic_bridge")
    assert (b.fault_code, b.source_id) == ("MF", "/motor_driver")

    assert old.log is not None
    assert new.log is not None
    line = log("planner_server", LOG_ERROR, "no path")
    assert len(old.log.on_message(1, "/rosout", line) + old.log.on_message(2, "/rosout", line)) == 2
    assert new.log.on_message(1, "/rosout", line) == []  # floor 50

    old.action.service_ready = new.action.service_ready = False
    topic = status_topic("/nav")
    assert old.action.on_message(1, topic, arr((1, ABORTED))) == []
    assert new.action.on_message(1, topic, arr((1, ABORTED))) == []
    old.action.service_ready = new.action.service_ready = True
    assert old.action.reconcile_pending(2) == []  # lost at 0.6.0
    [raised] = new.action.reconcile_pending(2)
    assert raised.severity == 2
    # 0.6.0 thinks /nav failed: a success heals it, and the next abort raises at severity 1.
    [heal] = old.action.on_message(3, topic, arr((2, SUCCEEDED)))
    [again] = old.action.on_message(4, topic, arr((3, ABORTED)))
    assert (heal.event_type, again.severity) == (EventType.PASSED, 1)


def test_a_nan_cooldown_is_one_line_with_file_and_line_at_060(tmp_path: Path) -> None:
    path = tmp_path / "nan.yaml"
    path.write_text(
        'medkit_replay:\n  ros__parameters:\n    upstream_release: "0.6.0"\n'
        "log_bridge:\n  ros__parameters:\n    report_cooldown_sec: .nan\n"
    )
    params = load_parameters([path])
    with pytest.raises(ConfigError) as err:
        replay_options(params, release_of(params))
    assert (err.value.path, err.value.line) == (str(path), 6)
    assert "report_cooldown_sec" in str(err.value)
