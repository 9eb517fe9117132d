"""Parity with a robot that ran 0.6.0: its recorded FaultEvents carry 0.6.0's Fault (no
``last_passed``; cd8c19b0, #573 added it). They decode with the definition the recording stores,
or, where it stores none (rosbag2 on Humble writes no definitions), with the layout of the
release modelled, then another release's when that one does not fit; a definition of another
release than the one modelled is pointed out with the parameter that selects it. Recordings are
written in tmp_path and replayed whole.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import pytest
from rosbags.rosbag2 import Writer
from rosbags.rosbag2.enums import StoragePlugin

from medkit_replay.msgdefs import base_typestore
from tests.inputs.builders import FAKE_HASH, TS
from tests.pipeline_support import (
    DIAGNOSTICS,
    ERROR,
    EVENTS_TOPIC,
    FAULT_EVENT,
    MS,
    SEC,
    config,
    diagnostics,
    run,
    status,
    warnings_with,
)

if TYPE_CHECKING:
    from pathlib import Path

    from rosbags.typesys.store import Typestore

    from tests.inputs.builders import Storage

RAN_060 = (
    "the robot ran 0.6.0 and this replay models 0.7.0; to model 0.6.0, set "
    'medkit_replay: ros__parameters: upstream_release: "0.6.0"'
)
RAN_070 = "the robot ran 0.7.0 and this replay models 0.6.0"
FAULT = "ros2_medkit_msgs/msg/Fault"
LAYOUTS = {"0.6.0": base_typestore("0.6.0"), "0.7.0": TS}


def confirmed_event(store: Typestore, t_ns: int) -> Any:
    """MOTOR's fault_confirmed as a manager with ``store``'s messages publishes it."""
    time = store.types["builtin_interfaces/msg/Time"]
    fields: dict[str, Any] = {
        "fault_code": "MOTOR",
        "severity": 2,
        "description": "hot",
        "first_occurred": time(sec=t_ns // SEC, nanosec=t_ns % SEC),
        "last_occurred": time(sec=t_ns // SEC, nanosec=t_ns % SEC),
        "occurrence_count": 1,
        "status": "CONFIRMED",
        "reporting_sources": ["/diagnostic_bridge"],
    }
    if any(name == "last_passed" for name, _ in store.fielddefs[FAULT][1]):
        fields["last_passed"] = time(sec=0, nanosec=0)
    fault = store.types[FAULT](**fields)
    return store.types[FAULT_EVENT](
        event_type="fault_confirmed",
        fault=fault,
        timestamp=time(sec=t_ns // SEC, nanosec=t_ns % SEC),
        auto_cleared_codes=[],
    )


def robot_bag(tmp_path: Path, robot: str, storage: Storage, *, definitions: bool) -> Path:
    """One ERROR diagnostic for MOTOR at 1 s and the event a ``robot`` manager published."""
    store = LAYOUTS[robot]
    path = tmp_path / f"{robot}_{storage}_{definitions}"
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    diag = diagnostics(1 * SEC, status("motor", ERROR, "hot"))
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        for topic, msgtype, t_ns, payload, source in (
            (diag.topic, DIAGNOSTICS, diag.t_ns, diag.msg, TS),
            (EVENTS_TOPIC, FAULT_EVENT, 1 * SEC + 4 * MS, confirmed_event(store, SEC), store),
        ):
            text = source.generate_msgdef(msgtype, ros_version=2)[0] if definitions else ""
            connection = writer.add_connection(
                topic, msgtype, msgdef=text, rihs01=FAKE_HASH, serialization_format="cdr"
            )
            writer.write(connection, t_ns, bytes(source.serialize_cdr(payload, msgtype)))
    return path


def replayed(tmp_path: Path, bag: Path, release: str) -> dict[str, Any]:
    text = f'medkit_replay:\n  ros__parameters:\n    upstream_release: "{release}"\n'
    return run([bag], [config(tmp_path, text, f"release_{release}.yaml")])


def parity(report: dict[str, Any]) -> tuple[object, ...]:
    found = report["parity"]
    return found["recorded_events"], found["matched"], found["verdict"]


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_060_robots_recorded_definition_decodes_its_events(
    tmp_path: Path, storage: Storage
) -> None:
    bag = robot_bag(tmp_path, "0.6.0", storage, definitions=True)
    new, old = replayed(tmp_path, bag, "0.7.0"), replayed(tmp_path, bag, "0.6.0")
    assert parity(new) == parity(old) == (1, 1, "match")
    assert len(warnings_with(new, RAN_060)) == 1  # says so once, with the way to select it
    assert warnings_with(old, "the robot ran") == []  # 0.6.0 is already modelled


def test_without_a_definition_the_modelled_releases_layout_decodes_them(tmp_path: Path) -> None:
    humble = robot_bag(tmp_path, "0.6.0", "sqlite3", definitions=False)
    old = replayed(tmp_path, humble, "0.6.0")
    assert parity(old) == (1, 1, "match") and old["warnings"] == []
    # 0.7.0's Fault does not fit the payload: 0.6.0's does, and the warning says so
    new = replayed(tmp_path, humble, "0.7.0")
    assert parity(new) == (1, 1, "match")
    (said,) = warnings_with(new, "does not fit the data")
    assert "used the ros2_medkit 0.6.0 definition: the robot ran 0.6.0" in said
    assert 'upstream_release: "0.6.0"' in said


def test_a_070_robots_definition_is_pointed_out_when_060_is_modelled(tmp_path: Path) -> None:
    bag = robot_bag(tmp_path, "0.7.0", "mcap", definitions=True)
    old, new = replayed(tmp_path, bag, "0.6.0"), replayed(tmp_path, bag, "0.7.0")
    assert parity(old) == parity(new) == (1, 1, "match")
    assert len(warnings_with(old, RAN_070)) == 1
    assert warnings_with(new, "the robot ran") == []
