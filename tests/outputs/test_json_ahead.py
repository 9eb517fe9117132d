"""The report's long lists encoded by a child process while the replay runs: the same bytes as
encoding them at the end, whether the child delivers every chunk, some, or none."""

from __future__ import annotations

import io
import signal
import sys
import threading
from typing import TYPE_CHECKING

import pytest

from medkit_replay import spool
from medkit_replay.cli import main
from medkit_replay.outputs import json_ahead
from medkit_replay.outputs.json_ahead import JsonAhead
from medkit_replay.outputs.json_report import write_json_bytes
from medkit_replay.pipeline import loop, replay
from tests.outputs.scripts import SEC, T0, healing_config, report, write_script

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.result import Result


@pytest.fixture
def small_chunks(monkeypatch: pytest.MonkeyPatch) -> None:
    """Spools spill every 5 records, looked at every 3 messages: a short script spills often."""
    monkeypatch.setattr(spool, "DEFAULT_CHUNK", 5)
    monkeypatch.setattr(loop, "SETTLE_EVERY", 3)


def _busy_script(tmp_path: Path) -> Path:
    """Many reports, events and transitions, texts that need escaping among them."""
    lines = []
    for k in range(300):
        code = f"CODE_{k % 7}"
        event = "PASSED" if k % 5 == 4 else "FAILED"
        lines.append(
            report(T0 + k * SEC // 10, code, event, description=f'v\u00e9rt "{k}"\n\u2603 {k}')
        )
    lines.append(report(T0 + 31 * SEC, "bad code!", source="/misconfigured"))
    return write_script(tmp_path / "busy.jsonl", lines)


def _report(result: Result, ahead: JsonAhead | None) -> bytes:
    out = io.BytesIO()
    write_json_bytes(result, out, ahead)
    return out.getvalue()


def test_chunks_encoded_ahead_give_the_same_bytes(small_chunks: None, tmp_path: Path) -> None:
    script, config = _busy_script(tmp_path), healing_config(tmp_path)
    plain = _report(replay([script], [config]), None)
    with JsonAhead() as ahead:
        result = replay([script], [config], spill_listener=ahead)
        encoded = _report(result, ahead)
        delivered = ahead.delivered()
    assert encoded == plain
    assert len(delivered) > 50  # reports, events and transitions all went through the child
    assert {number for number, _ in delivered} == {0, 1, 2}


def test_a_child_that_dies_changes_nothing(small_chunks: None, tmp_path: Path) -> None:
    script, config = _busy_script(tmp_path), healing_config(tmp_path)
    plain = _report(replay([script], [config]), None)
    with JsonAhead() as ahead:
        result = replay([script], [config], spill_listener=ahead)
        assert ahead._child is not None
        ahead._child.send_signal(signal.SIGKILL)
        assert _report(result, ahead) == plain  # what it answered before, and the rest here
        assert ahead._ended


def test_a_child_that_cannot_start_changes_nothing(
    small_chunks: None, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    script = _busy_script(tmp_path)
    plain = _report(replay([script]), None)
    monkeypatch.setattr(sys, "executable", str(tmp_path / "no-such-python"))
    with JsonAhead() as ahead:
        result = replay([script], spill_listener=ahead)
        assert _report(result, ahead) == plain
        assert ahead._child is None


def test_no_thread_to_be_had_changes_nothing(
    small_chunks: None, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    script = _busy_script(tmp_path)
    plain = _report(replay([script]), None)

    def refuse(self: threading.Thread) -> None:
        raise RuntimeError("can't start new thread")

    monkeypatch.setattr(threading.Thread, "start", refuse)
    with JsonAhead() as ahead:
        result = replay([script], spill_listener=ahead)
        assert _report(result, ahead) == plain
        assert ahead._child is None or ahead._child.poll() is not None  # stopped at once


def test_chunks_beyond_the_queue_bound_are_encoded_at_the_end(
    small_chunks: None, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(json_ahead, "QUEUE_LIMIT", 1)  # nothing fits: every chunk stays here
    script = _busy_script(tmp_path)
    plain = _report(replay([script]), None)
    with JsonAhead() as ahead:
        result = replay([script], spill_listener=ahead)
        assert _report(result, ahead) == plain
        assert ahead.delivered() == {}


def test_a_short_recording_starts_no_process(tmp_path: Path) -> None:
    script = _busy_script(tmp_path)  # 300 reports: far below a spool's chunk
    with JsonAhead() as ahead:
        replay([script], spill_listener=ahead)
        assert ahead._child is None


def test_analyze_writes_the_same_report_to_a_file_and_stdout(
    small_chunks: None, tmp_path: Path, capsysbinary: pytest.CaptureFixture[bytes]
) -> None:
    script, config = _busy_script(tmp_path), healing_config(tmp_path)
    plain = _report(replay([script], [config]), None)
    target = tmp_path / "report.json"
    args = ["analyze", str(script), "--config", str(config), "--quiet"]
    assert main([*args, "--json", str(target)]) == 0
    assert target.read_bytes() == plain
    capsysbinary.readouterr()
    assert main([*args, "--json", "-"]) == 0
    assert capsysbinary.readouterr().out == plain


def test_the_child_refuses_a_frame_it_does_not_know(tmp_path: Path) -> None:
    """A frame naming no spooled list, or cut short, ends the child with status 2."""
    import subprocess  # noqa: PLC0415

    target = tmp_path / "lines"
    with target.open("wb") as out:
        fd = out.fileno()
        frame = json_ahead._FRAME.pack(0, b"Nothing", 0, 3) + b"abc"
        done = subprocess.run(
            [sys.executable, "-m", json_ahead.__name__, str(fd)],
            input=frame,
            capture_output=True,
            pass_fds=(fd,),
            check=False,
        )
    assert done.returncode == 2
    assert done.stdout == b""


def test_a_with_block_closes_it_through_the_shared_closing() -> None:
    """JsonAhead's context is Closing's (exit calls close), not a pair of its own."""
    from medkit_replay.closing import Closing  # noqa: PLC0415

    assert issubclass(JsonAhead, Closing)
    assert "__enter__" not in vars(JsonAhead)
    assert "__exit__" not in vars(JsonAhead)
    with pytest.raises(RuntimeError), JsonAhead() as ahead:
        ahead._file = io.BytesIO()
        raise RuntimeError
    assert ahead._file is None  # closed on the way out
