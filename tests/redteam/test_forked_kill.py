"""Red team, the forked output writer: killed or crashed at a named point (a real signal), it
costs only its own outputs, written after the report as a normal run writes them; no leftovers.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from tests.checks.support import NAV2, mission

if TYPE_CHECKING:
    from collections.abc import Callable

DYING = """
import contextlib, os, sys
from medkit_replay.outputs import atomic, html, tables
point, when, signum = sys.argv[1], sys.argv[2], int(sys.argv[3])
parent, real = os.getpid(), atomic.atomic_text

@contextlib.contextmanager
def dying(target, **options):
    with real(target, **options) as stream:
        if when == "opened" and target.name == point and os.getpid() != parent:
            os.kill(os.getpid(), signum)
        yield stream
        if when == "written" and target.name == point and os.getpid() != parent:
            stream.flush()  # all of it in the temporary file, not yet renamed into place
            os.kill(os.getpid(), signum)

html.atomic_text = tables.atomic_text = dying
sys.argv[1:] = sys.argv[4:]
from medkit_replay.cli import run
run()
"""
"""Runs the command line with the real writers; the forked child (never this process) sends
itself ``signum`` when it has opened, or written all of, the temporary file for ``point``."""


def analyze(inputs: Path, out: Path, html: Path | None = None) -> list[str]:
    """The arguments of a run writing the JSON report, the HTML page and the CSV tables."""
    out.mkdir(exist_ok=True)
    page = html if html is not None else out / "r.html"
    script, report = str(inputs / "mission.jsonl"), str(out / "r.json")
    command = ["analyze", script, "--config", str(NAV2), "--quiet", "--json", report]
    return [*command, "--html", str(page), "--csv", str(out / "csv")]


def environment() -> dict[str, str]:
    env = dict(os.environ)
    env.pop("PYTHONFAULTHANDLER", None)  # a crash says nothing but its status
    return env


def files(root: Path) -> dict[str, bytes]:
    """Every file under ``root`` (hidden ones included) with its bytes."""
    return {
        str(path.relative_to(root)): path.read_bytes()
        for path in sorted(root.rglob("*"))
        if path.is_file()
    }


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("inputs")
    mission(folder)
    return folder


@pytest.fixture(scope="module")
def normal(inputs: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, bytes]:
    """What a run nobody kills writes."""
    out = tmp_path_factory.mktemp("normal")
    command = [sys.executable, "-m", "medkit_replay.cli", *analyze(inputs, out)]
    done = subprocess.run(command, capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    written = files(out)
    assert {"r.json", "r.html", "csv/faults.csv", "csv/clusters.csv"} <= set(written)
    return written


def assert_as_normal(
    done: subprocess.CompletedProcess[str], out: Path, normal: dict[str, bytes]
) -> None:
    assert done.returncode == 0, done.stderr
    assert "internal error" not in done.stderr and "Traceback" not in done.stderr, done.stderr
    assert len(done.stderr.splitlines()) <= 1, done.stderr
    assert files(out) == normal  # every output whole, nothing else: no temporary file left


@pytest.mark.parametrize(
    ("point", "when", "signum"),
    [
        ("r.html", "written", signal.SIGKILL),
        ("r.html", "opened", signal.SIGKILL),
        ("events.csv", "written", signal.SIGKILL),  # after faults.csv, before the other tables
        ("faults.csv", "opened", signal.SIGKILL),  # the first file of the first output
        ("r.html", "written", signal.SIGSEGV),  # a crash in a native library
        ("events.csv", "written", signal.SIGTERM),  # the child alone is asked to end
    ],
)
def test_a_killed_writer_costs_only_its_outputs_written_here(
    point: str, when: str, signum: int, inputs: Path, tmp_path: Path, normal: dict[str, bytes]
) -> None:
    out = tmp_path / "out"
    command = [sys.executable, "-c", DYING, point, when, str(signum), *analyze(inputs, out)]
    done = subprocess.run(
        command, capture_output=True, text=True, timeout=120, check=False, env=environment()
    )
    assert_as_normal(done, out, normal)
    (warning,) = done.stderr.splitlines()
    assert warning.startswith("medkit-replay: warning: ") and signal.Signals(signum).name in warning
    assert ("HTML" in warning) and (("CSV" in warning) == point.endswith(".csv")), warning


def children(pid: int) -> list[int]:
    """The processes whose parent is ``pid``."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                found.append(int(entry.name))
    return found


def gone(pid: int) -> bool:
    """True once ``pid`` has ended (a zombie: its files are closed) or been reaped."""
    try:
        return (Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()[0] == "Z"
    except OSError:
        return True


def wait_for(condition: Callable[[], bool], what: str) -> None:
    deadline = time.monotonic() + 60
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.02)


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="finds the child through /proc")
def test_a_writer_killed_from_outside_while_it_waits(
    inputs: Path, tmp_path: Path, normal: dict[str, bytes]
) -> None:
    """The page goes to a FIFO: the child writes the tables, then waits there for a reader, and
    is killed by pid, from here. This process then writes the page, read from the FIFO."""
    out = tmp_path / "out"
    out.mkdir()
    fifo = tmp_path / "page"
    os.mkfifo(fifo)
    command = [sys.executable, "-m", "medkit_replay.cli", *analyze(inputs, out, fifo)]
    with subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=environment()
    ) as proc:
        tables = {name for name in normal if name.startswith("csv/")}
        wait_for(lambda: tables <= set(files(out)) or proc.poll() is not None, "the tables")
        (child,) = children(proc.pid)
        os.kill(child, signal.SIGKILL)
        wait_for(lambda: gone(child), "the child's end")
        page: list[bytes] = []  # the parent's own writing of it, read meanwhile
        reader = threading.Thread(target=lambda: page.append(fifo.read_bytes()), daemon=True)
        reader.start()
        stdout, stderr = proc.communicate(timeout=120)
        if reader.is_alive():  # the page was never written: end the reader's wait
            os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        reader.join(60)
    done = subprocess.CompletedProcess(command, proc.returncode, stdout, stderr)
    assert page == [normal["r.html"]], stderr
    assert_as_normal(done, out, {name: data for name, data in normal.items() if name != "r.html"})
    assert "SIGKILL" in stderr and "HTML" in stderr, stderr
