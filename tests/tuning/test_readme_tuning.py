"""docs/tuning.md's ("Tuning your fault manager") commands run as shown and print what it shows."""

from __future__ import annotations

import shlex
import shutil
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.cli import main

if TYPE_CHECKING:
    import pytest

ROOT = Path(__file__).resolve().parents[2]


def shown_commands() -> list[tuple[list[str], str]]:
    """``$ medkit-replay ...`` lines of the section and the output printed under each."""
    section = (ROOT / "docs" / "tuning.md").read_text(encoding="utf-8")
    blocks: list[str] = []
    inside: list[str] | None = None
    for line in section.splitlines(keepends=True):
        if line.startswith("```"):
            if inside is None:
                inside = []
            else:
                blocks.append("".join(inside))
                inside = None
        elif inside is not None:
            inside.append(line)
    found = []
    for block in blocks:
        if block.startswith("$ medkit-replay "):
            command, _, output = block.partition("\n")
            found.append((shlex.split(command)[2:], output))
    return found


def test_the_tuning_section_shows_real_output(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    shutil.copytree(ROOT / "examples" / "tuning_fleet", tmp_path / "examples" / "tuning_fleet")
    monkeypatch.chdir(tmp_path)
    commands = shown_commands()
    assert [argv[0] for argv, _ in commands] == ["suggest-rules", "sweep"]
    for argv, output in commands:
        assert main(argv) == 0
        assert capsys.readouterr().out == output
    assert (tmp_path / "tuning-out" / "variants.parquet").is_file()
    assert (tmp_path / "tuning.html").read_text().startswith("<!DOCTYPE html>")
