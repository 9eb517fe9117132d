"""ROS 2 parameter files in, one flat parameter table per node out, each value with file and line.

Reads YAML only; knows nothing of what the parameters mean (see fault_manager.py and the bridges).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import yaml

from medkit_replay.errors import ConfigError
from medkit_replay.files import read_limited
from medkit_replay.yaml_bounds import (
    compose_config,
    shown_text,
)

if TYPE_CHECKING:
    from collections.abc import Iterable, Mapping

KNOWN_NODES = (
    "fault_manager",
    "diagnostic_bridge",
    "action_status_bridge",
    "log_bridge",
    "medkit_replay",
)
ParamValue = bool | int | float | str | list[bool] | list[int] | list[float] | list[str] | None

_BOOL_TRUE = {"true", "True", "TRUE", "yes", "Yes", "YES", "on", "On", "ON", "y", "Y"}
_BOOL_FALSE = {"false", "False", "FALSE", "no", "No", "NO", "off", "Off", "OFF", "n", "N"}
_INT = re.compile(r"[-+]?[0-9]+")
_FLOAT = re.compile(
    r"[-+]?(?:[0-9]+\.[0-9]*|\.[0-9]+|[0-9]+)(?:[eE][-+]?[0-9]+)?|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN)"
)
_NULL = {"", "~", "null", "Null", "NULL"}
_INT64_MAX = 2**63 - 1
_INT64_DIGITS = len(str(_INT64_MAX))


@dataclass(frozen=True, slots=True)
class Param:
    """One parameter value and where it was written."""

    value: ParamValue
    path: Path
    line: int

    def error(self, name: str, problem: str) -> ConfigError:
        """A ConfigError pointing at this parameter's file and line."""
        return ConfigError(f"{shown_text(name)}: {problem}", path=str(self.path), line=self.line)


NodeParams = dict[str, Param]


def _scalar(node: yaml.ScalarNode) -> bool | int | float | str | None:
    """Type a scalar the way ROS 2's parameter-file parser does: quoted text stays a string."""
    text = str(node.value)
    if node.style is not None and node.style != "":
        return text
    if text in _NULL:
        return None
    if text in _BOOL_TRUE:
        return True
    if text in _BOOL_FALSE:
        return False
    if _INT.fullmatch(text):
        digits = text.lstrip("+-").lstrip("0")
        if len(digits) <= _INT64_DIGITS:
            value = int(text)
            if -_INT64_MAX - 1 <= value <= _INT64_MAX:
                return value
        # rcl's parser: strtoll overflows (ERANGE), so the text is tried as a double.
        return _double(text)
    if _FLOAT.fullmatch(text):
        lowered = text.lower()
        if lowered.endswith((".inf", ".nan")):
            return float(lowered.replace(".", ""))
        return _double(text)
    return text


def _double(text: str) -> float | str:
    """rcl's strtod step: a number past the double range (ERANGE) stays a string parameter."""
    value = float(text)
    return text if math.isinf(value) else value


def _value(node: yaml.Node, path: Path, name: str) -> ParamValue:
    if isinstance(node, yaml.ScalarNode):
        return _scalar(node)
    if isinstance(node, yaml.SequenceNode):
        items: list[bool | int | float | str] = []
        for item in node.value:
            if not isinstance(item, yaml.ScalarNode):
                msg = f"{shown_text(name)}: arrays of maps or arrays are not ROS 2 parameters"
                raise ConfigError(msg, path=str(path), line=item.start_mark.line + 1)
            value = _scalar(item)
            if value is None:
                raise ConfigError(
                    f"{shown_text(name)}: null inside an array",
                    path=str(path),
                    line=item.start_mark.line + 1,
                )
            items.append(value)
        kinds = {type(v) for v in items}
        if len(kinds) > 1:
            mixed = ", ".join(sorted(k.__name__ for k in kinds))
            msg = f"{shown_text(name)}: array mixes {mixed} values"
            raise ConfigError(msg, path=str(path), line=node.start_mark.line + 1)
        return items  # type: ignore[return-value]  # homogeneous, checked above
    msg = f"{shown_text(name)}: unexpected YAML node"
    raise ConfigError(msg, path=str(path), line=node.start_mark.line + 1)


def _flatten(node: yaml.Node, path: Path, prefix: str, out: NodeParams) -> None:
    """Nested maps and dotted names are the same parameter: ``a: {b: 1}`` ≡ ``a.b: 1``."""
    if isinstance(node, yaml.MappingNode):
        for key_node, value_node in node.value:
            key = _key(key_node, path)
            name = f"{prefix}.{key}" if prefix else key
            _flatten(value_node, path, name, out)
        return
    out[prefix] = Param(_value(node, path, prefix), path, node.start_mark.line + 1)


def _key(node: yaml.Node, path: Path) -> str:
    """A map key's text; a list or map as a key names no parameter and no node."""
    if not isinstance(node, yaml.ScalarNode):
        msg = "a map key must be a name, not a list or map"
        raise ConfigError(msg, path=str(path), line=node.start_mark.line + 1)
    return str(node.value)


def _node_matches(pattern: str, node_name: str) -> bool:
    """Match a node key (``fault_manager``, ``/ns/fault_manager``, ``/**``, ``/**/x``)."""
    segments = [s for s in pattern.strip("/").split("/") if s]
    if not segments:
        return False
    last = segments[-1]
    if last == "**":
        return True
    regex = re.escape(last).replace(r"\*", ".*")
    return re.fullmatch(regex, node_name) is not None


def _collect(
    node: yaml.MappingNode,
    path: Path,
    keys: list[str],
    found: list[tuple[str, int, yaml.Node]],
    line: int = 1,
) -> None:
    """Every ``ros__parameters`` map with its node key and the line of that key."""
    for key_node, value_node in node.value:
        key = _key(key_node, path)
        if key == "ros__parameters":
            name = "/" + "/".join(k.strip("/") for k in keys)
            found.append((name, line if keys else key_node.start_mark.line + 1, value_node))
        elif isinstance(value_node, yaml.MappingNode):
            _collect(value_node, path, [*keys, key], found, key_node.start_mark.line + 1)
        else:
            where = shown_text("/".join([*keys, key]))
            msg = f"{where}: expected a node name holding ros__parameters"
            raise ConfigError(msg, path=str(path), line=key_node.start_mark.line + 1)


def _wrong_kind(err: ConfigError, root: yaml.MappingNode) -> ConfigError:
    """The error for a file that is not a parameter file, saying which kind it looks like."""
    from yaml.constructor import ConstructorError, SafeConstructor  # noqa: PLC0415

    from medkit_replay.config.kinds import belongs, guess_kind  # noqa: PLC0415

    try:
        kind = guess_kind(SafeConstructor().construct_document(root))
    except ConstructorError:
        kind = None
    if kind is None or kind == "parameters":
        return err
    problem = f"{belongs(kind, '--config')} ({err.problem})"
    return ConfigError(problem, path=err.path, line=err.line)


def parse_value(text: str, name: str, where: str) -> ParamValue:
    """One parameter value written on a command line, typed as in a parameter file (``-3`` an
    integer, ``3.0`` a double, ``'3'`` a string, ``[a, b]`` an array).

    Raises:
        ConfigError: not a single YAML scalar or flat array; ``where`` names the text.
    """
    node = compose_config(text, where)
    if node is None:
        return None
    return _value(node, Path(where), name)


@dataclass(frozen=True, slots=True)
class Section:
    """One node section of a parameter file: its key (``/ns/node``, ``/**``), where the key is
    written, and its flat parameters."""

    key: str
    path: Path
    line: int
    params: NodeParams

    @property
    def node_name(self) -> str:
        """The key's last segment: the node name, or a wildcard (``**``, ``fault_*``)."""
        return self.key.rstrip("/").rsplit("/", 1)[-1]


def load_sections(path: Path) -> list[Section]:
    """Parse one ROS 2 parameter file into its node sections, in file order."""
    try:
        data = read_limited(path)
    except FileNotFoundError:
        raise ConfigError("config file not found", path=str(path)) from None
    except OSError as err:  # a FIFO, device, directory or oversized file too
        raise ConfigError(f"cannot read config file: {err}", path=str(path)) from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        at = data.count(b"\n", 0, err.start) + 1
        raise ConfigError(f"cannot read config file: {err}", path=str(path), line=at) from None
    try:
        root = compose_config(text, str(path))
    except ConfigError as err:
        from medkit_replay.config.kinds import belongs, guess_text_kind  # noqa: PLC0415

        if guess_text_kind(text, str(path)) != "graph":
            raise
        problem = f"{belongs('graph', '--config')} ({err.problem})"
        raise ConfigError(problem, path=str(path)) from None
    if root is None:
        return []
    if not isinstance(root, yaml.MappingNode):
        msg = "expected a ROS 2 parameter file: node names mapping to ros__parameters"
        raise ConfigError(msg, path=str(path), line=root.start_mark.line + 1)
    found: list[tuple[str, int, yaml.Node]] = []
    try:
        _collect(root, path, [], found)
    except ConfigError as err:
        raise _wrong_kind(err, root) from None
    result: list[Section] = []
    for node_key, line, params_node in found:
        params: NodeParams = {}
        if isinstance(params_node, yaml.MappingNode):
            _flatten(params_node, path, "", params)
        elif not (isinstance(params_node, yaml.ScalarNode) and params_node.value in _NULL):
            msg = f"{shown_text(node_key)}: ros__parameters must be a map"
            raise ConfigError(msg, path=str(path), line=params_node.start_mark.line + 1)
        result.append(Section(node_key, path, line, params))
    return result


@dataclass(frozen=True, slots=True)
class ParameterSet:
    """Merged parameters per recognised node; later files override earlier ones key by key."""

    nodes: Mapping[str, NodeParams]
    files: tuple[Path, ...]
    named: frozenset[str] = frozenset()
    sections: tuple[Section, ...] = ()
    """Every node section of the files as written, for checks of names (config/unknown_keys.py)."""

    def node(self, name: str) -> NodeParams:
        """Parameters of one node (empty when the config never names it)."""
        return dict(self.nodes.get(name, {}))

    def mentions(self, name: str) -> bool:
        """True when some file has a section naming this node itself (not through a wildcard)."""
        return name in self.named


def load_parameters(paths: Iterable[Path]) -> ParameterSet:
    """Load and merge parameter files in order (cli-and-report.md §2)."""
    nodes: dict[str, NodeParams] = {}
    files: list[Path] = []
    named: set[str] = set()
    sections: list[Section] = []
    for path in paths:
        files.append(path)
        for section in load_sections(path):
            sections.append(section)
            for name in KNOWN_NODES:
                if _node_matches(section.key, name):
                    nodes.setdefault(name, {}).update(section.params)
                    if section.node_name == name:
                        named.add(name)
    return ParameterSet(nodes, tuple(files), frozenset(named), tuple(sections))
