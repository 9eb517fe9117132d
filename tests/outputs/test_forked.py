"""Outputs written by a forked child while the JSON report is written: the same files, and the
child's failures as the parent's own."""

from __future__ import annotations

import os
import time
from typing import TYPE_CHECKING

import pytest

from medkit_replay.cli import main
from medkit_replay.errors import ConfigError
from medkit_replay.outputs.forked import Forked
from tests.outputs.scripts import healing_config, mission

if TYPE_CHECKING:
    from pathlib import Path


def test_outputs_written_beside_the_report_are_the_ones_written_alone(tmp_path: Path) -> None:
    script, config = mission(tmp_path), healing_config(tmp_path)
    base = ["analyze", str(script), "--config", str(config), "--quiet"]
    alone, beside = tmp_path / "alone", tmp_path / "beside"
    assert main([*base, "--html", str(alone / "r.html"), "--csv", str(alone / "csv")]) == 0
    report = tmp_path / "r.json"
    both = [*base, "--json", str(report), "--html", str(beside / "r.html")]
    assert main([*both, "--csv", str(beside / "csv")]) == 0
    assert (beside / "r.html").read_bytes() == (alone / "r.html").read_bytes()
    for table in sorted((alone / "csv").iterdir()):
        assert (beside / "csv" / table.name).read_bytes() == table.read_bytes()
    assert report.stat().st_size > 0


def test_a_failing_output_is_the_same_one_line_with_or_without_the_report(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    script = mission(tmp_path)
    (tmp_path / "blocked").write_text("a file where a folder is needed")
    html = str(tmp_path / "blocked" / "r.html")
    assert main(["analyze", str(script), "--quiet", "--html", html]) == 2
    alone = capsys.readouterr().err
    report = tmp_path / "r.json"
    assert main(["analyze", str(script), "--quiet", "--json", str(report), "--html", html]) == 2
    assert capsys.readouterr().err == alone
    assert alone.startswith("medkit-replay: error: ") and alone.count("\n") == 1


def test_the_childs_errors_come_back_as_raised() -> None:
    def refuse() -> None:
        raise ConfigError("bad value", path="p.yaml", line=4)

    with pytest.raises(ConfigError, match=r"^p\.yaml:4: bad value$"), Forked([("page", refuse)]):
        pass


def test_what_the_child_left_undone_is_done_here(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A job that fails otherwise (a bug) is run again here, with what followed it; the jobs the
    child finished are not. A bug raises here what it raised there."""
    done: list[tuple[str, int]] = []
    here = os.getpid()

    def first() -> None:
        (tmp_path / "first").write_text(str(os.getpid()))

    def bug() -> None:
        if os.getpid() != here:
            raise ValueError("oops")
        done.append(("bug", os.getpid()))

    with Forked([("first", first), ("second", bug), ("third", lambda: done.append(("third", 0)))]):
        pass
    assert (tmp_path / "first").read_text() != str(here)
    assert done == [("bug", here), ("third", 0)]
    warning = capsys.readouterr().err
    assert warning == (
        "medkit-replay: warning: the process writing second, third failed (ValueError: oops); "
        "second, third written by the main one instead\n"
    )

    def always() -> None:
        raise ValueError("oops")

    with pytest.raises(ValueError, match="oops"), Forked([("page", always)]):
        pass


def test_a_failure_here_ends_the_child(tmp_path: Path) -> None:
    marker = tmp_path / "late"

    def slow() -> None:
        time.sleep(30)
        marker.write_text("the child outlived its parent's failure")

    with pytest.raises(RuntimeError), Forked([("slow", slow)]) as forked:
        pid = forked._pid
        assert pid is not None
        raise RuntimeError("the report could not be written")
    assert pid is not None
    with pytest.raises(ChildProcessError):
        os.waitpid(pid, 0)  # reaped already
    assert not marker.exists()


def test_no_process_to_be_had_does_the_work_here(monkeypatch: pytest.MonkeyPatch) -> None:
    def refuse() -> int:
        raise BlockingIOError(11, "Resource temporarily unavailable")

    monkeypatch.setattr(os, "fork", refuse)
    done: list[int] = [os.getpid()]
    with Forked([("pid", lambda: done.append(os.getpid()))]):
        pass
    assert done == [os.getpid(), os.getpid()]

    def refuse_with_error() -> None:
        raise ConfigError("bad value", path="p.yaml")

    with pytest.raises(ConfigError, match="bad value"), Forked([("e", refuse_with_error)]):
        pass
