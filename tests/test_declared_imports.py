"""Every module the package imports comes from the standard library, the package itself or a
distribution pyproject.toml declares (a dependency, or an extra); every dependency is imported.
"""

from __future__ import annotations

import ast
import functools
import sys
import tomllib
from importlib.metadata import distribution, packages_distributions
from pathlib import Path
from typing import TYPE_CHECKING

from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

if TYPE_CHECKING:
    from collections.abc import Mapping

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "medkit_replay"
LATER_STDLIB = {"compression"}
"""The standard library's from Python 3.14 (``compression.zstd``), imported only there."""


def imports() -> dict[str, set[str]]:
    """Every absolute import in the package (``from a import b`` gives ``a`` and ``a.b``), with
    the files that make it."""
    found: dict[str, set[str]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        where = str(path.relative_to(ROOT))
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names: list[str] = []
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module, *(f"{node.module}.{alias.name}" for alias in node.names)]
            for name in names:
                found.setdefault(name, set()).add(where)
    return found


def third_party(found: dict[str, set[str]]) -> dict[str, set[str]]:
    """The imports from neither the standard library nor the package."""
    return {
        name: files
        for name, files in found.items()
        if (top := name.partition(".")[0]) not in sys.stdlib_module_names
        and top not in LATER_STDLIB
        and top != "medkit_replay"
    }


@functools.cache
def _installed() -> Mapping[str, list[str]]:
    """Top-level module -> the installed distributions holding it."""
    return packages_distributions()


def owners(module: str) -> set[str]:
    """The installed distributions that hold ``module`` (a namespace package such as
    ``backports`` is shared: then only the ones holding this module's own files)."""
    top, _, rest = module.partition(".")
    candidates = _installed().get(top, [])
    if len(candidates) <= 1 or not rest:
        return {canonicalize_name(name) for name in candidates}
    folder = module.replace(".", "/")
    return {
        canonicalize_name(name)
        for name in candidates
        if any(
            str(file).startswith((f"{folder}/", f"{folder}."))
            for file in distribution(name).files or []
        )
    }


def declared() -> tuple[dict[str, Requirement], dict[str, Requirement]]:
    """The dependencies, and the distributions of every extra, by canonical name."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    core = [Requirement(text) for text in project["dependencies"]]
    extra = [Requirement(t) for texts in project["optional-dependencies"].values() for t in texts]
    return (
        {canonicalize_name(r.name): r for r in core},
        {canonicalize_name(r.name): r for r in extra},
    )


def test_every_imported_distribution_is_declared() -> None:
    core, extras = declared()
    undeclared = []
    for module, files in sorted(third_party(imports()).items()):
        held = owners(module)
        if module.partition(".")[2] and not held:
            continue  # ``from a import b``, b a name inside a: ``a`` itself is checked
        assert held, f"{module} ({sorted(files)}) comes from no installed distribution"
        if not held & (core.keys() | extras.keys()):
            undeclared.append(f"{module} from {sorted(held)} in {sorted(files)}")
    assert undeclared == [], "imported, not declared in pyproject.toml: " + "; ".join(undeclared)


def test_every_dependency_is_imported() -> None:
    """A dependency no module imports any more (zstandard, once the reports are read with the
    zstd binding rosbags uses) is dropped from pyproject.toml."""
    core, _ = declared()
    imported = set().union(*(owners(module) for module in third_party(imports())))
    assert sorted(core.keys() - imported) == []


def test_the_zstd_binding_is_declared_where_the_standard_library_has_none() -> None:
    """Below Python 3.14 the package imports ``backports.zstd``, as rosbags 0.11.9 does, with
    the same markers; from 3.14, the standard library's ``compression.zstd``."""
    core, _ = declared()
    assert owners("backports.zstd") == {"backports-zstd"}
    requirement = core["backports-zstd"]
    assert str(requirement.marker) == 'python_version < "3.14"'
    rosbags = [Requirement(t) for t in distribution("rosbags").requires or []]
    assert [str(r.marker) for r in rosbags if r.name == "backports.zstd"] in (
        [],
        [str(requirement.marker)],
    )


def test_the_scan_sees_what_the_package_imports() -> None:
    found = third_party(imports())
    assert {"lz4.frame", "numpy", "backports", "backports.zstd", "yaml", "rosbags.rosbag2"} <= set(
        found
    )
    assert "compression" not in found and "os" not in found and "medkit_replay.cli" not in found
