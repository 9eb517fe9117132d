"""The plumbing the bridges share: the Bridge protocol, the registry, reporters and parameters.

The FaultReporter rules here are bridges.md §0 and fault-manager.md §2.4.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from medkit_replay.bridges import (
    ActionStatusBridge,
    Bridge,
    DiagnosticBridge,
    FaultReporter,
    LogBridge,
)
from medkit_replay.bridges.base import (
    RequestList,
    any_substring,
    passes_lists,
    resolve_topic,
)
from medkit_replay.config.reader import ParameterReader, to_int32
from medkit_replay.engine.local_filter import LocalFilterConfig
from medkit_replay.errors import ConfigError
from medkit_replay.model import EventType, ReportRequest
from tests.bridges.messages import (
    ABORTED,
    DIAGNOSTIC_ARRAY,
    GOAL_STATUS_ARRAY,
    LOG,
    TS,
    diag,
    diag_array,
    log,
    one,
)


def test_every_bridge_fits_the_protocol_and_claims_its_own_input() -> None:
    bridges: list[Bridge] = [ActionStatusBridge(), DiagnosticBridge(), LogBridge()]
    inputs = [
        ("/nav/_action/status", GOAL_STATUS_ARRAY),
        ("/diagnostics", DIAGNOSTIC_ARRAY),
        ("/rosout", LOG),
    ]
    claims = [[bridge.wants(topic, kind) for topic, kind in inputs] for bridge in bridges]
    assert claims == [[True, False, False], [False, True, False], [False, False, True]]
    assert [b.origin for b in bridges] == [b.name for b in bridges]


def test_bridges_do_not_import_rosbags_at_run_time() -> None:
    code = "import json, sys, medkit_replay.bridges; print(json.dumps(sorted(sys.modules)))"
    out = subprocess.run(
        [sys.executable, "-c", code], check=True, capture_output=True, text=True
    ).stdout
    loaded = json.loads(out)
    assert "medkit_replay.bridges.log" in loaded
    assert not [m for m in loaded if m.split(".")[0] in ("rosbags", "numpy", "yaml", "pandas")]


def test_reporter_drops_empty_codes_and_stamps_its_source() -> None:
    reporter = FaultReporter("/src", LocalFilterConfig(enabled=False), origin="log_bridge")
    sent = RequestList()
    reporter.report(1, "/t", "", 2, "x", sent)
    reporter.report_passed(1, "/t", "", sent)
    assert sent == []
    reporter.report(1, "/t", "C", 1, "x", sent)
    assert sent == [
        ReportRequest(
            t_ns=1,
            fault_code="C",
            event_type=EventType.FAILED,
            severity=1,
            description="x",
            source_id="/src",
            origin="log_bridge",
            topic="/t",
        )
    ]
    reporter.report_passed(2, "/t", "C", sent)
    passed = sent[-1]
    assert (passed.event_type, passed.severity, passed.description) == (EventType.PASSED, 0, "")
    assert type(passed.event_type) is int  # plain numbers travel to the manager


def test_reporter_filter_is_sanitised_from_its_config() -> None:
    reporter = FaultReporter(
        "/src",
        LocalFilterConfig(default_threshold=0, default_window_sec=-1.0),
        origin="diagnostic_bridge",
    )
    assert reporter.local_filter.config.default_threshold == 1
    assert reporter.local_filter.config.default_window_sec == 1.0
    sent = RequestList()
    reporter.report(1, "/t", "C", 0, "", sent)
    assert len(sent) == 1


@pytest.mark.parametrize(
    ("name", "fqn", "resolved"),
    [
        ("/diagnostics", "/diagnostic_bridge", "/diagnostics"),
        ("diagnostics", "/diagnostic_bridge", "/diagnostics"),
        ("diagnostics", "/robot1/diagnostic_bridge", "/robot1/diagnostics"),
        ("~/in", "/robot1/diagnostic_bridge", "/robot1/diagnostic_bridge/in"),
    ],
)
def test_resolve_topic(name: str, fqn: str, resolved: str) -> None:
    assert resolve_topic(name, fqn) == resolved


def test_substring_lists() -> None:
    assert any_substring(["", "nav"], "/navigate")
    assert not any_substring(["", "arm"], "/navigate")
    assert passes_lists((), (), "/x")
    assert not passes_lists(("",), (), "/x")
    assert not passes_lists(("x",), ("/x",), "/x")


@pytest.mark.parametrize(
    ("value", "narrowed"), [(3, 3), (2**32 + 3, 3), (2**31, -(2**31)), (-1, -1), (2**32 - 1, -1)]
)
def test_to_int32_wraps_like_a_static_cast(value: int, narrowed: int) -> None:
    assert to_int32(value) == narrowed


def test_parameter_errors_name_node_parameter_and_value() -> None:
    read = ParameterReader("log_bridge", {"report_cooldown_sec": 5, "exclude_nodes": None})
    with pytest.raises(ConfigError) as err:
        read.double("report_cooldown_sec", 5.0)
    assert err.value.problem == (
        "log_bridge parameter 'report_cooldown_sec' must be a double, got integer 5 (write 5.0)"
    )
    with pytest.raises(ConfigError, match="'exclude_nodes' must be a list of strings, got null"):
        read.strings("exclude_nodes")


def test_parameter_reader_accepts_empty_and_tuple_lists() -> None:
    read = ParameterReader("n", {"a": [], "b": ("x", "y")})
    assert read.strings("a") == ()
    assert read.strings("b") == ("x", "y")
    assert read.strings("missing") == ()


def test_bridges_read_messages_decoded_from_cdr() -> None:
    # What a bag read hands over: CDR bytes deserialised by rosbags, not hand-built objects.
    def decoded(msg: object, msgtype: str) -> object:
        return TS.deserialize_cdr(TS.serialize_cdr(msg, msgtype), msgtype)

    diagnostics = decoded(diag_array(diag("motor temp", 3, "hot")), DIAGNOSTIC_ARRAY)
    status = decoded(one(1, ABORTED), GOAL_STATUS_ARRAY)
    line = decoded(log("ctrl", 40, "oops 42"), LOG)
    out = [
        *DiagnosticBridge().on_message(1, "/diagnostics", diagnostics),
        *ActionStatusBridge().on_message(2, "/nav/_action/status", status),
        *LogBridge().on_message(3, "/rosout", line),
    ]
    assert [(r.fault_code, r.severity, r.source_id) for r in out] == [
        ("MOTOR_TEMP", 3, "/diagnostic_bridge"),
        ("ACTION_NAV_ABORTED", 2, "/nav"),
        ("LOG_CTRL_0bf0b26e", 2, "/ctrl"),
    ]
