"""Red team: hostile sqlite3 bags and metadata.yaml, through the real command line.

Huge or generated blobs, untyped rows, duplicate topic ids, duplicate and escaping file names:
each run is bounded, warns naming the file and what was lost, and reports the rest.
"""

from __future__ import annotations

import json
import sqlite3
from contextlib import closing
from typing import TYPE_CHECKING

import pytest

from tests.inputs.builders import diag, log, set_metadata, storage_file, write_bag
from tests.redteam.support import run_limited

if TYPE_CHECKING:
    from pathlib import Path

    from tests.redteam.support import Outcome

SECOND = 1_000_000_000
MEMORY = 1024 * 1024 * 1024


def analyze(tmp_path: Path, *inputs: Path) -> tuple[Outcome, dict[str, object]]:
    """Run analyze under limits; expect success; return the outcome and the JSON report."""
    report = tmp_path / "report.json"
    outcome = run_limited(
        ["analyze", *inputs, "--json", report, "--quiet"], memory=MEMORY, cpu_seconds=30
    )
    assert outcome.status == 0, outcome.stderr[-2000:]
    assert "Traceback" not in outcome.stderr
    return outcome, json.loads(report.read_text())


def warnings_of(report: dict[str, object]) -> list[str]:
    warnings = report["warnings"]
    assert isinstance(warnings, list)
    return [str(w) for w in warnings]


def messages_read(report: dict[str, object]) -> int:
    summary = report["summary"]
    assert isinstance(summary, dict)
    return int(summary["messages_read"])


def sqlite_bag(tmp_path: Path, count: int = 3) -> tuple[Path, Path]:
    bag = write_bag(
        tmp_path / "bag", [diag((k + 1) * SECOND) for k in range(count)], storage="sqlite3"
    )
    return bag, storage_file(bag)


def rebuild_messages(db: Path, data_column: str, timestamp: str = "timestamp INTEGER") -> None:
    """Replace the messages table by one whose ``data`` column is given (e.g. generated)."""
    with closing(sqlite3.connect(db)) as connection:
        connection.executescript(
            f"""
            ALTER TABLE messages RENAME TO old;
            CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER, {timestamp},
                                  real BLOB, {data_column});
            INSERT INTO messages(id, topic_id, timestamp, real)
                SELECT id, topic_id, timestamp, data FROM old;
            DROP TABLE old;
            CREATE INDEX timestamp_idx ON messages (timestamp ASC);
            """
        )
        connection.commit()


# --- item 1: a row may not make us allocate without bound -----------------------------


def test_generated_gigabyte_blob_in_one_row_is_skipped_and_named(tmp_path: Path) -> None:
    bag, db = sqlite_bag(tmp_path)
    rebuild_messages(
        db,
        "data BLOB GENERATED ALWAYS AS "
        "(CASE WHEN id = 2 THEN zeroblob(id * 450000000) ELSE real END) VIRTUAL",
    )
    outcome, report = analyze(tmp_path, bag)
    assert f"{db}: 1 message row with a payload that cannot be loaded within the " in "\n".join(
        warnings_of(report)
    )
    assert "(id 2)" in "\n".join(warnings_of(report))
    assert messages_read(report) == 2
    assert outcome.peak_rss_kib < 400 * 1024


def test_constant_generated_blob_loses_the_rows_with_a_warning(tmp_path: Path) -> None:
    """SQLite builds a constant expression once per query: then no row can be loaded."""
    bag, db = sqlite_bag(tmp_path)
    rebuild_messages(db, "data BLOB GENERATED ALWAYS AS (zeroblob(900000000)) VIRTUAL")
    outcome, report = analyze(tmp_path, bag)
    text = "\n".join(warnings_of(report))
    assert f"{db}: 3 message rows with a payload that cannot be loaded" in text
    assert messages_read(report) == 0
    assert outcome.peak_rss_kib < 400 * 1024


# --- items 2 and 3: rows without a blob or an integer time are named ---------------------


def test_rows_without_blob_data_are_counted_and_named(tmp_path: Path) -> None:
    bag, db = sqlite_bag(tmp_path, count=5)
    with closing(sqlite3.connect(db)) as connection:
        connection.execute("PRAGMA ignore_check_constraints = ON")
        rebuild_messages(db, "data BLOB")
        connection.execute("UPDATE messages SET data = real")
        connection.execute("UPDATE messages SET data = NULL WHERE id = 2")
        connection.execute("UPDATE messages SET data = 'text' WHERE id = 4")
        connection.commit()
    _, report = analyze(tmp_path, bag)
    assert (
        f"{db}: 2 message rows without a binary payload (ids 2, 4); 2 messages (size unknown) "
        "at unknown bag times skipped"
    ) in warnings_of(report)
    assert messages_read(report) == 3


@pytest.mark.parametrize(
    ("value", "shown"),
    [("'abc'", "abc"), ("1e999", "Infinity"), ("2.5", "2.5"), ("NULL", None), ("-5", "-5")],
)
def test_timestamps_that_are_not_integers_in_range_are_skipped(
    tmp_path: Path, value: str, shown: str | None
) -> None:
    bag, db = sqlite_bag(tmp_path, count=4)
    rebuild_messages(db, "data BLOB", timestamp="timestamp")
    with closing(sqlite3.connect(db)) as connection:
        connection.execute("UPDATE messages SET data = real")
        connection.execute(f"UPDATE messages SET timestamp = {value} WHERE id IN (1, 3)")
        connection.commit()
    _, report = analyze(tmp_path, bag)
    assert (
        f"{db}: 2 message rows: not an integer log time in [0, 2^63) (ids 1, 3); "
        "2 messages (size unknown) at unknown bag times skipped" in warnings_of(report)
    )
    assert messages_read(report) == 2
    text = json.dumps(report)
    if shown is not None:
        assert shown not in text.replace(str(bag), "")
    inputs = report["inputs"]
    assert isinstance(inputs, list)
    assert inputs[0]["start_ns"] == 2 * SECOND
    assert inputs[0]["end_ns"] == 4 * SECOND


# --- item 4: a topic id declared twice ------------------------------------------------


def test_duplicate_topic_id_is_named_and_the_first_declared_wins(tmp_path: Path) -> None:
    bag, db = sqlite_bag(tmp_path)
    with closing(sqlite3.connect(db)) as connection:
        connection.executescript(
            """
            ALTER TABLE topics RENAME TO old;
            CREATE TABLE topics(id INTEGER, name TEXT, type TEXT, serialization_format TEXT,
                                offered_qos_profiles TEXT, type_description_hash TEXT);
            INSERT INTO topics SELECT * FROM old;
            INSERT INTO topics VALUES (1, '/chatter', 'std_msgs/msg/String', 'cdr', '', '');
            DROP TABLE old;
            """
        )
        connection.commit()
    _, report = analyze(tmp_path, bag)
    assert (
        f"{db}: topic id 1 is declared twice (/diagnostics of type "
        "diagnostic_msgs/msg/DiagnosticArray, then /chatter of type std_msgs/msg/String); "
        "its messages cannot be told apart and are read as /diagnostics, the first declared"
    ) in warnings_of(report)
    assert messages_read(report) == 3


# --- item 5: metadata.yaml ------------------------------------------------------------


def mcap_bag(tmp_path: Path, count: int = 3) -> tuple[Path, Path]:
    bag = write_bag(tmp_path / "bag", [diag((k + 1) * SECOND) for k in range(count)])
    return bag, storage_file(bag)


def test_a_file_listed_three_ways_is_read_once(tmp_path: Path) -> None:
    bag, _ = mcap_bag(tmp_path)
    names = ["bag.mcap", "./bag.mcap", "old/../bag.mcap"]
    set_metadata(bag, relative_file_paths=names, files=[{"path": n} for n in names])
    _, report = analyze(tmp_path, bag)
    assert messages_read(report) == 3
    shown = "'bag.mcap', './bag.mcap', 'old/../bag.mcap'"
    for key in ("relative_file_paths", "files"):
        assert (
            f"{bag / 'metadata.yaml'}: {key} names bag.mcap more than once ({shown}); read once"
            in warnings_of(report)
        )


@pytest.mark.parametrize(
    ("changes", "warning"),
    [
        ({"files": [{"path": "bag.mcap", "starting_time": [1]}]}, None),
        ({"files": [1, None, {"path": 5}], "relative_file_paths": None}, "no storage file"),
        ({"files": 1, "relative_file_paths": "bag.mcap"}, "files is not a list; ignored"),
        ({"relative_file_paths": ["../../elsewhere/bag.mcap"], "files": None}, "points outside"),
        ({"storage_identifier": [1], "compression_mode": {"a": 1}}, None),
        ({"version": int("9" * 4000)}, "metadata version far is newer than 9"),
    ],
)
def test_metadata_with_wrong_types_is_read_leniently(
    tmp_path: Path, changes: dict[str, object], warning: str | None
) -> None:
    bag, _ = mcap_bag(tmp_path)
    set_metadata(bag, **changes)
    outcome, report = analyze(tmp_path, bag)
    assert "internal error" not in outcome.stderr
    assert messages_read(report) == 3
    if warning == "no storage file":
        assert f"{bag}: bag.mcap not listed in metadata.yaml" in "\n".join(warnings_of(report))
    elif warning is not None:
        assert warning in "\n".join(warnings_of(report))


def test_a_version_of_five_thousand_digits_is_a_warning(tmp_path: Path) -> None:
    bag, _ = mcap_bag(tmp_path)
    path = bag / "metadata.yaml"
    path.write_text(path.read_text().replace("version: 9", "version: " + "7" * 5000))
    _, report = analyze(tmp_path, bag)
    assert messages_read(report) == 3
    assert any(
        w.startswith(f"{path}: cannot be read (") and "digits" in w for w in warnings_of(report)
    )


def test_metadata_alias_bomb_is_refused_with_a_warning(tmp_path: Path) -> None:
    bag, _ = mcap_bag(tmp_path)
    levels = ["a0: &a0 [bag.mcap, bag.mcap, bag.mcap, bag.mcap, bag.mcap, bag.mcap]"]
    levels += [f"a{k}: &a{k} [{', '.join([f'*a{k - 1}'] * 9)}]" for k in range(1, 9)]
    path = bag / "metadata.yaml"
    path.write_text(
        "\n".join(levels) + "\nrosbag2_bagfile_information:\n  relative_file_paths: *a8\n"
    )
    outcome, report = analyze(tmp_path, bag)
    assert messages_read(report) == 3
    assert f"{path}: cannot be read (the YAML expands to more than" in "\n".join(
        warnings_of(report)
    )
    assert outcome.peak_rss_kib < 300 * 1024


# --- item 9: a bag of /rosout alone -----------------------------------------------------


def test_rosout_alone_says_the_log_bridge_would_read_it(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "bag", [log(k * SECOND) for k in range(1, 4)])
    _, report = analyze(tmp_path, bag)
    assert (
        "no topic the replay reads was found (action status, /diagnostics, ReportFault/"
        "ClearFault service events, fault manager events); the report is empty; /rosout holds "
        "3 log message(s), which the log bridge would read, but it is off (add a log_bridge "
        "section to the config, or set medkit_replay: {enable_log_bridge: true})"
    ) in warnings_of(report)
