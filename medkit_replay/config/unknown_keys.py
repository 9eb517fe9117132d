"""Names in parameter files that upstream would ignore: node names near a modelled node, and
parameters a modelled node does not declare at the release modelled (config/declared.py).

Warnings only: upstream ignores both, and so does the replay.
"""

from __future__ import annotations

from functools import partial
from typing import TYPE_CHECKING

from medkit_replay.config.declared import DECLARED
from medkit_replay.config.params import KNOWN_NODES
from medkit_replay.errors import ConfigWarning
from medkit_replay.releases import RELEASES
from medkit_replay.text import closest
from medkit_replay.yaml_bounds import shown_text

if TYPE_CHECKING:
    from collections.abc import Callable
    from pathlib import Path

    from medkit_replay.config.params import ParameterSet
    from medkit_replay.releases import Release

NODE_CUTOFF = 0.8
"""A node name is "near" a modelled node when difflib's ratio of the two is at least this
(``fault_manger`` 0.96, ``diagnostics_bridge`` 0.97; ``diagnostic_aggregator`` 0.68 is not)."""
REPLAY_NODE = "medkit_replay"
MAX_LISTED = 100
"""Ignored names listed one by one; any more are counted in one last warning."""


def declares(node: str, name: str, release: str) -> bool:
    """Whether ``node`` declares (or reads) parameter ``name`` at ``release``."""
    known = DECLARED[release][node]
    return name in known or any(
        k.endswith(".*") and name.startswith(k[:-1]) and len(name) > len(k) - 1 for k in known
    )


def near_node(name: str) -> str | None:
    """The modelled node ``name`` is near (and not equal to), or None."""
    return None if name in KNOWN_NODES else closest(name, KNOWN_NODES, NODE_CUTOFF)


def undeclared(node: str, name: str, release: Release) -> tuple[str, str | None] | None:
    """Why ``node`` ignores ``name`` at ``release`` and the closest declared name; None when
    it declares it."""
    return None if declares(node, name, release.name) else _why(node, name, release)


def _why(node: str, name: str, release: Release) -> tuple[str, str | None]:
    quoted = repr(shown_text(name))
    order = list(RELEASES)
    others = [r for r in order if declares(node, name, r)]
    if others:
        newer = [r for r in others if order.index(r) > order.index(release.name)]
        span = f"from {newer[0]} on" if newer else f"up to {others[-1]}"
        problem = (
            f"{node} has no parameter {quoted} at ros2_medkit {release.name}: "
            f"it is declared {span}; {release.name} ignores it"
        )
        return problem, None
    suggestion = closest(name, _plain(DECLARED[release.name][node]))
    hint = f" (did you mean {suggestion!r}?)" if suggestion else ""
    if node == REPLAY_NODE:
        return f"{node} has no parameter {quoted}{hint}; the replay ignores it", suggestion
    problem = f"{node} has no parameter {quoted} at ros2_medkit {release.name}{hint}; "
    return problem + "upstream ignores it", suggestion


def _not_modelled(node: str, near: str) -> tuple[str, str | None]:
    problem = f"node {shown_text(node)!r} is not a node the replay models; did you mean {near!r}?"
    return problem, near


def _plain(names: frozenset[str]) -> list[str]:
    return sorted(n for n in names if not n.endswith(".*"))


def unknown_keys(params: ParameterSet, release: Release) -> list[ConfigWarning]:
    """Every ignored name in the parameter files, in file order; past ``MAX_LISTED`` of them,
    one more saying how many others there are.

    Only sections naming a node outright are looked at: a wildcard section (``/**``) is for
    every node of a robot, and a node name far from the modelled ones is another node's.
    """
    found: list[ConfigWarning] = []
    more: list[tuple[Path, int]] = []

    def add(path: Path, line: int, why: Callable[[], tuple[str, str | None]]) -> None:
        if len(found) < MAX_LISTED:
            problem, suggestion = why()
            found.append(ConfigWarning(problem, path=str(path), line=line, suggestion=suggestion))
        else:  # only counted: finding the closest name for each costs time
            more.append((path, line))

    for section in params.sections:
        node = section.node_name
        if "*" in node:
            continue
        if node not in KNOWN_NODES:
            near = near_node(node)
            if near is not None:
                add(section.path, section.line, partial(_not_modelled, node, near))
            continue
        for name, param in section.params.items():
            if not declares(node, name, release.name):
                add(param.path, param.line, partial(_why, node, name, release))
    if more:
        problem = (
            f"{len(more):,} more names upstream ignores from here on "
            f"(the first {MAX_LISTED} are listed)"
        )
        path, line = more[0]
        found.append(ConfigWarning(problem, path=str(path), line=line))
    return found
