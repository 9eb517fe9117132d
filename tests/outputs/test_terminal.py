"""The terminal summary: fits 80 columns, plain off a terminal, recorded text kept literal."""

from __future__ import annotations

import io
import json
import re
from typing import TYPE_CHECKING

import pytest
from rich.console import Console

from medkit_replay.cli import main
from medkit_replay.outputs.terminal import (
    print_summary,
    render_summary,
    summary_renderable,
    summary_text,
)
from medkit_replay.pipeline import replay
from medkit_replay.text import severity_name
from tests.outputs.scripts import SEC, T0, FakeTTY, healing_config, mission, report, write_script

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.result import Result

ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")
MARKUP = "[bold red]85 C[/] [link=http://x]click[/link] :smile:"


@pytest.fixture(autouse=True)
def _plain_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    """Rich reads these; the tests fix terminal-ness and width themselves."""
    for name in (
        "COLUMNS",
        "LINES",
        "FORCE_COLOR",
        "NO_COLOR",
        "TTY_COMPATIBLE",
        "TTY_INTERACTIVE",
    ):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv("TERM", "xterm-256color")


@pytest.fixture
def result(tmp_path: Path) -> Result:
    return replay([mission(tmp_path)], [healing_config(tmp_path)])


def drawn(result: Result, *, width: int, terminal: bool) -> str:
    buffer = io.StringIO()
    console = Console(file=buffer, width=width, force_terminal=terminal, highlight=False)
    console.print(summary_renderable(result, width))
    return buffer.getvalue()


def test_plain_summary_fits_80_columns_and_says_what_happened(result: Result) -> None:
    text = render_summary(result)
    assert ANSI.search(text) is None and "\x1b" not in text
    lines = text.splitlines()
    # Only a word wider than the line (here the script's path under tmp_path) is wider.
    assert all(len(line) <= 80 or len(line.split()) == 1 for line in lines)
    assert all(line == line.rstrip() for line in lines)  # no padding left for logs
    assert "recording: 40.000 s of bag time from 2023-11-14 22:13:20.000 UTC" in text
    assert "faults: 3 - CONFIRMED 1, HEALED 1, CLEARED 1" in text
    assert "9 reports (1 rejected), 1 clear" in text
    row = lines.index(next(line for line in lines if line.startswith("MOTOR_OVERHEAT")))
    assert lines[row].split() == ["MOTOR_OVERHEAT", "CONFIRMED", "CRITICAL", "1"]
    assert lines[row + 1] == "  confirmed 0.000 s"
    row = lines.index(next(line for line in lines if line.startswith("BATTERY_LOW")))
    assert lines[row].split() == ["BATTERY_LOW", "CLEARED", "WARN", "1"]
    assert lines[row + 1] == "  confirmed 6.000 s → cleared 20.000 s"
    assert "LIDAR_DROPOUT" in text and "HEALED" in text
    assert "from /power/bms, /power/bms2" in text
    assert "  85 C" in text  # the description, under its code


@pytest.mark.parametrize("terminal", [False, True])
def test_rich_console_at_80_columns(result: Result, terminal: bool) -> None:
    text = drawn(result, width=80, terminal=terminal)
    assert (ANSI.search(text) is not None) == terminal
    plain = ANSI.sub("", text)
    assert max(len(line) for line in plain.splitlines()) <= 80
    assert "MOTOR_OVERHEAT" in plain and "CRITICAL" in plain


def test_wide_terminal_sizes_columns_to_their_content(result: Result) -> None:
    text = render_summary(result, width=140)
    header = next(line for line in text.splitlines() if line.startswith("code"))
    assert header == "code            status     severity  occ"  # the longest code is 14


def test_print_summary_is_plain_when_not_a_terminal(result: Result) -> None:
    stream = io.StringIO()
    print_summary(result, stream)
    assert stream.getvalue() == render_summary(result)


def test_print_summary_colours_a_terminal(result: Result) -> None:
    stream = FakeTTY()
    print_summary(result, stream)
    assert ANSI.search(stream.getvalue()) is not None
    assert "MOTOR_OVERHEAT" in ANSI.sub("", stream.getvalue())


@pytest.mark.parametrize("color", ["", "1"])
def test_the_summary_drawn_ahead_is_the_one_printed(
    result: Result, monkeypatch: pytest.MonkeyPatch, color: str
) -> None:
    """``analyze`` draws the summary while outputs are written and prints it after: the same
    text, colours included, and the stream is not touched while drawing."""
    if color:
        monkeypatch.setenv("NO_COLOR", color)
    for stream, fresh in ((FakeTTY(), FakeTTY()), (io.StringIO(), io.StringIO())):
        print_summary(result, stream)
        assert summary_text(result, fresh) == stream.getvalue()
        assert fresh.getvalue() == ""


def test_no_color_is_honoured_on_a_terminal(
    result: Result, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("NO_COLOR", "1")
    stream = FakeTTY()
    print_summary(result, stream)
    assert "\x1b[3" not in stream.getvalue()  # no foreground colour


def test_recorded_text_is_never_markup(tmp_path: Path) -> None:
    script = write_script(
        tmp_path / "s.jsonl",
        [
            report(T0, "MOTOR_OVERHEAT", description=MARKUP, source="/robot/[red]motor"),
            report(T0 + SEC, "ESCAPES", description="a\x1b[2Jb\u202ec\nd", source="/x"),
        ],
    )
    result = replay([script])
    for text in (
        render_summary(result, width=400),
        ANSI.sub("", drawn(result, width=100, terminal=True)),
        ANSI.sub("", drawn(result, width=400, terminal=True)),
    ):
        assert MARKUP in text
        assert "/robot/[red]motor" in text
        assert "a\\x1b[2Jb\\u202ec d" in text  # control characters shown, not obeyed
        assert "\x1b[2J" not in text and "\u202e" not in text


def test_correlation_disabled_is_loud_and_warnings_stay_literal(tmp_path: Path) -> None:
    config = tmp_path / "params.yaml"
    config.write_text(
        "fault_manager:\n  ros__parameters:\n    correlation:\n"
        "      config_file: '[bold]rules[/bold].yaml'\n",
        encoding="utf-8",
    )
    result = replay([mission(tmp_path)], [config])
    assert any("correlation is off" in w for w in result.warnings)
    text = render_summary(result)
    assert "CORRELATION IS DISABLED FOR THIS RUN" in text
    assert text.index("CORRELATION IS DISABLED") < text.index("MOTOR_OVERHEAT")
    panel = [line for line in text.splitlines() if line.startswith(("┏", "┃", "┗"))]
    assert len(panel) >= 4 and max(len(line) for line in panel) <= 80
    assert "correlation disabled" in panel[0]
    wide = render_summary(result, width=400)
    assert "[bold]rules[/bold].yaml: Correlation config file not found" in wide  # not markup
    coloured = drawn(result, width=80, terminal=True)
    assert "\x1b[1;31m" in coloured  # bold red border


def test_other_warnings_are_listed_literally(tmp_path: Path) -> None:
    config = tmp_path / "params.yaml"
    config.write_text(
        "fault_manager:\n  ros__parameters:\n    entity_thresholds:\n"
        "      config_file: '[italic]missing[/italic].yaml'\n",
        encoding="utf-8",
    )
    result = replay([mission(tmp_path)], [config])
    assert len(result.warnings) == 1
    text = render_summary(result, width=400)
    assert "CORRELATION" not in text
    assert "Warnings (1)" in text
    assert "[italic]missing[/italic].yaml: Entity thresholds config file not found" in text
    assert text.index("Warnings (1)") > text.index("MOTOR_OVERHEAT")  # after the table


def test_long_recordings_keep_seconds_from_the_start(tmp_path: Path) -> None:
    script = write_script(
        tmp_path / "long.jsonl",
        [report(T0, "A"), report(T0 + 3725 * SEC, "B")],
    )
    text = render_summary(replay([script]))
    assert "recording: 1 h 02 min 05.000 s of bag time" in text
    lines = text.splitlines()
    row = lines.index(next(line for line in lines if line.startswith("B ")))
    assert lines[row + 1] == "  confirmed 3725.000 s"  # one format: seconds from the start


def test_empty_replay_summary(tmp_path: Path) -> None:
    script = write_script(tmp_path / "e.jsonl", [report(T0, "bad code!")])
    text = render_summary(replay([script]))
    assert "no fault reported" in text
    assert "1 report (1 rejected), 0 clears" in text


def test_severity_names() -> None:
    assert [severity_name(n) for n in (0, 1, 2, 3, 7)] == ["INFO", "WARN", "ERROR", "CRITICAL", "7"]


def test_json_to_stdout_is_only_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    status = main(["analyze", str(mission(tmp_path)), "--json", "-"])
    out, err = capsys.readouterr()
    assert status == 0
    assert json.loads(out)["schema"] == "medkit-replay/report/v1"
    assert out.startswith("{") and out.endswith("}\n")
    assert "MOTOR_OVERHEAT" in err and "faults:" in err  # the summary went to standard error
    assert "\x1b" not in out + err


def test_summary_on_stdout_by_default(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["analyze", str(mission(tmp_path))]) == 0
    out, err = capsys.readouterr()
    assert err == ""
    assert "\x1b" not in out
    assert all(len(line) <= 80 or len(line.split()) == 1 for line in out.splitlines())
