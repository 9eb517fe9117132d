"""open_recording on bags built in tmp_path: roles, storages, compression, merging, errors.

Every bag is written with rosbags' Writer by tests/inputs/builders.py.
"""

from __future__ import annotations

import shutil
import sqlite3
import tracemalloc
from contextlib import closing
from typing import TYPE_CHECKING, Any
from unittest.mock import patch

import pytest
import yaml

from medkit_replay.errors import InputError
from medkit_replay.inputs import READERS, Message, open_recording
from tests.inputs.builders import (
    Rec,
    clear_fault,
    diag,
    fault_event,
    goal_status,
    log,
    report_fault,
    set_metadata,
    storage_file,
    string_msg,
    write_bag,
    write_bare,
)

if TYPE_CHECKING:
    from collections.abc import Iterator, Sequence
    from pathlib import Path

    from medkit_replay.inputs import Input
    from medkit_replay.model import InputSummary


def traffic() -> list[Rec]:
    return [
        diag(1_000, "motor temp", 1),
        goal_status(1_500, 6),
        report_fault(2_000),
        string_msg(2_100),
        clear_fault(2_500),
        fault_event(3_000),
        log(3_500),
        diag(4_000, "battery", 0),
    ]


def read(
    paths: Sequence[Path], **options: Any
) -> tuple[list[Message], list[InputSummary], list[str]]:
    with open_recording(paths, **options) as recording:
        messages = list(recording.messages())
        return messages, list(recording.inputs), list(recording.warnings)


def shape(messages: list[Message]) -> list[tuple[int, int, str, str]]:
    return [(m.t_ns, m.input_index, m.topic, m.role) for m in messages]


EXPECTED = [
    (1_000, 0, "/diagnostics", "diagnostics"),
    (1_500, 0, "/navigate/_action/status", "action_status"),
    (2_000, 0, "/fault_manager/report_fault/_service_event", "report_fault"),
    (2_500, 0, "/fault_manager/clear_fault/_service_event", "clear_fault"),
    (3_000, 0, "/fault_manager/events", "fault_events"),
    (3_500, 0, "/rosout", "rosout"),
    (4_000, 0, "/diagnostics", "diagnostics"),
]

VARIANTS = [
    ("mcap", "none"),
    ("mcap", "chunk"),
    ("mcap", "file"),
    ("mcap", "message"),
    ("sqlite3", "none"),
    ("sqlite3", "file"),
    ("sqlite3", "message"),
]


@pytest.mark.parametrize("definitions", [True, False], ids=["recorded-defs", "bundled-defs"])
@pytest.mark.parametrize(("storage", "compression"), VARIANTS)
def test_every_role_from_every_storage(
    tmp_path: Path, storage: str, compression: str, definitions: bool
) -> None:
    bag = write_bag(
        tmp_path / "bag",
        traffic(),
        storage=storage,  # type: ignore[arg-type]
        compression=compression,  # type: ignore[arg-type]
        definitions=definitions,
        chunk_every=2,
    )
    messages, (summary,), warnings = read([bag], rosout=True)
    assert shape(messages) == EXPECTED
    assert warnings == []
    by_role = {m.role: m.msg for m in messages}
    assert by_role["report_fault"].request[0].fault_code == "MOTOR_HOT"  # type: ignore[attr-defined]
    assert by_role["clear_fault"].request[0].skip_correlation_auto_clear is False  # type: ignore[attr-defined]
    assert by_role["fault_events"].fault.reporting_sources == ["/motor"]  # type: ignore[attr-defined]
    assert by_role["action_status"].status_list[0].status == 6  # type: ignore[attr-defined]
    assert messages[0].msg.status[0].name == "motor temp"  # type: ignore[attr-defined]
    assert (summary.storage, summary.start_ns, summary.end_ns) == (storage, 1_000, 4_000)
    assert summary.message_count == 8
    topics = {t.topic: (t.type, t.role, t.messages) for t in summary.topics}
    assert topics["/chatter"] == ("std_msgs/msg/String", None, 1)
    assert topics["/diagnostics"] == ("diagnostic_msgs/msg/DiagnosticArray", "diagnostics", 2)


@pytest.mark.parametrize("suffix", [".mcap", ".db3"])
def test_bare_storage_files(tmp_path: Path, suffix: str) -> None:
    path = write_bare(tmp_path / f"download{suffix}", traffic())
    messages, (summary,), warnings = read([path], rosout=True)
    assert shape(messages) == EXPECTED
    assert summary.path == str(path)
    assert warnings == []


def test_rosout_and_diagnostics_topics_are_options(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "bag", [diag(1), log(2), diag(3)])
    messages, _, _ = read([bag])
    assert [m.role for m in messages] == ["diagnostics", "diagnostics"]
    messages, _, _ = read([bag], diagnostics_topics=["/diag_other"])
    assert messages == []


def test_inputs_merge_by_time_then_input_then_position(tmp_path: Path) -> None:
    first = write_bag(tmp_path / "a", [diag(10, "a1"), diag(20, "a2"), diag(20, "a3")])
    second = write_bag(
        tmp_path / "b", [diag(5, "b0"), diag(20, "b1"), diag(30, "b2")], storage="sqlite3"
    )
    messages, summaries, _ = read([first, second])
    names = [m.msg.status[0].name for m in messages]  # type: ignore[attr-defined]
    assert names == ["b0", "a1", "a2", "a3", "b1", "b2"]
    assert [m.input_index for m in messages] == [1, 0, 0, 0, 1, 1]
    assert [s.storage for s in summaries] == ["mcap", "sqlite3"]
    again, _, _ = read([first, second])
    assert shape(again) == shape(messages)


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_ties_in_one_file_keep_stored_order(tmp_path: Path, storage: str) -> None:
    recs = [diag(7, f"n{i}") for i in range(5)] + [diag(3, "early")]
    bag = write_bag(tmp_path / "bag", recs, storage=storage, chunk_every=2)  # type: ignore[arg-type]
    messages, _, _ = read([bag])
    names = [m.msg.status[0].name for m in messages]  # type: ignore[attr-defined]
    assert names == ["early", "n0", "n1", "n2", "n3", "n4"]


def split_bag(tmp_path: Path, parts: list[list[Rec]], storage: str = "mcap") -> Path:
    """A directory with one storage file per part and a metadata.yaml listing them in order."""
    bag = tmp_path / "split"
    bag.mkdir()
    files = []
    for index, recs in enumerate(parts):
        part = write_bag(tmp_path / f"part{index}", recs, storage=storage, chunk_every=3)  # type: ignore[arg-type]
        source = storage_file(part)
        target = bag / f"split_{index}{source.suffix}"
        shutil.move(source, target)
        start = min(r.t_ns for r in recs)
        files.append({"path": target.name, "starting_time": {"nanoseconds_since_epoch": start}})
    info = {
        "version": 9,
        "storage_identifier": storage,
        "relative_file_paths": [f["path"] for f in files],
        "files": files,
        "compression_format": "",
        "compression_mode": "",
    }
    (bag / "metadata.yaml").write_text(yaml.safe_dump({"rosbag2_bagfile_information": info}))
    return bag


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_split_files_that_overlap_are_merged_exactly(tmp_path: Path, storage: str) -> None:
    # A recorder's receive times can jitter across a split: file 1 starts before file 0 ends.
    parts = [[diag(t, f"a{t}") for t in (10, 20, 30, 40)], [diag(t, f"b{t}") for t in (35, 50, 60)]]
    messages, (summary,), warnings = read([split_bag(tmp_path, parts, storage)])
    assert [m.t_ns for m in messages] == [10, 20, 30, 35, 40, 50, 60]
    assert summary.message_count == 7
    assert warnings == []


@pytest.mark.parametrize("version", [1, 4, 5, 6, 7, 8, 9])
def test_metadata_versions(tmp_path: Path, version: int) -> None:
    bag = write_bag(tmp_path / "bag", traffic(), storage="sqlite3")
    name = storage_file(bag).name
    changes: dict[str, object] = {"version": version}
    if version < 4:
        changes["relative_file_paths"] = [f"bag/{name}"]  # older layout names the folder too
    if version < 5:
        changes["files"] = None
    for key, since in (("custom_data", 6), ("ros_distro", 8)):
        if version < since:
            changes[key] = None
    set_metadata(bag, **changes)
    messages, _, warnings = read([bag], rosout=True)
    assert shape(messages) == EXPECTED
    assert warnings == []


def test_newer_metadata_version_is_read_with_a_warning(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "bag", [diag(1)])
    set_metadata(bag, version=10)
    messages, _, warnings = read([bag])
    assert len(messages) == 1
    assert warnings == [
        f"{bag}/metadata.yaml: metadata version 10 is newer than 9, the newest known; read as 9"
    ]


def test_missing_metadata_yaml(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "bag", traffic())
    (bag / "metadata.yaml").unlink()
    messages, _, warnings = read([bag], rosout=True)
    assert shape(messages) == EXPECTED
    assert warnings == [
        f"{bag}: no usable metadata.yaml; reading the storage files in name order: bag.mcap"
    ]


def test_broken_metadata_yaml_falls_back_to_the_files(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "bag", traffic(), storage="sqlite3")
    (bag / "metadata.yaml").write_text("rosbag2_bagfile_information: [unclosed\n")
    messages, _, warnings = read([bag], rosout=True)
    assert shape(messages) == EXPECTED
    assert warnings[0].startswith(f"{bag}/metadata.yaml: cannot be read (")
    assert (
        warnings[1]
        == f"{bag}: no usable metadata.yaml; reading the storage files in name order: bag.db3"
    )


def test_listed_file_missing_and_unlisted_file_present(tmp_path: Path) -> None:
    bag = split_bag(tmp_path, [[diag(1)], [diag(2)], [diag(3)]])
    (bag / "split_1.mcap").unlink()
    set_metadata(bag, relative_file_paths=["split_0.mcap", "split_1.mcap"], files=None)
    messages, _, warnings = read([bag])
    assert [m.t_ns for m in messages] == [1, 3]
    assert warnings == [
        f"{bag}/split_1.mcap: listed in metadata.yaml but missing; how much was lost is unknown",
        f"{bag}: split_2.mcap not listed in metadata.yaml; read after the listed files",
    ]


def test_type_mismatch_on_a_known_topic_is_warned(tmp_path: Path) -> None:
    bag = write_bag(
        tmp_path / "bag", [string_msg(1, "/diagnostics"), string_msg(2, "/a/_action/status")]
    )
    messages, _, warnings = read([bag])
    assert messages == []
    assert warnings == [
        f"{bag}: topic /diagnostics has type 'std_msgs/msg/String', not "
        "diagnostic_msgs/msg/DiagnosticArray; not read",
        f"{bag}: topic /a/_action/status has type 'std_msgs/msg/String', not "
        "action_msgs/msg/GoalStatusArray; not read",
    ]


def test_old_type_names_without_definitions_use_bundled_types(tmp_path: Path) -> None:
    bag = write_bag(
        tmp_path / "bag", [diag(1), goal_status(2, 4)], storage="sqlite3", definitions=False
    )
    with closing(sqlite3.connect(storage_file(bag))) as db:
        db.execute("UPDATE topics SET type = replace(type, '/msg/', '/')")
        db.execute("DELETE FROM message_definitions")
        db.commit()
    messages, (summary,), warnings = read([bag])
    assert [(m.msgtype, m.role) for m in messages] == [
        ("diagnostic_msgs/msg/DiagnosticArray", "diagnostics"),
        ("action_msgs/msg/GoalStatusArray", "action_status"),
    ]
    assert warnings == []
    assert {t.type for t in summary.topics} == {m.msgtype for m in messages}


def test_input_errors_are_one_line_with_the_path(tmp_path: Path) -> None:
    (tmp_path / "notes.txt").write_text("hello")
    (tmp_path / "empty").mkdir()
    (tmp_path / "junk.mcap").write_bytes(b"\x00" * 100)
    (tmp_path / "junk.db3").write_text("SQLite? no")
    cases = {
        tmp_path / "missing.mcap": "input not found",
        tmp_path / "notes.txt": (
            "unsupported input (expected a rosbag2 directory or a .bag, .db3, .jsonl, .mcap file)"
        ),
        tmp_path / "empty": "no metadata.yaml and no .mcap or .db3 file in it",
        tmp_path / "junk.mcap": "not an MCAP file (bad magic)",
        tmp_path / "junk.db3": "not an SQLite database",
    }
    for path, problem in cases.items():
        with pytest.raises(InputError) as info:
            open_recording([path])
        assert str(info.value) == f"{path}: {problem}"
    with pytest.raises(InputError, match=r"^no input given$"):
        open_recording([])


def test_a_failing_input_closes_the_ones_opened_before(tmp_path: Path) -> None:
    closed: list[str] = []

    class Fake:
        def messages(self) -> Iterator[Any]:
            return iter(())

        def summary(self) -> Any:
            return None

        def close(self) -> None:
            closed.append("fake")

    def fake_opener(path: Path, ctx: Any) -> Input:
        return Fake()

    def failing(path: Path, ctx: Any) -> Input:
        raise InputError("broken", path=str(path))

    (tmp_path / "a.fake").write_text("")
    (tmp_path / "b.bad").write_text("")
    with patch.dict(READERS, {".fake": fake_opener, ".bad": failing}), pytest.raises(InputError):
        open_recording([tmp_path / "a.fake", tmp_path / "b.bad"])
    assert closed == ["fake"]


def test_messages_can_be_read_once(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "bag", [diag(1)])
    with open_recording([bag]) as recording:
        assert len(list(recording.messages())) == 1
        with pytest.raises(RuntimeError, match="only once"):
            recording.messages()


def test_unselected_topics_are_never_decoded(tmp_path: Path) -> None:
    bag = write_bag(
        tmp_path / "bag", [string_msg(t) for t in range(50)] + [diag(60)], chunk_every=10
    )
    with patch("medkit_replay.inputs.typestore.Decoder.decode", autospec=True) as decode:
        decode.return_value = "decoded"
        messages, (summary,), _ = read([bag])
    assert [m.msg for m in messages] == ["decoded"]
    assert decode.call_count == 1
    assert {t.topic: t.messages for t in summary.topics} == {"/chatter": 50, "/diagnostics": 1}


def _peak_bytes(bag: Path) -> int:
    tracemalloc.start()
    try:
        with open_recording([bag]) as recording:
            count = sum(1 for _ in recording.messages())
        return tracemalloc.get_traced_memory()[1] if count else 0
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_memory_does_not_grow_with_recording_size(tmp_path: Path, storage: str) -> None:
    text = "x" * 2000

    def recs(n: int) -> Iterator[Rec]:
        return (diag(t, "motor", 1, text) for t in range(n))

    small = write_bag(tmp_path / "small", recs(500), storage=storage, chunk_every=100)  # type: ignore[arg-type]
    large = write_bag(tmp_path / "large", recs(4000), storage=storage, chunk_every=100)  # type: ignore[arg-type]
    assert storage_file(large).stat().st_size > 8_000_000
    assert _peak_bytes(large) < 2 * _peak_bytes(small) + 1_000_000


def test_chunks_without_selected_topics_are_never_read(tmp_path: Path) -> None:
    # Damage a chunk holding only /chatter: with an intact index it is skipped, so nobody notices.
    recs = [string_msg(t) for t in range(5)] + [diag(10 + t) for t in range(5)]
    bag = write_bag(tmp_path / "bag", recs, compression="chunk", chunk_every=5)
    path = storage_file(bag)
    data = bytearray(path.read_bytes())
    first_chunk = data.index(b"\x06", 8 + 9 + int.from_bytes(data[9:17], "little"))
    data[first_chunk + 80] ^= 0xFF
    path.write_bytes(bytes(data))
    messages, (summary,), warnings = read([bag])
    assert [m.t_ns for m in messages] == [10, 11, 12, 13, 14]
    assert warnings == []
    assert {t.topic: t.messages for t in summary.topics} == {"/chatter": 5, "/diagnostics": 5}
    messages, _, warnings = read([bag], extra_topics=["/chatter"])
    assert len(messages) == 5
    assert "cannot be decompressed" in warnings[0]
