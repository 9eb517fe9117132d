"""Every command example of README.md, CONTRIBUTING.md and docs/ runs, and exits as they say.

A line starting with ``medkit-replay `` (or ``$ medkit-replay ``) inside a fenced code block is
an example. It runs from one scratch folder that holds the sample recordings, rules and examples
(``REAL``) and the small files the examples name (``FIXTURES``), in document order (README.md,
CONTRIBUTING.md, then docs/ by path), each distinct command once. It must exit 0 unless an HTML
comment right before its block says otherwise (the convention is told in docs/about.md):

- ``<!-- example: exits 0 1 -->``: each command's exit status, in order;
- ``<!-- example: synopsis -->`` and ``<!-- example: output -->``: usage lines and printed text;
- ``<!-- example: needs-server -->``, ``needs-network``, ``needs-cluster``: not run here. Their
  own tests: serve in tests/gateway/test_serve_command.py and test_serve_routes.py (a real
  uvicorn), follow in tests/follow/test_follow_cli.py (a recording written while followed),
  s3://, gs:// and http(s):// inputs in tests/inputs/test_remote.py, test_remote_gcs.py and
  tests/fleet/test_remote_fleet.py (moto, fake-gcs-server and a Range server on 127.0.0.1),
  Dask in tests/fleet/test_dask.py and tests/tuning/test_sweep_dask.py.
"""

from __future__ import annotations

import re
import shlex
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from medkit_replay.cli import main

if TYPE_CHECKING:
    from collections.abc import Iterator

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", ROOT / "CONTRIBUTING.md", *sorted((ROOT / "docs").rglob("*.md"))]
SKIPPED = {"synopsis", "output"}
NEEDS = {
    "needs-server": "needs a server or a recording being written",
    "needs-network": "needs object storage or an HTTP server",
    "needs-cluster": "needs a Dask cluster",
}
# What only a server, a network or a cluster can answer: such an example must carry a marker.
OUT_OF_REACH = re.compile(r"^medkit-replay (serve|follow) |s3://|gs://|https?://|--dask")

# Paths the examples name, to what they are in the scratch folder: the repository's own folders
# (linked), and files written there for the examples that name a robot's files.
REAL = {name: ROOT / name for name in ("sample_bags", "rules", "examples")}
FIXTURES = {
    # docs/commands/validate.md: a parameter file with a positive threshold (line 4) naming a
    # correlation file (line 8) that misspells a key (line 3).
    "robot/fault_manager.yaml": (
        "# the robot's fault manager\n"
        "fault_manager:\n"
        "  ros__parameters:\n"
        "    confirmation_threshold: 3\n"
        "    healing_enabled: true\n"
        "    healing_threshold: 3\n"
        "    correlation:\n"
        "      config_file: correlation.yaml\n"
    ),
    "robot/correlation.yaml": (
        "correlation:\n"
        "  enabled: true\n"
        "  default_windw_ms: 2000\n"
        "  rules:\n"
        "    - id: motor_overheat_cascade\n"
        "      mode: hierarchical\n"
        "      root_cause: {codes: [MOTOR_OVERHEAT]}\n"
        "      symptoms: [{codes: [WHEEL_SLIP]}]\n"
        "      window_ms: 2000\n"
    ),
}


@dataclass(frozen=True)
class Block:
    """One fenced code block holding examples, where it is, and its marker."""

    page: str
    line: int
    marker: str
    commands: tuple[str, ...]
    output: str


def _commands(lines: list[str]) -> tuple[tuple[str, ...], str]:
    """A block's commands (continuation lines joined) and, in a ``$`` block, what it prints."""
    prompted = any(line.startswith("$ ") for line in lines)
    found: list[str] = []
    printed: list[str] = []
    pending = ""
    for line in lines:
        if pending:
            pending += " " + line.strip()
        elif prompted and line.startswith("$ medkit-replay "):
            pending = line[2:]
        elif not prompted and line.startswith("medkit-replay "):
            pending = line
        else:
            if prompted and found:
                printed.append(line)
            continue
        if pending.endswith("\\"):
            pending = pending[:-1].rstrip()
        else:
            found.append(pending)
            pending = ""
    return tuple(found), "".join(f"{line}\n" for line in printed)


def blocks() -> Iterator[Block]:
    """Every fenced block of the pages that holds a ``medkit-replay`` line."""
    for page in PAGES:
        lines = page.read_text(encoding="utf-8").splitlines()
        start: int | None = None
        for number, line in enumerate(lines):
            if not line.startswith("```"):
                continue
            if start is None:
                start = number
                continue
            commands, output = _commands(lines[start + 1 : number])
            before = lines[start - 1].strip() if start else ""
            found = re.fullmatch(r"<!-- example: (.*) -->", before)
            if commands:
                yield Block(
                    str(page.relative_to(ROOT)),
                    start + 1,
                    found.group(1) if found else "",
                    commands,
                    output,
                )
            start = None


def expected_statuses(block: Block) -> list[int]:
    """The exit status of each command: 0 unless ``exits ...`` says otherwise."""
    if not block.marker:
        return [0] * len(block.commands)
    kind, _, rest = block.marker.partition(" ")
    assert kind == "exits", f"{block.page}:{block.line}: unknown marker {block.marker!r}"
    statuses = [int(word) for word in rest.split()]
    assert len(statuses) == len(block.commands), f"{block.page}:{block.line}: one per command"
    return statuses


def skip_reason(block: Block) -> str | None:
    kind = block.marker.split(" ", 1)[0]
    if kind in SKIPPED:
        return kind
    return NEEDS.get(kind)


BLOCKS = list(blocks())


def test_the_pages_hold_examples() -> None:
    """The parser finds what the pages hold (a parser that found nothing would pass anything)."""
    pages = {block.page for block in BLOCKS if skip_reason(block) is None}
    assert {"README.md", "docs/commands/check.md", "docs/tuning.md"} <= pages
    assert sum(len(b.commands) for b in BLOCKS if skip_reason(b) is None) >= 15


def test_what_needs_a_server_is_marked() -> None:
    for block in BLOCKS:
        kind = block.marker.split(" ", 1)[0]
        assert kind in {"", "exits", *SKIPPED, *NEEDS}, f"{block.page}:{block.line}: {kind!r}"
        if skip_reason(block) is None:
            for command in block.commands:
                assert not OUT_OF_REACH.search(command), f"{block.page}:{block.line}: {command}"


@pytest.mark.parametrize(
    "block",
    [b for b in BLOCKS if b.marker.split(" ", 1)[0] in NEEDS],
    ids=lambda b: f"{b.page}:{b.line}",
)
def test_marked_examples_are_covered_elsewhere(block: Block) -> None:
    pytest.skip(f"{NEEDS[block.marker.split(' ', 1)[0]]}: covered by its own tests")


def test_every_example_runs_as_documented(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    for name, real in REAL.items():
        (tmp_path / name).symlink_to(real, target_is_directory=True)
    for name, text in FIXTURES.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text, encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("COLUMNS", raising=False)
    done: dict[str, int] = {}
    wrong: list[str] = []
    for block in BLOCKS:
        if skip_reason(block) is not None:
            continue
        for command, expected in zip(block.commands, expected_statuses(block), strict=True):
            if command not in done:
                done[command] = main(shlex.split(command)[1:])
                out, err = capsys.readouterr()
                # a "$" block shows what the command prints: it must be what it printed
                if block.output and done[command] == expected and out != block.output:
                    wrong.append(f"{block.page}:{block.line}: {command}: printed\n{out}")
                if "Traceback" in err:
                    wrong.append(f"{block.page}:{block.line}: {command}: {err}")
            if done[command] != expected:
                wrong.append(
                    f"{block.page}:{block.line}: {command}: exit {done[command]}, "
                    f"the docs say {expected}"
                )
    assert wrong == []
