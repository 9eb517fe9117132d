"""Regenerates the declared-parameter table from an upstream ros2_medkit git checkout and compares.

``python -m tests.config.declared_upstream [GIT_DIR]`` prints each node's names and any
difference from medkit_replay/config/declared.py (exit 1); without a checkout it says so (exit 0).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

from medkit_replay.config.declared import DECLARED, ROS_PARAMETERS
from medkit_replay.releases import RELEASES

MIRROR_ENV = "MEDKIT_UPSTREAM_GIT"
DEFAULT_MIRROR = Path("/work/.mirror/selfpatch+ros2_medkit/repo")
_REPORTER = "src/ros2_medkit_fault_reporter/src"
PACKAGES = {
    "fault_manager": ("src/ros2_medkit_fault_manager/src",),
    "diagnostic_bridge": ("src/ros2_medkit_diagnostic_bridge/src", _REPORTER),
    "action_status_bridge": ("src/ros2_medkit_action_status_bridge/src", _REPORTER),
    "log_bridge": ("src/ros2_medkit_log_bridge/src", _REPORTER),
}
"""Each upstream node's sources: its package, and the FaultReporter it builds on its node."""

# declare_parameter<std::vector<std::string>>("name", ...), has_parameter("name"), across lines.
_CALL = re.compile(
    r"\b(?:declare_parameter|get_parameter|has_parameter)\s*(?:<.*?>)?\s*\(\s*\"([^\"]+)\""
)
# Names read undeclared: get_parameter_overrides() filtered by a prefix string.
_PREFIX = re.compile(r"\bprefix\s*=\s*\"([^\"]+\.)\"")


def mirror() -> Path | None:
    """The upstream git directory, from ``MEDKIT_UPSTREAM_GIT`` or the default place."""
    path = Path(os.environ.get(MIRROR_ENV, DEFAULT_MIRROR))
    return path if (path / "HEAD").is_file() or (path / ".git").exists() else None


def _git(git_dir: Path, *args: str) -> str:
    return subprocess.run(
        ["git", "--git-dir" if (git_dir / "HEAD").is_file() else "-C", str(git_dir), *args],
        check=True,
        capture_output=True,
        text=True,
    ).stdout


def upstream_names(git_dir: Path, commit: str, node: str) -> dict[str, str]:
    """Parameter name -> ``file:line`` of its first declaration or read, at ``commit``."""
    found: dict[str, str] = {}
    for folder in PACKAGES[node]:
        listing = _git(git_dir, "ls-tree", "-r", "--name-only", commit, folder).split()
        for path in sorted(p for p in listing if p.endswith((".cpp", ".hpp"))):
            text = _git(git_dir, "show", f"{commit}:{path}")
            names = [(m.group(1), m.start()) for m in _CALL.finditer(text)]
            if "get_parameter_overrides" in text:
                names += [(m.group(1) + "*", m.start()) for m in _PREFIX.finditer(text)]
            for name, at in names:
                found.setdefault(name, f"{path}:{text.count(chr(10), 0, at) + 1}")
    return found


def compare(git_dir: Path) -> list[str]:
    """Differences between the table and upstream, one line each (empty: they agree)."""
    problems: list[str] = []
    for release_name, release in RELEASES.items():
        commit = release.commit.split("+", 1)[0]
        for node in PACKAGES:
            upstream = upstream_names(git_dir, commit, node)
            table = DECLARED[release_name][node] - ROS_PARAMETERS
            problems += [
                f"{release_name} {node}: upstream declares {name!r} ({upstream[name]}), "
                "the table does not"
                for name in sorted(set(upstream) - table)
            ]
            problems += [
                f"{release_name} {node}: the table has {name!r}, upstream ({commit}) does not"
                for name in sorted(table - set(upstream))
            ]
    return problems


def main(argv: list[str]) -> int:
    """Compare (or, with ``--print``, also list) and say what was found."""
    git_dir = Path(argv[0]) if argv and not argv[0].startswith("-") else mirror()
    if git_dir is None:
        print(f"skipped: no ros2_medkit git checkout at {DEFAULT_MIRROR} (set {MIRROR_ENV})")
        return 0
    if "--print" in argv:
        for release_name, release in RELEASES.items():
            commit = release.commit.split("+", 1)[0]
            for node in PACKAGES:
                for name, where in sorted(upstream_names(git_dir, commit, node).items()):
                    print(f"{release_name} {node} {name}  # {where}")
    problems = compare(git_dir)
    for problem in problems:
        print(problem)
    total = sum(len(nodes[n]) for nodes in DECLARED.values() for n in PACKAGES)
    print(f"{len(problems)} differences; the table holds {total} names for the upstream nodes")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
