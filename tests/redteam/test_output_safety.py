"""Red team, output writers: hostile text and out-of-range values in every file we write.

Each run is the real command line in a child process under rlimits (``run_limited``): a full disk
is RLIMIT_FSIZE, a page that grows with string lengths is caught by its size and the memory bound.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import re
import shutil
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import pyarrow.parquet as pq
import pytest
from mcap.reader import make_reader

from medkit_replay.outputs import terminal
from medkit_replay.outputs.csv_safety import neutralise
from medkit_replay.outputs.html import write_html
from medkit_replay.outputs.mcap_events import (
    SEC_MAX,
    SEC_MIN,
    message_store,
    time_fields,
    write_mcap,
)
from medkit_replay.outputs.parquet import INT64_MAX, INT64_MIN, clamped, write_parquet
from medkit_replay.outputs.tables import write_csv
from medkit_replay.pipeline import replay
from medkit_replay.text import clip
from tests.checks.support import write_budget
from tests.inputs.builders import diag, write_bag, write_bare
from tests.outputs.scripts import clear, report, write_script
from tests.redteam.support import MIB, assert_one_line_error, run_limited

if TYPE_CHECKING:
    from pathlib import Path

SEC = 1_000_000_000
DANGEROUS = "\u202a\u202b\u202c\u202d\u202e\u2066\u2067\u2068\u2069\u200e\u200f\u061c\u2028\u2029"
"""Bidirectional controls, the Arabic letter mark, line and paragraph separators."""
OUTPUT_FLAGS = {"--csv": "csv", "--parquet": "parquet", "--mcap": "e.mcap", "--html": "r.html"}


def strict_json(text: str) -> object:
    """JSON as RFC 8259 has it: NaN, Infinity and -Infinity are refused."""

    def refuse(constant: str) -> object:
        raise AssertionError(f"{constant} in the JSON report")

    return json.loads(text, parse_constant=refuse)


def files_of(target: Path) -> dict[str, bytes]:
    """Every file of an output (one file, or a folder's files) by name."""
    if target.is_dir():
        return {p.name: p.read_bytes() for p in sorted(target.iterdir())}
    return {target.name: target.read_bytes()} if target.exists() else {}


def busy_script(path: Path, faults: int, reports_each: int) -> Path:
    """Many accepted reports with hard-to-compress descriptions: outputs of some 100 KB."""
    lines = []
    t_ns = SEC
    for n in range(reports_each):
        for code in range(faults):
            digest = hashlib.sha256(f"{n}-{code}".encode()).hexdigest()
            event = "PASSED" if n % 4 == 3 else "FAILED"
            lines.append(report(t_ns, f"F{code}", event, description=digest, source=f"/n/{code}"))
            t_ns += 1000
    return write_script(path, lines)


# --- 1. atomic outputs: a full disk leaves old or whole new files, never partial ones -----------


@pytest.fixture(scope="module")
def disk_runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """An old small run's outputs and the outputs a bigger run writes without a size limit."""
    root = tmp_path_factory.mktemp("disk")
    small = busy_script(root / "small.jsonl", 2, 3)
    big = busy_script(root / "big.jsonl", 20, 100)
    folders = {"old": root / "old", "new": root / "new"}
    for name, script in (("old", small), ("new", big)):
        argv: list[str | Path] = ["analyze", script, "--quiet"]
        for flag, leaf in OUTPUT_FLAGS.items():
            argv += [flag, folders[name] / leaf]
        outcome = run_limited(argv, timeout=120)
        assert outcome.status == 0, outcome.stderr
    return {**folders, "big": big}


@pytest.mark.parametrize("flag", list(OUTPUT_FLAGS))
def test_a_full_disk_leaves_no_partial_output(
    flag: str, disk_runs: dict[str, Path], tmp_path: Path
) -> None:
    """Past RLIMIT_FSIZE the write fails with one line; every file at a target is the old one
    or the whole new one (byte for byte), and no temporary file is left beside them."""
    leaf = OUTPUT_FLAGS[flag]
    target = tmp_path / leaf
    source = disk_runs["old"] / leaf
    if source.is_dir():
        shutil.copytree(source, target)
    else:
        shutil.copy2(source, target)
    old, new = files_of(target), files_of(disk_runs["new"] / leaf)
    limit = max(len(data) for data in new.values()) // 2
    changed = {name for name in old if new[name] != old[name]}
    assert limit > 8192 and changed
    outcome = run_limited(
        ["analyze", disk_runs["big"], flag, target, "--quiet"], file_size=limit, timeout=120
    )
    assert_one_line_error(outcome, "cannot write", "File too large", leaf)
    after = files_of(target)
    assert set(after) == set(old)  # nothing beside them, no ".partial" left
    assert all(after[name] in (old[name], new[name]) for name in after)
    assert any(after[name] == old[name] for name in changed)  # the limit did bite


# --- 2, 3. long and bidirectional text: bounded, visible --------------------------------------


def test_megabyte_strings_do_not_grow_the_page(tmp_path: Path) -> None:
    """Descriptions, a rejected code and a source of a few MB each in a small compressed MCAP:
    the page and the summary stay small (cut with an ellipsis), the JSON keeps every byte."""
    big = "\u202e" + "y" * 2_000_000
    records = [diag((n + 1) * SEC, name=f"motor{n % 2}", message=f"{big}{n}") for n in range(6)]
    records.append(diag(7 * SEC, name="m" + big[:5000], message=big))  # rejected: code too long
    bag = write_bag(tmp_path / "bag", records, compression="chunk")
    assert sum(p.stat().st_size for p in bag.iterdir()) < 200_000
    out = tmp_path / "out"
    out.mkdir()
    outcome = run_limited(
        ["analyze", bag, "--html", out / "r.html", "--json", out / "r.json"],
        memory=1024 * MIB,
        cpu_seconds=30,
        env={"COLUMNS": "200"},
    )
    assert outcome.status == 0, outcome.stderr[-2000:]
    page = (out / "r.html").read_text(encoding="utf-8")
    assert len(page) < 300_000, len(page)
    assert "... (+1,999," in page
    assert len(outcome.stdout) < 20_000, len(outcome.stdout)
    report_json = strict_json((out / "r.json").read_text(encoding="utf-8"))
    assert isinstance(report_json, dict)
    assert {len(f["description"]) for f in report_json["faults"]} == {len(big) + 1}


def test_bidirectional_controls_are_visible_in_page_and_summary(tmp_path: Path) -> None:
    """Every reordering character a recording holds is shown as an escape in the HTML (cells,
    tooltips, the page's data) and on the terminal; the JSON keeps the text as it is."""
    hostile = f"a{DANGEROUS}b"
    script = write_script(
        tmp_path / "bidi.jsonl",
        [
            report(SEC, "MOTOR", severity=3, description=hostile, source="/s" + hostile),
            report(2 * SEC, "bad" + hostile, source="/s"),  # rejected: listed in the reports
            clear(3 * SEC, "NOPE" + hostile),
        ],
    )
    out = tmp_path / "out"
    out.mkdir()
    outcome = run_limited(
        ["analyze", script, "--html", out / "r.html", "--json", out / "r.json"], timeout=120
    )
    assert outcome.status == 0, outcome.stderr
    page = (out / "r.html").read_text(encoding="utf-8")
    summary = "".join(line.strip() for line in outcome.stdout.splitlines())  # unfolded
    for char in DANGEROUS:
        assert char not in page, hex(ord(char))
        assert char not in outcome.stdout, hex(ord(char))
        escaped = f"\\u{ord(char):04x}"
        assert escaped in page and escaped in summary, escaped
    assert f'"description":"a{DANGEROUS.encode("unicode_escape").decode()}' not in page
    report_json = strict_json((out / "r.json").read_text(encoding="utf-8"))
    assert isinstance(report_json, dict)
    assert report_json["faults"][0]["description"] == hostile


def test_lone_surrogates_never_stop_a_writer(tmp_path: Path) -> None:
    """Text UTF-8 cannot encode (a lone surrogate a reader let through) is written as its
    escape by every file writer instead of ending the run."""
    script = write_script(
        tmp_path / "s.jsonl", [report(SEC, "MOTOR", severity=3, description="d", source="/s")]
    )
    result = replay([script])
    fault = replace(result.faults[0], description="bad \udcff", reporting_sources=("/\udcff",))
    events = [replace(e, fault=replace(e.fault, description="bad \udcff")) for e in result.events]
    hostile = replace(result, faults=(fault,), events=events)
    write_csv(hostile, tmp_path / "csv")
    write_parquet(hostile, tmp_path / "pq")
    write_mcap(hostile, tmp_path / "e.mcap")
    write_html(hostile, tmp_path / "r.html")
    assert "bad \\udcff" in (tmp_path / "csv" / "faults.csv").read_text(encoding="utf-8")
    assert "bad \\udcff" in (tmp_path / "r.html").read_text(encoding="utf-8")
    faults = pq.read_table(tmp_path / "pq" / "faults.parquet").to_pylist()
    assert faults[0]["reporting_sources"] == ["/\\udcff"]


# --- 4. CSV formulas ----------------------------------------------------------------------------


def test_csv_text_cells_never_start_a_formula(tmp_path: Path) -> None:
    """Codes, descriptions, sources and messages that a spreadsheet would run get a leading
    quote; a negative debounce counter stays the number -1.0; a carriage return never
    ends a row; Parquet keeps the text."""
    script = write_script(
        tmp_path / "f.jsonl",
        [
            report(SEC, "F1", severity=3, description="=HYPERLINK(1)", source="@x"),
            report(2 * SEC, "F2", description="+1+1", source="-s"),
            report(3 * SEC, "=cmd|' /C calc'!A0", source="\tx"),
            clear(4 * SEC, "\rF9"),
        ],
    )
    out = tmp_path / "out"
    out.mkdir()
    outcome = run_limited(
        ["analyze", script, "--csv", out / "csv", "--parquet", out / "pq", "--quiet"],
        timeout=120,
    )
    assert outcome.status == 0, outcome.stderr
    quoted = 0
    for path in sorted((out / "csv").glob("*.csv")):
        with path.open(newline="", encoding="utf-8") as stream:
            for row in csv.DictReader(stream):
                for column, cell in row.items():
                    if cell.startswith("-") and cell.lstrip("-").replace(".", "").isdigit():
                        assert column in {"debounce_counter", "confirmation_threshold"}, cell
                        continue
                    assert not cell.startswith(("=", "+", "-", "@", "\t", "\r")), (path, cell)
                    quoted += cell.startswith("'")
    assert quoted >= 6
    with (out / "csv" / "reports.csv").open(newline="", encoding="utf-8") as stream:
        first = next(csv.DictReader(stream))
    assert first["description"] == "'=HYPERLINK(1)" and first["debounce_counter"] == "-1.0"
    table = pq.read_table(out / "pq" / "reports.parquet").to_pylist()
    assert table[0]["description"] == "=HYPERLINK(1)" and table[1]["source_id"] == "-s"


def test_the_guard_leaves_numbers_alone() -> None:
    assert neutralise(-3) == -3 and neutralise(True) is True and neutralise(None) is None
    assert neutralise("-3") == "'-3" and neutralise("a=b") == "a=b"


# --- 5. times past 2038 and up to 2^63 - 1 --------------------------------------------------------


def test_extreme_times_in_every_output(tmp_path: Path) -> None:
    """Bag times after 2038-01-19 and at 2^63 - 1 ns (the largest a script takes): every output
    is written, exact where its format can hold them; MCAP stamps are saturated, said once."""
    last = 2**63 - 1
    after_2038 = 2_200_000_000 * SEC
    script = write_script(
        tmp_path / "t.jsonl",
        [
            report(after_2038, "LATE", severity=3, description="after 2038"),
            report(after_2038 + SEC, "LATE", "PASSED"),
            report(last, "LAST", severity=3),
            clear(last, "LATE"),
        ],
    )
    out = tmp_path / "out"
    out.mkdir()
    argv: list[str | Path] = ["analyze", script, "--json", out / "r.json"]
    for flag, leaf in OUTPUT_FLAGS.items():
        argv += [flag, out / leaf]
    outcome = run_limited(argv, timeout=120)
    assert outcome.status == 0, outcome.stderr
    assert "Traceback" not in outcome.stderr and "internal error" not in outcome.stderr
    warnings = [line for line in outcome.stderr.splitlines() if "builtin_interfaces" in line]
    assert len(warnings) == 1 and "saturated" in warnings[0], outcome.stderr
    assert "LAST" in outcome.stdout and "LATE" in outcome.stdout
    report_json = strict_json((out / "r.json").read_text(encoding="utf-8"))
    assert isinstance(report_json, dict)
    assert report_json["summary"]["end_ns"] == last
    faults = pq.read_table(out / "parquet" / "faults.parquet").to_pylist()
    assert {f["fault_code"]: f["first_occurred_ns"] for f in faults} == {
        "LAST": last,
        "LATE": after_2038,
    }
    with (out / "csv" / "faults.csv").open(newline="", encoding="utf-8") as stream:
        assert str(last) in {row["first_occurred_ns"] for row in csv.DictReader(stream)}
    with (out / "e.mcap").open("rb") as stream:
        stamps = {
            (message.log_time, stamp_sec(message.data, schema.name))
            for schema, _, message in make_reader(stream).iter_messages()
            if schema is not None and schema.name.endswith("FaultTransition")
        }
    assert (last, SEC_MAX) in stamps and (after_2038, SEC_MAX) in stamps
    assert str(last) in (out / "r.html").read_text(encoding="utf-8")


def stamp_sec(data: bytes, msgtype: str) -> int:
    """The ``stamp.sec`` of a FaultTransition payload."""
    message: Any = message_store().deserialize_cdr(data, msgtype)
    return int(message.stamp.sec)


def test_time_fields_saturate_at_int32_seconds() -> None:
    assert time_fields(SEC_MAX * SEC + 5) == (SEC_MAX, 5, False)
    assert time_fields((SEC_MAX + 1) * SEC) == (SEC_MAX, SEC - 1, True)
    assert time_fields(SEC_MIN * SEC) == (SEC_MIN, 0, False)
    assert time_fields(SEC_MIN * SEC - 1) == (SEC_MIN, 0, True)


def test_parquet_integers_outside_int64_are_saturated_and_counted() -> None:
    import pandas as pd  # noqa: PLC0415  # only this test needs it here

    frame = pd.DataFrame({"t_ns": [1, 2**64 - 1, -(2**70)], "fault_code": ["a", "b", "c"]})
    safe, count = clamped(frame)
    assert count == 2
    assert list(safe["t_ns"]) == [1, INT64_MAX, INT64_MIN]


# --- 6. warnings --------------------------------------------------------------------------------


def test_a_megabyte_warning_is_cut_on_the_terminal_and_the_page(tmp_path: Path) -> None:
    """A serialization format of 1 MB (printed in a warning) shows as a few hundred characters
    with the count of those left out; the JSON report keeps the warning whole."""
    fmt = "\u202e" + "z" * 1_000_000
    bag = write_bare(tmp_path / "w.mcap", [diag(SEC)], serialization=fmt)
    out = tmp_path / "out"
    out.mkdir()
    outcome = run_limited(
        ["analyze", bag, "--html", out / "r.html", "--json", out / "r.json", "--all"],
        memory=1024 * MIB,
        timeout=120,
    )
    assert outcome.status == 0, outcome.stderr
    # --all prints warnings whole (as far as they are shown at all: cut with the count).
    assert len(outcome.stdout) < 5000 and "characters)" in outcome.stdout
    assert "\\u202e" in outcome.stdout
    page = (out / "r.html").read_text(encoding="utf-8")
    assert len(page) < 100_000 and re.search(r"\.\.\. \(\+999,\d{3} characters\)", page)
    report_json = strict_json((out / "r.json").read_text(encoding="utf-8"))
    assert isinstance(report_json, dict)
    assert any(fmt[1:] in warning for warning in report_json["warnings"])


def test_a_megabyte_warning_is_cut_in_the_check_gate(tmp_path: Path) -> None:
    """The check command prints the replay's warnings on the terminal, as GitHub annotations
    and in the step summary: each cut the same way."""
    bag = write_bare(tmp_path / "w.mcap", [diag(SEC)], serialization="z" * 1_000_000)
    budget = write_budget(tmp_path, "- never_confirm: ['NOTHING_*']")
    summary = tmp_path / "summary.md"
    outcome = run_limited(
        # Its one message cannot be decoded: nothing is replayed, which --allow-empty passes.
        ["check", bag, "--budget", budget, "--github", "--allow-empty"],
        memory=1024 * MIB,
        env={"GITHUB_STEP_SUMMARY": str(summary)},
        timeout=120,
    )
    assert outcome.status == 0, outcome.stderr
    assert len(outcome.stdout) < 10_000 and "characters)" in outcome.stdout
    assert "::warning" in outcome.stdout
    text = summary.read_text(encoding="utf-8")
    assert len(text) < 5000 and "zzzz" in text


def test_clip_names_what_it_left_out() -> None:
    assert clip("abcdef", 6) == "abcdef"
    assert clip("abcdefgh", 3) == "abc... (+5 characters)"


# --- 7. COLUMNS ---------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def small_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("columns")
    return write_script(
        root / "c.jsonl",
        [report(SEC, "MOTOR_OVERHEAT", severity=3, description="85 C", source="/m")],
    )


@pytest.mark.parametrize(
    ("columns", "like"), [("0", "80"), ("-5", "80"), ("abc", "80"), ("1", "60"), ("100000", "1000")]
)
def test_unusable_widths_fall_back(
    columns: str, like: str, small_run: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """COLUMNS that says nothing usable lays the summary out at 80 columns; 1 and 100000 are
    brought into 60 .. 1000."""
    result = replay([small_run])

    def summary(value: str) -> str:
        monkeypatch.setenv("COLUMNS", value)
        stream = io.StringIO()
        terminal.print_summary(result, stream)
        return stream.getvalue()

    shown = summary(columns)
    assert "MOTOR_OVERHEAT" in shown and "CONFIRMED" in shown
    assert shown == summary(like)


def test_columns_zero_prints_the_summary(small_run: Path) -> None:
    outcome = run_limited(["analyze", small_run], env={"COLUMNS": "0"}, timeout=120)
    assert outcome.status == 0, outcome.stderr
    assert "MOTOR_OVERHEAT" in outcome.stdout and "Faults: 1" in outcome.stdout
