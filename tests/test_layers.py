"""The architecture, tested: the engine imports no I/O layer, bridges import no outputs."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest


def loaded_after(module: str) -> set[str]:
    code = f"import json, sys; import {module}; print(json.dumps(sorted(sys.modules)))"
    out = subprocess.run(
        [sys.executable, "-c", code], check=True, capture_output=True, text=True
    ).stdout
    return set(json.loads(out))


FORBIDDEN_FOR_ENGINE = (
    "rosbags",
    "pandas",
    "yaml",
    "click",
    "medkit_replay.inputs",
    "medkit_replay.bridges",
    "medkit_replay.outputs",
    "medkit_replay.config",
    "medkit_replay.cli",
    "medkit_replay.pipeline",
)


@pytest.mark.parametrize("module", ["medkit_replay.engine", "medkit_replay.engine.correlation"])
def test_engine_is_pure(module: str) -> None:
    loaded = loaded_after(module)
    bad = sorted(m for m in loaded if m.startswith(FORBIDDEN_FOR_ENGINE))
    assert bad == []


def test_engine_sources_never_read_a_clock() -> None:
    from pathlib import Path  # noqa: PLC0415

    from medkit_replay import engine  # noqa: PLC0415

    root = Path(engine.__file__).parent
    for path in root.rglob("*.py"):
        text = path.read_text()
        for needle in ("import time", "datetime", "monotonic", "perf_counter", "open("):
            assert needle not in text, f"{path.name} uses {needle}"


def test_bridges_do_not_import_outputs_or_inputs() -> None:
    loaded = loaded_after("medkit_replay.bridges")
    bad = sorted(
        m
        for m in loaded
        if m.startswith(("medkit_replay.outputs", "medkit_replay.inputs", "pandas"))
    )
    assert bad == []
