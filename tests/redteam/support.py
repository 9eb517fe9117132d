"""Running the real command line in a child process under hard limits, for hostile inputs.

Bombs are tested here with ``resource.setrlimit`` set in the child (address space, CPU,
file size), never by hoping: a bound that does not hold kills the child and fails the test.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence
    from pathlib import Path

MIB = 1024 * 1024
# Python, rosbags, numpy and pandas need some 300-400 MiB of address space to start;
# every bomb below would need many GiB.
DEFAULT_MEMORY = 1536 * MIB
DEFAULT_CPU_SECONDS = 60


@dataclass(frozen=True, slots=True)
class Outcome:
    """What the child did: its status, its output, and its peak memory (KiB, from rusage)."""

    status: int
    stdout: str
    stderr: str
    peak_rss_kib: int

    @property
    def error_lines(self) -> list[str]:
        return [line for line in self.stderr.splitlines() if line.startswith("medkit-replay:")]


def _limits(memory: int, cpu_seconds: int, file_size: int | None) -> None:
    resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    resource.setrlimit(resource.RLIMIT_CPU, (cpu_seconds, cpu_seconds))
    if file_size is not None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (file_size, file_size))


def run_limited(
    argv: Sequence[str | Path],
    *,
    memory: int = DEFAULT_MEMORY,
    cpu_seconds: int = DEFAULT_CPU_SECONDS,
    file_size: int | None = None,
    timeout: float = 120.0,
    cwd: Path | None = None,
    env: Mapping[str, str] | None = None,
) -> Outcome:
    """Run ``medkit-replay ARGV...`` in a child process under the given limits."""
    child_env = dict(os.environ)
    child_env.update(env or {})
    child_env.setdefault("COLUMNS", "100")
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        proc = subprocess.Popen(
            [sys.executable, "-m", "medkit_replay.cli", *map(str, argv)],
            stdout=out,
            stderr=err,
            stdin=subprocess.DEVNULL,
            cwd=cwd,
            env=child_env,
            preexec_fn=lambda: _limits(memory, cpu_seconds, file_size),  # noqa: PLW1509
        )
        status, peak = _wait(proc, timeout)
        out.seek(0)
        err.seek(0)
        stdout = out.read().decode("utf-8", "replace")
        stderr = err.read().decode("utf-8", "replace")
    return Outcome(status, stdout, stderr, peak)


def _wait(proc: subprocess.Popen[bytes], timeout: float) -> tuple[int, int]:
    """Wait for this one child and take its own peak RSS (KiB) from wait4's rusage."""
    deadline = time.monotonic() + timeout
    while True:
        pid, raw, usage = os.wait4(proc.pid, os.WNOHANG)
        if pid == proc.pid:
            proc.returncode = os.waitstatus_to_exitcode(raw)
            return proc.returncode, usage.ru_maxrss
        if time.monotonic() > deadline:
            proc.kill()
            proc.wait()
            raise subprocess.TimeoutExpired(proc.args, timeout)
        time.sleep(0.02)


def assert_one_line_error(outcome: Outcome, *needles: str) -> str:
    """Exit 2 with exactly one ``medkit-replay: error:`` line holding every needle; no traceback."""
    assert outcome.status == 2, (outcome.status, outcome.stderr[-2000:])
    assert "Traceback" not in outcome.stderr, outcome.stderr[-2000:]
    assert "internal error" not in outcome.stderr, outcome.stderr[-2000:]
    lines = [
        line for line in outcome.stderr.splitlines() if line.startswith("medkit-replay: error")
    ]
    assert len(lines) == 1, outcome.stderr[-2000:]
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])
    return lines[0]


def tree_listing(root: Path) -> dict[str, tuple[int, int]]:
    """Every path under ``root`` with its size and mtime (ns): to show nothing changed."""
    listing: dict[str, tuple[int, int]] = {}
    for path in sorted(root.rglob("*")):
        info = path.lstat()
        listing[str(path.relative_to(root))] = (info.st_size, info.st_mtime_ns)
    return listing
