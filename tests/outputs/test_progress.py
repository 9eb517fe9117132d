"""Progress: the replay's callback, the recording's span, the bar (on a terminal, not --quiet)."""

from __future__ import annotations

import io
import sys
from typing import TYPE_CHECKING

import pytest

from medkit_replay.cli import main
from medkit_replay.inputs import open_recording
from medkit_replay.outputs.console import progress_bar
from medkit_replay.outputs.json_report import dumps
from medkit_replay.outputs.mcap_events import write_mcap
from medkit_replay.outputs.progress import ProgressBar
from medkit_replay.pipeline import Progress, replay
from tests.outputs.scripts import SEC, T0, FakeTTY, healing_config, mission, report, write_script

if TYPE_CHECKING:
    from pathlib import Path


@pytest.fixture(autouse=True)
def _terminal_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    for name in ("COLUMNS", "FORCE_COLOR", "NO_COLOR", "TTY_COMPATIBLE", "TTY_INTERACTIVE"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv("TERM", "xterm-256color")


def script_of(tmp_path: Path, count: int) -> Path:
    return write_script(
        tmp_path / "run.jsonl", [report(T0 + i * SEC, f"CODE_{i % 3}") for i in range(count)]
    )


def test_callback_every_n_messages_and_once_at_the_end(tmp_path: Path) -> None:
    seen: list[Progress] = []
    replay([script_of(tmp_path, 7)], progress=seen.append, progress_every=3)
    assert [(p.phase, p.messages, p.t_ns, p.done) for p in seen] == [
        ("replay", 0, None, False),
        ("replay", 3, T0 + 2 * SEC, False),
        ("replay", 6, T0 + 5 * SEC, False),
        ("replay", 7, T0 + 6 * SEC, True),
    ]
    # A script declares no span up front: no fraction until the end.
    assert [p.fraction for p in seen] == [None, None, None, 1.0]


def test_progress_does_not_change_the_result(tmp_path: Path) -> None:
    script, config = mission(tmp_path), healing_config(tmp_path)
    calls: list[Progress] = []
    with_progress = replay([script], [config], progress=calls.append, progress_every=1)
    assert dumps(with_progress) == dumps(replay([script], [config]))
    assert [p.messages for p in calls] == [*range(11), 10]  # start, each message, end


def test_bags_report_bag_time_fractions_in_two_passes(tmp_path: Path) -> None:
    events = tmp_path / "events.mcap"
    write_mcap(replay([mission(tmp_path)], [healing_config(tmp_path)]), events)
    seen: list[Progress] = []
    result = replay([events], progress=seen.append, progress_every=2)
    phases = [p.phase for p in seen]
    assert phases == sorted(phases, key=["prescan", "replay"].index)  # prescan, then replay
    prescan = [p for p in seen if p.phase == "prescan"]
    assert [(p.messages, p.done) for p in prescan] == [(0, False), (0, True)]  # no service calls
    passes = [p for p in seen if p.phase == "replay"]
    first, last = passes[0], passes[-1]
    # The MCAP's summary gives the span before anything is read.
    assert (first.start_ns, first.end_ns) == (T0, T0 + 20 * SEC)
    assert first.fraction is None and first.messages == 0
    assert last.done and last.fraction == 1.0 and last.messages == result.summary.messages_read
    fractions = [p.fraction for p in passes[1:-1]]
    assert fractions and all(f is not None and 0.0 <= f <= 1.0 for f in fractions)
    assert fractions == sorted(fractions)  # type: ignore[type-var]


def test_recording_span(tmp_path: Path) -> None:
    script = mission(tmp_path)
    events = tmp_path / "events.mcap"
    write_mcap(replay([script], [healing_config(tmp_path)]), events)
    with open_recording([events]) as recording:
        assert recording.span == (T0, T0 + 20 * SEC)
    with open_recording([script]) as recording:
        assert recording.span is None  # a script says nothing before it is read
    with open_recording([events, script]) as recording:
        assert recording.span is None  # a partial span would be wrong about the end


def test_progress_fraction_edges() -> None:
    assert Progress("replay", 5, 15, 10, 20).fraction == 0.5
    assert Progress("replay", 5, 25, 10, 20).fraction == 1.0  # clamped
    assert Progress("replay", 5, 10, 10, 10).fraction == 0.0  # zero-length span
    assert Progress("replay", 5, None, 10, 20, done=True).fraction == 1.0


def test_no_bar_when_quiet_or_not_a_terminal() -> None:
    assert progress_bar(io.StringIO()) is None
    assert progress_bar(FakeTTY(), quiet=True) is None
    assert isinstance(progress_bar(FakeTTY()), ProgressBar)


def test_no_bar_on_a_dumb_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("TERM", "dumb")
    assert progress_bar(FakeTTY()) is None


def test_bar_draws_on_a_terminal_and_clears_itself(tmp_path: Path) -> None:
    stream = FakeTTY()
    bar = progress_bar(stream)
    assert bar is not None
    with bar:
        result = replay([script_of(tmp_path, 50)], progress=bar, progress_every=5)
    assert result.summary.messages_read == 50
    drawn = stream.getvalue()
    assert "replaying" in drawn and "50 msgs" in drawn
    assert "\x1b[?25h" in drawn and drawn.endswith("\x1b[2K")  # cursor back, bar erased


def test_bar_with_a_known_span(tmp_path: Path) -> None:
    events = tmp_path / "events.mcap"
    write_mcap(replay([mission(tmp_path)], [healing_config(tmp_path)]), events)
    stream = FakeTTY()
    bar = progress_bar(stream)
    assert bar is not None
    with bar:
        replay([events], progress=bar, progress_every=1)
    assert "20.0/20.0 s" in stream.getvalue() and "100%" in stream.getvalue()


def test_cli_is_silent_on_stderr_when_it_is_not_a_terminal(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["analyze", str(script_of(tmp_path, 20))]) == 0
    out, err = capsys.readouterr()
    assert err == "" and "CODE_0" in out


def test_cli_draws_a_bar_on_a_terminal_unless_quiet(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    script = str(script_of(tmp_path, 20))
    terminal = FakeTTY()
    monkeypatch.setattr(sys, "stderr", terminal)
    assert main(["analyze", script, "--json", str(tmp_path / "r.json")]) == 0
    assert "replaying" in terminal.getvalue()
    quiet = FakeTTY()
    monkeypatch.setattr(sys, "stderr", quiet)
    assert main(["analyze", script, "--quiet"]) == 0
    assert quiet.getvalue() == ""
    assert capsys.readouterr().out.count("CODE_0") >= 1  # the first run's summary only
