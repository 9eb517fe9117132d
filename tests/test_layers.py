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


def test_waiting_for_a_growing_recording_is_the_only_clock_of_inputs_and_pipeline() -> None:
    # follow mode polls with time.monotonic/time.sleep in inputs/follow.py, a remote read
    # waits before a retry in inputs/remote/store.py and measures a stalled transfer's speed in
    # inputs/remote/fetch.py; what the replay computes keeps bag time
    # (the pipeline reads no clock either).
    root = Path(__file__).resolve().parents[1] / "medkit_replay"
    users = sorted(
        str(path.relative_to(root))
        for folder in ("inputs", "pipeline")
        for path in (root / folder).rglob("*.py")
        if any(needle in path.read_text() for needle in ("import time", "monotonic", "sleep("))
    )
    assert users == ["inputs/follow.py", "inputs/remote/fetch.py", "inputs/remote/store.py"]


def test_remote_clients_load_only_for_remote_inputs() -> None:
    """inputs.remote loads with the first URL opened, never with a local replay; even then
    obstore (the 'remote' extra) and boto3 load only when a store is asked for."""
    local = loaded_after("medkit_replay.pipeline")
    assert sorted(m for m in local if m.startswith("medkit_replay.inputs.remote")) == []
    loaded = loaded_after("medkit_replay.inputs.remote.bag")
    assert "medkit_replay.inputs.ranges" in loaded
    assert sorted(m for m in loaded if m.startswith(("obstore", "boto3", "botocore"))) == []


def test_bridges_do_not_import_outputs_or_inputs() -> None:
    loaded = loaded_after("medkit_replay.bridges")
    bad = sorted(
        m
        for m in loaded
        if m.startswith(("medkit_replay.outputs", "medkit_replay.inputs", "pandas"))
    )
    assert bad == []


# -- start-up: what a command that only prints loads --------------------------------------

HEAVY_AT_START = (
    "pandas",
    "pyarrow",
    "dask",
    "distributed",
    "numpy",
    "rosbags",
    "mcap",
    "yaml",
    "rich",
    "msgspec",
    "zstandard",
    "medkit_replay.pipeline",
    "medkit_replay.inputs",
    "medkit_replay.engine",
    "medkit_replay.bridges",
    "medkit_replay.config",
    "medkit_replay.checks",
    "medkit_replay.diffing",
    "medkit_replay.fleet",
    "medkit_replay.outputs.html",
    "medkit_replay.outputs.mcap_events",
    "medkit_replay.outputs.json_report",
    "medkit_replay.outputs.tables",
    "medkit_replay.outputs.terminal",
    "medkit_replay.outputs.progress",
    "medkit_replay.gateway",
    "starlette",
    "uvicorn",
)
"""Loaded only when a command runs: none of it is needed to print a version or a help text."""


@pytest.mark.parametrize(
    "arguments",
    [
        ["--version"],
        ["--help"],
        ["analyze", "--help"],
        ["check", "--help"],
        ["diff", "--help"],
        ["explain", "--help"],
        ["fleet", "--help"],
        ["follow", "--help"],
        ["sweep", "--help"],
        ["suggest-rules", "--help"],
        ["validate", "--help"],
        ["serve", "--help"],
    ],
)
def test_printing_commands_load_nothing_heavy(arguments: list[str]) -> None:
    """The console script's path, in a fresh interpreter; modules listed once it is done."""
    code = (
        "import json, sys\n"
        "from medkit_replay.cli import main\n"
        f"status = main({arguments!r})\n"
        "sys.stderr.write(json.dumps([status, sorted(sys.modules)]))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    status, loaded = json.loads(done.stderr)
    assert status == 0
    assert done.stdout.strip()  # it printed its version or help
    assert sorted(m for m in loaded if m.startswith(HEAVY_AT_START)) == []


# -- the declared import table ------------------------------------------------------------

PACKAGE = Path(__file__).resolve().parents[1] / "medkit_replay"

NEUTRAL = {
    "model",
    "rows",
    "captures",
    "errors",
    "version",
    "text",
    "wildcards",
    "releases",
    "jsonio",
    "closing",
}
"""Values and vocabulary every layer may use; they import nothing of ours but each other."""
ALLOWED: dict[str, set[str]] = {
    "model": {"rows"},
    "rows": set(),
    "captures": set(),
    "errors": set(),
    "version": set(),
    "text": {"model"},
    "wildcards": set(),
    "releases": set(),
    "jsonio": set(),
    "closing": set(),
    "files": {"errors"},
    "yaml_bounds": {"errors", "text"},
    "spool": {"errors"},
    "result": {"model", "captures", "releases"},
    "trace": {"model"},
    "history": {"model"},
    "engine": {"model", "rows", "wildcards", "releases"},
    "bridges": {"model", "engine", "trace", "releases"},
    "inputs": {
        "model",
        "errors",
        "files",
        "yaml_bounds",
        "text",
        "msgdefs",
        "releases",
        "jsonio",
        "closing",
    },
    # config reads parameters into the settings types of the layers it configures.
    "config": {
        "model",
        "errors",
        "files",
        "yaml_bounds",
        "text",
        "engine",
        "bridges",
        "evidence",
        "releases",
    },
    # evidence plans captures from a Result's records and reads them back from the inputs.
    "evidence": NEUTRAL | {"files", "yaml_bounds", "inputs", "msgdefs"},
    "parity": {"model", "bridges", "config", "releases"},
    "pipeline": NEUTRAL
    | {
        "spool",
        "result",
        "parity",
        "engine",
        "bridges",
        "inputs",
        "config",
        "trace",
        "evidence",
        "history",
    },
    # explaining reads a Result and the FaultTrace the replay filled; it draws through outputs.
    "explaining": NEUTRAL | {"result", "trace", "outputs"},
    "outputs": NEUTRAL | {"result", "files", "msgdefs", "spool"},
    "msgdefs": NEUTRAL,
    "checks": NEUTRAL | {"result", "files", "yaml_bounds", "outputs"},
    # diffing.render draws through outputs.console; compare and align import neither.
    "diffing": NEUTRAL | {"result", "files", "outputs"},
    "fleet": NEUTRAL | {"result", "files", "inputs", "config", "pipeline", "checks", "outputs"},
    # tuning drives several engines through the pipeline's one pass, and runs like a fleet.
    "tuning": NEUTRAL
    | {"result", "files", "spool", "config", "engine", "pipeline", "checks", "fleet", "outputs"},
    # gateway answers the gateway's REST API from a Result and its FaultHistory; it reuses the
    # engine's query rules (ListFaults) and reads the node graph's type; the event stream
    # resumes a spooled event log from its chunk (Spool.iter_from).
    "gateway": NEUTRAL | {"result", "history", "engine", "evidence", "spool"},
    "pytest_plugin": NEUTRAL | {"result", "pipeline", "checks", "diffing", "outputs"},
    "commands": NEUTRAL
    | {
        "result",
        "files",
        "inputs",
        "config",
        "pipeline",
        "checks",
        "diffing",
        "fleet",
        "outputs",
        "explaining",
        "trace",
        "evidence",
        "tuning",
        "history",
        "gateway",
    },
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


VERDICTS = ("checks", "diffing", "pytest_plugin")
"""Verdicts on reports and replays: they judge what a replay produced, never a recording."""


@pytest.mark.parametrize("unit", VERDICTS)
def test_verdicts_import_nothing_from_inputs(unit: str) -> None:
    assert "inputs" not in ALLOWED[unit]
    assert "inputs" not in imports_by_unit().get(unit, {})


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


PURE_INPUT_MODULES = {
    # ROS 1 bags: the record parser and the ROS 1 -> ROS 2 message mapping; ros1/bag.py reads.
    "ros1/records.py": set(),
    "ros1/messages.py": {"medkit_replay.msgdefs", "medkit_replay.inputs.selection"},
    "ros1/decoders.py": {"medkit_replay.inputs.ros1.messages"},
    # MCAP chunks read by index: the plan of a chunk and the read-ahead window (hints only).
    "mcap/plan.py": set(),
    # MCAP time windows: which chunks, and their messages merged in log-time order.
    "mcap/window.py": {"medkit_replay.inputs.mcap.plan", "medkit_replay.inputs.merge"},
    # MCAP records: opcodes, layouts, the bounded cursor; the readers around them read.
    "mcap/records.py": {"medkit_replay.inputs.mcap.plan", "medkit_replay.inputs.storage"},
}
"""Modules of inputs that parse or map values they are given: no file access, few imports."""


@pytest.mark.parametrize("module", sorted(PURE_INPUT_MODULES))
def test_pure_input_modules_read_no_files(module: str) -> None:
    path = PACKAGE / "inputs" / module
    ours = {n for n in _imported(path) if n.startswith("medkit_replay")}
    assert ours <= PURE_INPUT_MODULES[module]
    text = path.read_text(encoding="utf-8")
    for needle in ("open(", "Path", "os."):
        assert needle not in text, f"{module} uses {needle}"


INPUT_FORMATS = ["cdr", "mcap", "remote", "ros1", "sqlite"]
"""The subpackages of inputs, one per format (or the CDR decoders all formats but ROS 1 share);
what every format shares is at inputs/ itself."""


def test_inputs_are_split_by_format_each_saying_its_job_in_one_line() -> None:
    root = PACKAGE / "inputs"
    found = sorted(p.parent.name for p in root.glob("*/__init__.py"))
    assert found == INPUT_FORMATS
    for name in INPUT_FORMATS:
        tree = ast.parse((root / name / "__init__.py").read_text(encoding="utf-8"))
        docstring = ast.get_docstring(tree)
        assert docstring is not None, name
        assert "\n" not in docstring.strip(), name
        assert len(tree.body) == 1, f"inputs/{name}/__init__.py holds more than its docstring"


MAX_MODULE_LINES = 500


def test_no_input_module_is_over_500_lines() -> None:
    long = {
        str(path.relative_to(PACKAGE)): lines
        for path in (PACKAGE / "inputs").rglob("*.py")
        if (lines := len(path.read_text(encoding="utf-8").splitlines())) > MAX_MODULE_LINES
    }
    assert long == {}
