"""Every copied rosbag2 fixture (real recordings by the rosbag2 project) reads without a traceback.

Reads tests/fixtures/rosbag2 only; see its NOTICE.md for their origin and licence.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

from medkit_replay.inputs import Message, open_recording

if TYPE_CHECKING:
    from medkit_replay.model import InputSummary

FIXTURES = Path(__file__).parents[1] / "fixtures" / "rosbag2"
ALL = sorted(p for p in FIXTURES.iterdir() if p.is_dir()) + sorted(
    (FIXTURES / "bare_files").iterdir()
)


def read(path: Path, **options: Any) -> tuple[list[Message], InputSummary, list[str]]:
    with open_recording([path], **options) as recording:
        messages = list(recording.messages())
        return messages, recording.inputs[0], list(recording.warnings)


def counts(summary: InputSummary) -> dict[str, int]:
    return {t.topic: t.messages for t in summary.topics}


@pytest.mark.parametrize("path", ALL, ids=lambda p: p.name)
def test_every_fixture_reads_in_time_order(path: Path) -> None:
    messages, summary, _ = read(path, rosout=True)
    assert [m.t_ns for m in messages] == sorted(m.t_ns for m in messages)
    assert {m.role for m in messages} <= {"rosout"}
    assert summary.message_count == sum(counts(summary).values())


@pytest.mark.parametrize("name", ["talker_mcap", "talker_sqlite3"])
def test_real_rosout(name: str) -> None:
    messages, summary, warnings = read(FIXTURES / name, rosout=True)
    assert len(messages) == 10
    first = messages[0]
    assert (first.topic, first.msgtype, first.role) == (
        "/rosout",
        "rcl_interfaces/msg/Log",
        "rosout",
    )
    assert first.msg.name == "minimal_publisher"  # type: ignore[attr-defined]
    assert first.msg.level == 20  # type: ignore[attr-defined]
    assert first.msg.msg.startswith("Publishing: ")  # type: ignore[attr-defined]
    assert summary.storage == name.removeprefix("talker_")
    assert (summary.start_ns, summary.message_count) == (1585866235112411371, 20)
    assert counts(summary) == {"/parameter_events": 0, "/rosout": 10, "/topic": 10}
    roles = {t.topic: t.role for t in summary.topics}
    assert roles == {"/parameter_events": None, "/rosout": "rosout", "/topic": None}
    if name == "talker_sqlite3":  # its message_definitions table holds one-line stubs
        assert warnings == [
            f"{FIXTURES / name}: /rosout: recorded definition does not fit the data; "
            "used the bundled definition"
        ]
    else:
        assert warnings == []


def test_both_talker_storages_hold_the_same_messages() -> None:
    mcap, _, _ = read(FIXTURES / "talker_mcap", rosout=True)
    sqlite, _, _ = read(FIXTURES / "talker_sqlite3", rosout=True)
    assert [(m.t_ns, m.msg.msg) for m in mcap] == [(m.t_ns, m.msg.msg) for m in sqlite]  # type: ignore[attr-defined]


@pytest.mark.parametrize("name", ["service_events_mcap", "service_events_sqlite3"])
def test_recorded_service_events(name: str) -> None:
    topic = "/test_service1/_service_event"
    messages, summary, warnings = read(FIXTURES / name, extra_topics=[topic])
    assert [m.msgtype for m in messages] == ["test_msgs/srv/BasicTypes_Event"] * 4
    kinds = [m.msg.info.event_type for m in messages]  # type: ignore[attr-defined]
    assert kinds == [0, 3, 0, 3]  # two client-side calls: REQUEST_SENT, RESPONSE_RECEIVED
    assert [len(m.msg.request) for m in messages] == [1, 0, 1, 0]  # type: ignore[attr-defined]
    assert [len(m.msg.response) for m in messages] == [0, 1, 0, 1]  # type: ignore[attr-defined]
    assert counts(summary)[topic] == 4
    assert summary.message_count == 10
    assert warnings == []


@pytest.mark.parametrize(
    "name", ["only_services.mcap", "topics_and_services.mcap", "topics_and_services.db3"]
)
def test_bare_files_with_srv_text_schemas(name: str) -> None:
    topic = "/add_two_ints/_service_event"
    messages, summary, _ = read(FIXTURES / "bare_files" / name, extra_topics=[topic])
    requests = [m.msg.request[0] for m in messages if m.msg.request]  # type: ignore[attr-defined]
    responses = [m.msg.response[0] for m in messages if m.msg.response]  # type: ignore[attr-defined]
    assert requests
    assert len(requests) == len(responses)
    assert [r.a + r.b for r in requests] == [r.sum for r in responses]
    assert summary.storage == ("sqlite3" if name.endswith(".db3") else "mcap")
    assert summary.path == str(FIXTURES / "bare_files" / name)


def test_empty_bag() -> None:
    messages, summary, warnings = read(FIXTURES / "empty_bag", rosout=True)
    assert messages == []
    assert (summary.start_ns, summary.end_ns, summary.message_count) == (None, None, 0)
    assert counts(summary) == {"/parameter_events": 0, "/rosout": 0}
    assert warnings == []


def test_split_bag_reads_five_files_in_order() -> None:
    messages, summary, _ = read(FIXTURES / "split_bag_mcap", extra_topics=["AAA", "HHH"])
    assert len(messages) == 804 + 726
    assert [m.t_ns for m in messages] == sorted(m.t_ns for m in messages)
    assert summary.message_count == 6074
    assert counts(summary)["EEE"] == 804


def test_storage_files_without_metadata() -> None:
    messages, summary, warnings = read(FIXTURES / "no_metadata_mcap", extra_topics=["/chatter"])
    assert len(messages) == summary.message_count == 1324 + 1324 + 529
    assert {m.msg.data for m in messages} == {"test"}  # type: ignore[attr-defined]
    assert warnings == [
        f"{FIXTURES / 'no_metadata_mcap'}: no usable metadata.yaml; reading the storage files in "
        "name order: multiple_files_0.mcap, multiple_files_1.mcap, multiple_files_2.mcap"
    ]


def test_unknown_serialization_format_is_skipped_with_a_warning() -> None:
    path = FIXTURES / "wrong_serialization_mcap"
    messages, summary, warnings = read(path, extra_topics=["/test_topic", "/array_topic"])
    assert messages == []
    assert counts(summary) == {"/array_topic": 4, "/test_topic": 3}
    assert sorted(warnings) == [
        f"{path}: topic {topic} is serialized as 'wrong_format', not CDR; not read"
        for topic in ("/array_topic", "/test_topic")
    ]


def test_old_type_names() -> None:
    messages, summary, _ = read(FIXTURES / "old_type_names_mcap", extra_topics=["topic1"])
    assert [m.msgtype for m in messages] == ["test_msgs/msg/BasicTypes"] * 5
    assert [m.msg.int32_value for m in messages] == [1, 2, 3, 4, 5]  # type: ignore[attr-defined]
    path = FIXTURES / "old_type_names_sqlite3"
    messages, summary, warnings = read(path, extra_topics=["topic1"])
    # no definition stored and test_msgs is not bundled: said, not guessed
    assert messages == []
    assert summary.topics[0].type == "test_msgs/msg/BasicTypes"
    assert warnings == [
        f"{path}: topic topic1 cannot be decoded: no usable definition of "
        "test_msgs/msg/BasicTypes; not read"
    ]


def test_arrays_and_bounded_types() -> None:
    path = FIXTURES / "cdr_test_mcap"
    messages, _, warnings = read(path, extra_topics=["/test_topic", "/array_topic"])
    assert len(messages) == 7
    arrays = [m.msg for m in messages if m.topic == "/array_topic"]
    assert [len(a.float64_values) for a in arrays] == [3] * 4  # type: ignore[attr-defined]
    assert warnings == []
