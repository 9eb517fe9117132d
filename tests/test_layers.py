"""The architecture, tested: a declared table of what each layer may import, checked over the
whole package; the engine pure and clock-free; nothing heavy loaded where it is not used."""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

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


def test_remote_clients_load_only_for_remote_inputs() -> None:
    """inputs.ranges, inputs.remote and inputs.remote_store: obstore (the 'remote' extra) and
    boto3 are imported when a URL is opened, never by the CLI or a local replay."""
    loaded = loaded_after("medkit_replay.cli")
    assert {"medkit_replay.inputs.remote", "medkit_replay.inputs.ranges"} <= loaded
    assert sorted(m for m in loaded if m.startswith(("obstore", "boto3", "botocore"))) == []


def test_bridges_do_not_import_outputs_or_inputs() -> None:
    loaded = loaded_after("medkit_replay.bridges")
    bad = sorted(
        m
        for m in loaded
        if m.startswith(("medkit_replay.outputs", "medkit_replay.inputs", "pandas"))
    )
    assert bad == []


# -- the declared import table ------------------------------------------------------------

PACKAGE = Path(__file__).resolve().parents[1] / "medkit_replay"

NEUTRAL = {"model", "errors", "version", "text", "wildcards"}
"""Values and vocabulary every layer may use; they import nothing of ours but each other."""
ALLOWED: dict[str, set[str]] = {
    "model": set(),
    "errors": set(),
    "version": set(),
    "text": {"model"},
    "wildcards": set(),
    "files": {"errors"},
    "yaml_bounds": {"errors", "text"},
    "spool": {"errors"},
    "result": {"model"},
    "engine": {"model", "wildcards"},
    "bridges": {"model", "engine"},
    "inputs": {"model", "errors", "files", "yaml_bounds", "text", "msgdefs"},
    # config reads parameters into the settings types of the layers it configures.
    "config": {"model", "errors", "files", "yaml_bounds", "text", "engine", "bridges"},
    "parity": {"model", "bridges", "config"},
    "pipeline": NEUTRAL | {"spool", "result", "parity", "engine", "bridges", "inputs", "config"},
    "outputs": NEUTRAL | {"result", "files", "msgdefs"},
    "msgdefs": NEUTRAL,
    "checks": NEUTRAL | {"result", "files", "yaml_bounds", "outputs"},
    # diffing.render draws through outputs.console; compare and align import neither.
    "diffing": NEUTRAL | {"result", "files", "inputs", "outputs"},
    "fleet": NEUTRAL | {"result", "files", "inputs", "config", "pipeline", "checks", "outputs"},
    "pytest_plugin": NEUTRAL | {"result", "pipeline", "checks", "diffing", "outputs"},
    "commands": NEUTRAL
    | {"result", "files", "inputs", "config", "pipeline", "checks", "diffing", "fleet", "outputs"},
    "cli": {"commands", "errors", "outputs", "version"},
    "__init__": {"errors", "version", "pipeline", "result", "outputs"},
}
"""For every package and top-level module of medkit_replay: what of ours it may import."""


def _unit(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def imports_by_unit() -> dict[str, dict[str, set[str]]]:
    """unit -> imported unit -> the modules importing it (every import, also lazy or typing)."""
    found: dict[str, dict[str, set[str]]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        module = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        module = module.removesuffix(".__init__")
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module == "medkit_replay":
                names = [f"medkit_replay.{alias.name}" for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names = [node.module]
            else:
                continue
            for name in names:
                if name == "medkit_replay" or name.startswith("medkit_replay."):
                    source, target = _unit(module), _unit(name)
                    if source != target:
                        found.setdefault(source, {}).setdefault(target, set()).add(module)
    return found


def test_every_unit_is_declared() -> None:
    units = {
        _unit(".".join(p.relative_to(PACKAGE.parent).with_suffix("").parts))
        for p in PACKAGE.rglob("*.py")
    }
    units.discard("__main__")
    assert sorted(units - set(ALLOWED)) == []


def test_imports_follow_the_declared_table() -> None:
    broken = {
        f"{module} -> medkit_replay.{target}"
        for source, targets in imports_by_unit().items()
        for target, modules in targets.items()
        if target not in ALLOWED.get(source, set())
        for module in modules
    }
    assert sorted(broken) == []


def test_no_relative_imports() -> None:
    for path in PACKAGE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            assert not (isinstance(node, ast.ImportFrom) and node.level), path


def _imported(path: Path) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
    return names


@pytest.mark.parametrize("module", ["compare.py", "align.py", "reports.py"])
def test_the_diff_itself_draws_nothing(module: str) -> None:
    imported = _imported(PACKAGE / "diffing" / module)
    assert not [n for n in imported if n.startswith(("rich", "medkit_replay.outputs"))]
