"""A sweep's grid: ``--vary NODE.PARAM=V1,V2,...`` specs typed as ROS parameters, and their product.

Each variant is the layered base config with one value per varied parameter on top, checked as a
replay reads it: a bad name or value is one ConfigError naming the ``--vary`` it came from.
"""

from __future__ import annotations

import itertools
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, cast

from medkit_replay.config.fault_manager import fault_manager_config
from medkit_replay.config.params import KNOWN_NODES, Param, ParameterSet, parse_value
from medkit_replay.config.referenced import FILE_PARAMETERS
from medkit_replay.config.release import release_of
from medkit_replay.config.replay_options import replay_options
from medkit_replay.config.unknown_keys import near_node, undeclared
from medkit_replay.errors import ConfigError

if TYPE_CHECKING:
    from collections.abc import Sequence

    from medkit_replay.config.params import ParamValue
    from medkit_replay.config.replay_options import ReplayOptions
    from medkit_replay.engine.manager import FaultManagerConfig

VARY_SOURCE = Path("--vary")
"""Where a varied value was written, for the config layer: file-valued ones resolve beside it
(the current folder)."""
MAX_VARIANTS = 100_000
"""A larger grid is refused: it is almost surely a typo (and each variant is a replay)."""
DEFAULT_MAX_RUNS = 20_000
"""Replays a sweep runs at most, variants x recordings (``--max-runs``). Each is a fault manager
built, fed and summed: about half a millisecond and 10 KB on a 20-line script (10,000 runs take
5 s and 130 MB in one process), more on a long recording. A grid past it is refused before
anything runs, as one that would not finish in reasonable time."""
_UNREAD = object()
"""A value of no parameter type: every reader refuses it, which shows the name is read."""


@dataclass(frozen=True, slots=True)
class Vary:
    """One ``--vary``: a node's parameter and the values it takes, as written and typed."""

    node: str
    name: str
    texts: tuple[str, ...]
    values: tuple[ParamValue, ...]

    @property
    def key(self) -> str:
        """``node.name``, the column that holds the value in the tables."""
        return f"{self.node}.{self.name}"

    @property
    def kind(self) -> str:
        """The tables' type of its column: ``int``, ``float``, ``bool`` when every value has
        that type, else ``str`` (the values as written)."""
        kinds = {type(v) for v in self.values}
        if len(kinds) == 1:
            only = kinds.pop()
            if only in (bool, int, float):
                return only.__name__
        return "str"

    def cell(self, setting: Setting) -> object:
        """The value of ``setting`` (one of this parameter's) in its column."""
        return setting.value if self.kind != "str" else setting.text


@dataclass(frozen=True, slots=True)
class Setting:
    """One varied parameter's value in one variant."""

    node: str
    name: str
    value: ParamValue
    text: str


@dataclass(frozen=True, slots=True)
class Variant:
    """One point of the grid: ``v01``... and the settings that make it."""

    index: int
    settings: tuple[Setting, ...]

    @property
    def id(self) -> str:
        """``v01``, ``v02``... (as many digits as the largest grid index needs)."""
        return f"v{self.index + 1:02d}"

    @property
    def label(self) -> str:
        """``confirmation_threshold=-3 healing_threshold=1``: the values, by parameter name."""
        return " ".join(f"{s.name}={s.text}" for s in self.settings)


def split_values(text: str) -> list[str]:
    """``-1,-3,[a, b],'x,y'`` into its values: commas inside brackets or quotes do not split."""
    values: list[str] = []
    depth, quote, start = 0, "", 0
    for at, char in enumerate(text):
        if quote:
            quote = "" if char == quote else quote
        elif char in "'\"":
            quote = char
        elif char == "[":
            depth += 1
        elif char == "]":
            depth -= 1
        elif char == "," and depth == 0:
            values.append(text[start:at].strip())
            start = at + 1
    values.append(text[start:].strip())
    return values


def parse_vary(spec: str) -> Vary:
    """Parse one ``NODE.PARAM=V1,V2,...``.

    A file-valued parameter (``fault_manager.correlation.config_file``) takes paths relative to
    the current folder; an empty value there is the empty string (the feature off).

    Raises:
        ConfigError: no ``=``, an unknown node, a value that is not a parameter value, a value
            given twice.
    """
    where = f"--vary {spec}"
    target, equals, listed = spec.partition("=")
    node, dot, name = target.strip().partition(".")
    if not equals or not dot or not name:
        raise ConfigError(
            "expected NODE.PARAM=V1,V2,... (e.g. fault_manager.healing_threshold=1,3)", path=where
        )
    if node not in KNOWN_NODES:
        near = near_node(node)
        hint = f"did you mean {near!r}?" if near else f"known: {', '.join(KNOWN_NODES)}"
        raise ConfigError(f"unknown node {node!r} ({hint})", path=where)
    texts = split_values(listed)
    if len(set(texts)) != len(texts):
        raise ConfigError("a value is listed twice", path=where)
    file_valued = node == "fault_manager" and name in FILE_PARAMETERS
    values: list[ParamValue] = []
    for text in texts:
        if file_valued:
            values.append(str(Path(text).absolute()) if text else "")
        else:
            values.append(parse_value(text, name, where))
    return Vary(node, name, tuple(texts), tuple(values))


def make_grid(varies: Sequence[Vary]) -> list[Variant]:
    """Every combination of the varied values, the first ``--vary`` changing slowest.

    Raises:
        ConfigError: a parameter varied twice, or a grid past MAX_VARIANTS.
    """
    keys = [v.key for v in varies]
    for key in keys:
        if keys.count(key) > 1:
            raise ConfigError(f"{key} is varied twice (list all its values in one --vary)")
    grid_size(varies)
    choices = [
        [
            Setting(v.node, v.name, value, text)
            for value, text in zip(v.values, v.texts, strict=True)
        ]
        for v in varies
    ]
    return [Variant(i, tuple(c)) for i, c in enumerate(itertools.product(*choices))]


def grid_size(varies: Sequence[Vary]) -> int:
    """How many variants the grid has.

    Raises:
        ConfigError: more than MAX_VARIANTS.
    """
    size = math.prod(len(vary.values) for vary in varies)
    if size > MAX_VARIANTS:
        raise ConfigError(f"the grid has {size:,} variants; at most {MAX_VARIANTS:,} are run")
    return size


def check_runs(varies: Sequence[Vary], recordings: int, max_runs: int | None = None) -> None:
    """Refuse, before anything runs, a grid whose replays (variants x recordings) pass
    ``max_runs`` (None: DEFAULT_MAX_RUNS).

    Raises:
        ConfigError: too many variants or replays, said in one line with what to change.
    """
    size = grid_size(varies)
    max_runs = DEFAULT_MAX_RUNS if max_runs is None else max_runs
    if size * recordings > max_runs:
        raise ConfigError(
            f"the grid has {size:,} variants x {recordings:,} recording(s) = "
            f"{size * recordings:,} replays, more than --max-runs {max_runs:,}: vary fewer "
            "values, or raise --max-runs"
        )


def variant_parameters(base: ParameterSet, settings: Sequence[Setting]) -> ParameterSet:
    """The base parameters with the settings on top (as a last config file would put them)."""
    nodes = {node: dict(params) for node, params in base.nodes.items()}
    for setting in settings:
        nodes.setdefault(setting.node, {})[setting.name] = Param(setting.value, VARY_SOURCE, 0)
    named = base.named | {s.node for s in settings}
    return ParameterSet(nodes, base.files, frozenset(named), base.sections)


@dataclass(frozen=True, slots=True)
class VariantConfig:
    """What a replay of one variant runs with, and what reading its config said."""

    manager: FaultManagerConfig
    options: ReplayOptions
    warnings: tuple[str, ...]


def variant_config(base: ParameterSet, variant: Variant) -> VariantConfig:
    """Read one variant's config as a replay would.

    Raises:
        ConfigError: a value the node refuses, naming the ``--vary`` setting it came from (or the
            file, for a problem inside a varied correlation or entity-thresholds file).
    """
    params = variant_parameters(base, variant.settings)
    try:
        release = release_of(params)
        manager, warnings = fault_manager_config(params.node("fault_manager"), release)
        options, option_warnings = replay_options(params, release)
    except ConfigError as err:
        if err.path != str(VARY_SOURCE):
            raise
        setting = next(
            (s for s in variant.settings if s.name == err.parameter), variant.settings[0]
        )
        raise ConfigError(
            err.problem, path=f"--vary {setting.node}.{setting.name}={setting.text}"
        ) from None
    return VariantConfig(manager, options, tuple(warnings + option_warnings))


def _reads(params: ParameterSet, node: str, name: str) -> bool:
    """Whether reading the config looks at ``node``'s parameter ``name``."""
    probe = Param(cast("ParamValue", _UNREAD), VARY_SOURCE, 0)
    nodes = {n: dict(p) for n, p in params.nodes.items()}
    nodes.setdefault(node, {})[name] = probe
    probed = ParameterSet(nodes, params.files, params.named | {node})
    try:
        release = release_of(probed)  # which parameters exist depends on the variant's release
        if node == "fault_manager":
            fault_manager_config(probed.node(node), release)
        else:
            replay_options(probed, release)
    except ConfigError as err:
        return err.parameter == name
    return False


def check_names(base: ParameterSet, varies: Sequence[Vary], grid: Sequence[Variant]) -> None:
    """Refuse a varied name no variant's config reads (a typo, or one unused with this config).

    Raises:
        ConfigError: naming the ``--vary``.
    """
    for vary in varies:
        if any(
            _reads(
                variant_parameters(
                    base, [s for s in v.settings if s.name != vary.name or s.node != vary.node]
                ),
                vary.node,
                vary.name,
            )
            for v in grid
        ):
            continue
        problem = _undeclared(base, vary, grid) or (
            f"{vary.node} reads no parameter {vary.name!r} (a typo, or unused with this config)"
        )
        raise ConfigError(problem, path=f"--vary {vary.key}")


def _undeclared(base: ParameterSet, vary: Vary, grid: Sequence[Variant]) -> str | None:
    """Why upstream ignores a varied name at the first variant's release, when it is declared
    at none of the variants' releases (config/declared.py); None otherwise."""
    first: str | None = None
    checked: set[str] = set()
    for variant in grid:
        try:
            release = release_of(variant_parameters(base, variant.settings))
        except ConfigError:  # a bad release is said by the variant's own check
            return None
        if release.name in checked:
            continue
        checked.add(release.name)
        why = undeclared(vary.node, vary.name, release)
        if why is None:
            return None
        first = first or why[0]
    return first


def yaml_value(value: ParamValue) -> str:
    """A typed parameter value written so that a parameter file types it back the same
    (strings double-quoted, doubles with a point or exponent, arrays in flow style)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return ".nan"
        if math.isinf(value):
            return ".inf" if value > 0 else "-.inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    return "[" + ", ".join(yaml_value(item) for item in value) + "]"


def variant_yaml(variant: Variant, folder: Path) -> str:
    """A ROS 2 parameter file that, given last after the base configs, makes this variant
    (``analyze --config base.yaml --config variants/v03.yaml``); file paths are written
    relative to ``folder``, where the file goes."""
    lines = [f"# {variant.id}: {variant.label}".replace("\n", " ").replace("\r", " ")]
    for node in sorted({s.node for s in variant.settings}):
        lines += [f"{node}:", "  ros__parameters:"]
        for setting in variant.settings:
            if setting.node != node:
                continue
            value = setting.value
            if setting.node == "fault_manager" and setting.name in FILE_PARAMETERS and value:
                value = os.path.relpath(str(value), folder.absolute())
            lines.append(f"    {json.dumps(setting.name)}: {yaml_value(value)}")
    return "\n".join(lines) + "\n"
