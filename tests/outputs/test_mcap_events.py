"""The --mcap output: FaultEvents and status changes, read back with mcap, rosbags and ourselves."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import pytest
from mcap.reader import make_reader
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from medkit_replay.cli import main
from medkit_replay.outputs.mcap_events import (
    EVENTS_TOPIC,
    FAULT_EVENT_TYPE,
    TRANSITION_TYPE,
    TRANSITIONS_TOPIC,
    schemas,
    write_mcap,
)
from medkit_replay.pipeline import replay
from tests.outputs.scripts import SEC, T0, clear, report, write_script

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.result import Result

SUB = 123_456_789  # a sub-second part, so that nanoseconds are checked too


def correlated(tmp_path: Path) -> tuple[Path, Path]:
    """A script and a config: a root cause that auto-clears a muted symptom, a healed fault."""
    (tmp_path / "corr.yaml").write_text(
        "correlation:\n  enabled: true\n  rules:\n    - id: overheat\n"
        "      mode: hierarchical\n      root_cause: {codes: [MOTOR_OVERHEAT]}\n"
        "      symptoms: [{codes: ['WHEEL_*']}]\n      window_ms: 5000\n"
        "      mute_symptoms: true\n      auto_clear_with_root: true\n",
        encoding="utf-8",
    )
    config = tmp_path / "params.yaml"
    config.write_text(
        "fault_manager:\n  ros__parameters:\n    healing_enabled: true\n"
        "    healing_threshold: 3\n    correlation: {config_file: corr.yaml}\n",
        encoding="utf-8",
    )
    script = write_script(
        tmp_path / "run.jsonl",
        [
            report(T0, "MOTOR_OVERHEAT", severity=3, description="92 C", source="/drive/motor"),
            report(T0 + SEC + SUB, "WHEEL_SLIP", source="/drive/left"),
            report(T0 + 2 * SEC, "WHEEL_SLIP", source="/drive/right"),
            report(T0 + 3 * SEC, "LIDAR_DROPOUT", severity=1, source="/sensors/lidar"),
            *(
                report(T0 + (4 + i) * SEC, "LIDAR_DROPOUT", "PASSED", source="/sensors/lidar")
                for i in range(4)
            ),
            clear(T0 + 10 * SEC + SUB, "MOTOR_OVERHEAT"),
        ],
    )
    return script, config


@pytest.fixture
def result(tmp_path: Path) -> Result:
    script, config = correlated(tmp_path)
    replayed = replay([script], [config])
    assert replayed.warnings == ()
    assert any(e.auto_cleared_codes for e in replayed.events)
    assert any(t.cause == "auto_clear" for t in replayed.transitions)
    return replayed


def expected_events(result: Result) -> list[tuple[int, str, str, str]]:
    return [(e.t_ns, e.event_type, e.fault.fault_code, e.fault.status) for e in result.events]


def expected_transitions(result: Result) -> list[tuple[int, str, str, str, str, str]]:
    return [
        (t.t_ns, t.fault_code, t.from_status or "", t.to_status, t.cause, t.source_id or "")
        for t in result.transitions
    ]


def test_read_back_with_the_mcap_library(result: Result, tmp_path: Path) -> None:
    path = tmp_path / "replayed.mcap"
    counts = write_mcap(result, path)
    assert counts == {EVENTS_TOPIC: len(result.events), TRANSITIONS_TOPIC: len(result.transitions)}
    with path.open("rb") as stream:
        reader = make_reader(stream)
        header = reader.get_header()
        assert header.profile == "ros2" and header.library.startswith("medkit-replay ")
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        assert summary.statistics.message_start_time == T0
        assert summary.statistics.message_end_time == T0 + 10 * SEC + SUB
        by_topic: dict[str, list[tuple[int, int, int]]] = {}
        for schema, channel, message in reader.iter_messages(log_time_order=True):
            assert schema is not None and schema.encoding == "ros2msg"
            assert channel.message_encoding == "cdr"
            assert "offered_qos_profiles" in channel.metadata
            expected_type = FAULT_EVENT_TYPE if channel.topic == EVENTS_TOPIC else TRANSITION_TYPE
            assert schema.name == expected_type
            assert schema.data.decode() == schemas()[expected_type]
            by_topic.setdefault(channel.topic, []).append(
                (message.log_time, message.publish_time, message.sequence)
            )
    events = by_topic[EVENTS_TOPIC]
    assert [log for log, _, _ in events] == [e.t_ns for e in result.events]
    assert all(log == publish for log, publish, _ in events)
    assert [seq for _, _, seq in events] == list(range(1, len(events) + 1))
    assert [log for log, _, _ in by_topic[TRANSITIONS_TOPIC]] == [
        t.t_ns for t in result.transitions
    ]


def test_schema_text_is_rosbag2_concatenated_msg() -> None:
    text = schemas()[FAULT_EVENT_TYPE]
    assert text.startswith("string event_type\nFault fault\n")
    sections = text.split("=" * 80 + "\n")
    assert [s.splitlines()[0] for s in sections[1:]] == [
        "MSG: ros2_medkit_msgs/Fault",
        "MSG: builtin_interfaces/Time",
    ]
    assert "MSG: builtin_interfaces/Time" in schemas()[TRANSITION_TYPE]


def rosbags_messages(path: Path) -> dict[str, list[tuple[int, Any]]]:
    """Every message of a bare .mcap via rosbags, decoded with only the definitions it embeds."""
    store = get_typestore(Stores.EMPTY)
    out: dict[str, list[tuple[int, Any]]] = {}
    with Reader(path) as reader:
        for connection in reader.connections:
            assert connection.msgdef.data  # self-contained: nothing comes from a ROS install
            store.register(get_types_from_msg(connection.msgdef.data, connection.msgtype))
        assert {c.topic: c.msgtype for c in reader.connections} == {
            EVENTS_TOPIC: FAULT_EVENT_TYPE,
            TRANSITIONS_TOPIC: TRANSITION_TYPE,
        }
        for connection, t_ns, raw in reader.messages():
            message = store.deserialize_cdr(raw, connection.msgtype)
            out.setdefault(connection.topic, []).append((t_ns, message))
    return out


def ns(stamp: Any) -> int:  # a decoded builtin_interfaces/msg/Time
    return int(stamp.sec) * SEC + int(stamp.nanosec)


def test_read_back_with_rosbags(result: Result, tmp_path: Path) -> None:
    path = tmp_path / "replayed.mcap"
    write_mcap(result, path)
    messages = rosbags_messages(path)
    events = messages[EVENTS_TOPIC]
    assert len(events) == len(result.events)
    decoded = [(t, m.event_type, m.fault.fault_code, m.fault.status) for t, m in events]
    assert decoded == expected_events(result)
    for (t_ns, message), event in zip(events, result.events, strict=True):
        assert ns(message.timestamp) == t_ns == event.t_ns
        fault = event.fault
        assert ns(message.fault.first_occurred) == fault.first_occurred_ns
        assert ns(message.fault.last_occurred) == fault.last_occurred_ns
        assert ns(message.fault.last_passed) == fault.last_passed_ns
        assert message.fault.severity == fault.severity
        assert message.fault.description == fault.description
        assert message.fault.occurrence_count == fault.occurrence_count
        assert list(message.fault.reporting_sources) == list(fault.reporting_sources)
        assert list(message.auto_cleared_codes) == list(event.auto_cleared_codes)
    cleared = [m for _, m in events if m.event_type == "fault_cleared" and m.auto_cleared_codes]
    assert [list(m.auto_cleared_codes) for m in cleared] == [["WHEEL_SLIP"]]
    assert ns(cleared[0].timestamp) == T0 + 10 * SEC + SUB
    transitions = [
        (t, m.fault_code, m.from_status, m.to_status, m.cause, m.source_id)
        for t, m in messages[TRANSITIONS_TOPIC]
    ]
    assert transitions == expected_transitions(result)
    assert all(ns(m.stamp) == t for t, m in messages[TRANSITIONS_TOPIC])
    assert ("", "CONFIRMED", "report", "/drive/left") in [x[2:] for x in transitions]


def test_medkit_replay_reads_it_back_as_the_live_manager_events(
    result: Result, tmp_path: Path
) -> None:
    script, config = correlated(tmp_path)
    path = tmp_path / "replayed.mcap"
    write_mcap(result, path)
    again = replay([script, path], [config])  # the script beside "its recording"
    assert again.parity is not None
    assert again.parity["verdict"] == "match"
    assert again.parity["matched"] == len(result.events)
    assert again.parity["max_abs_time_offset_ns"] == 0


def test_same_result_same_bytes(result: Result, tmp_path: Path) -> None:
    write_mcap(result, tmp_path / "a.mcap")
    write_mcap(result, tmp_path / "b.mcap")
    assert (tmp_path / "a.mcap").read_bytes() == (tmp_path / "b.mcap").read_bytes()


def test_a_replay_without_events_gives_a_valid_empty_file(tmp_path: Path) -> None:
    script = write_script(tmp_path / "e.jsonl", [report(T0, "bad code!")])
    path = tmp_path / "empty.mcap"
    assert write_mcap(replay([script]), path) == {EVENTS_TOPIC: 0, TRANSITIONS_TOPIC: 0}
    assert rosbags_messages(path) == {}
    with path.open("rb") as stream:
        assert list(make_reader(stream).iter_messages()) == []


def test_cli_mcap(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    script, config = correlated(tmp_path)
    path = tmp_path / "out.mcap"
    status = main(["analyze", str(script), "--config", str(config), "--mcap", str(path), "--quiet"])
    assert status == 0 and capsys.readouterr() == ("", "")
    assert sum(len(v) for v in rosbags_messages(path).values()) > 0
    (tmp_path / "plain").write_text("a file where a folder would be\n")
    # A missing folder is made (as for --csv); a file in its place cannot be.
    status = main(["analyze", str(script), "--mcap", str(tmp_path / "plain" / "x.mcap")])
    _, err = capsys.readouterr()
    assert status == 2 and err.startswith("medkit-replay: error: ") and "cannot write MCAP" in err
