"""Running the real command line in a child process under hard limits, for hostile inputs.

Bombs are tested here with ``resource.setrlimit`` set in the child (address space, CPU,
file size), never by hoping: a bound that does not hold kills the child and fails the test.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence

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


_LAUNCHER = """
import os, resource, signal, sys
peak_file = sys.argv[1]
memory, cpu, size = (int(v) for v in sys.argv[2:5])
resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
resource.setrlimit(resource.RLIMIT_CPU, (cpu, cpu))
if size >= 0:
    resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))
child = os.fork()
if child == 0:
    os.execv(sys.executable, [sys.executable, *sys.argv[5:]])
_, raw, usage = os.wait4(child, 0)
with open(peak_file, "w") as out:
    out.write(str(usage.ru_maxrss))
if os.WIFSIGNALED(raw):
    signal.signal(os.WTERMSIG(raw), signal.SIG_DFL)
    os.kill(os.getpid(), os.WTERMSIG(raw))
sys.exit(os.waitstatus_to_exitcode(raw))
"""
"""Sets the limits (peak file, address space, CPU seconds, file size or -1), runs the rest of
its arguments as a fresh interpreter in a child, writes that child's peak RSS (KiB) to the peak
file and ends as the child ended. A peak taken from a process this test process started would
count this process's own pages (Linux keeps the high-water mark across fork and exec); the
launcher is small when it forks."""


def run_limited(
    argv: Sequence[str | Path],
    *,
    memory: int = DEFAULT_MEMORY,
    cpu_seconds: int = DEFAULT_CPU_SECONDS,
    file_size: int | None = None,
    timeout: float = 120.0,
    cwd: Path | None = None,
    env: Mapping[str, str] | None = None,
    module: str = "medkit_replay.cli",
) -> Outcome:
    """Run ``medkit-replay ARGV...`` (or ``python -m MODULE ARGV...``) in a child process
    under the given limits."""
    child_env = dict(os.environ)
    child_env.update(env or {})
    child_env.setdefault("COLUMNS", "100")
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        peak_file = Path(tempfile.mkdtemp()) / "peak"
        limits = [str(memory), str(cpu_seconds), str(file_size if file_size is not None else -1)]
        proc = subprocess.Popen(
            [
                sys.executable,
                "-c",
                _LAUNCHER,
                str(peak_file),
                *limits,
                "-m",
                module,
                *map(str, argv),
            ],
            stdout=out,
            stderr=err,
            stdin=subprocess.DEVNULL,
            cwd=cwd,
            env=child_env,
            start_new_session=True,  # a timeout ends the launcher and the CLI together
        )
        try:
            status = _wait(proc, timeout)
            peak = int(peak_file.read_text())
        finally:
            shutil.rmtree(peak_file.parent, ignore_errors=True)
        out.seek(0)
        err.seek(0)
        stdout = out.read().decode("utf-8", "replace")
        stderr = err.read().decode("utf-8", "replace")
    return Outcome(status, stdout, stderr, peak)


def _wait(proc: subprocess.Popen[bytes], timeout: float) -> int:
    """Wait for the launcher; its status is the CLI's."""
    try:
        return proc.wait(timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        raise


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
