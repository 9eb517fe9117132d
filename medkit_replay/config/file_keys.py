"""Unknown keys in the YAML files upstream reads without a schema (correlation, entity-threshold
and snapshot files): a warning each, with file, line and the closest known key.

Upstream ignores a key it does not read, so a typo silently leaves its default in force.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from yaml.nodes import MappingNode, ScalarNode

from medkit_replay.errors import ConfigWarning
from medkit_replay.text import closest, name_hint
from medkit_replay.yaml_bounds import shown_text

if TYPE_CHECKING:
    from collections.abc import Sequence

    from yaml.nodes import Node


def unknown_map_keys(
    node: Node | None, known: Sequence[str], path: str, where: str
) -> list[ConfigWarning]:
    """A warning for each key of the map ``node`` not in ``known`` (none when ``node`` is not a
    map); ``where`` names the map in the message (``correlation``, ``rule 'x'``)."""
    if not isinstance(node, MappingNode):
        return []
    found: list[ConfigWarning] = []
    for key_node, _ in node.value:
        if not isinstance(key_node, ScalarNode) or key_node.value in known:
            continue
        key = str(key_node.value)
        line = None if key_node.start_mark is None else key_node.start_mark.line + 1
        meant = closest(key, known)
        hint = name_hint(meant, known)
        found.append(
            ConfigWarning(
                f"{where}: unknown key '{shown_text(key)}' ({hint}); upstream ignores it",
                path=path,
                line=line,
                suggestion=meant,
            )
        )
    return found
