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

from tests.inputs.builders import diag, storage_file, write_bag
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
    assert f"{db}: 2 message rows without a binary payload skipped (ids 2, 4)" in warnings_of(
        report
    )
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
        f"{db}: 2 message rows skipped: not an integer log time in [0, 2^63) (ids 1, 3)"
        in warnings_of(report)
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
