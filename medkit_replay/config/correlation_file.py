"""The correlation YAML read as upstream's config_parser reads it, and loaded as the node loads it.

Parsing follows correlation.md §2 (yaml-cpp 0.7 rules); loading follows §1.1 (never fatal).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from medkit_replay.config.file_keys import unknown_map_keys
from medkit_replay.config.yamlcpp import (
    MAX_FILE_BYTES,
    YamlCppError,
    as_bool,
    as_string,
    as_uint32,
    compose,
    is_map,
    is_scalar,
    is_sequence,
    line_of,
    map_items,
    sequence_items,
    subscript,
)
from medkit_replay.engine.correlation.rules import (
    CorrelationConfig,
    CorrelationRule,
    Mode,
    Representative,
    string_to_mode,
    string_to_representative,
    validate_config,
)
from medkit_replay.errors import ConfigWarning
from medkit_replay.files import read_limited
from medkit_replay.yaml_bounds import shown_text

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.config.yamlcpp import Node

_OFF = "correlation is off for this run"

# The keys upstream's parser reads (correlation.md §2); a rule's keys depend on its mode.
_TOP_KEYS = ("correlation",)
_CORRELATION_KEYS = ("enabled", "default_window_ms", "patterns", "rules")
_RULE_KEYS = ("id", "name", "mode", "window_ms")
_HIERARCHICAL_KEYS = ("root_cause", "symptoms", "mute_symptoms", "auto_clear_with_root")
_CLUSTER_KEYS = ("match", "min_count", "show_as_single", "representative")


class InvalidArgumentError(ValueError):
    """Upstream's std::invalid_argument (bad `mode` or `representative`): exact text, plus line."""

    def __init__(self, message: str, line: int | None) -> None:
        super().__init__(message)
        self.line = line


@dataclass(frozen=True, slots=True)
class CorrelationLoad:
    """What the node ends up with: an engine config (None = no engine) and what it logged."""

    config: CorrelationConfig | None
    warnings: tuple[str, ...]


# -- upstream's getters: a key is read only when its value is a (non-null) scalar -------------


def _get_string(node: Node | None, key: str, default: str = "") -> str:
    value = subscript(node, key)
    return as_string(value) if value is not None and is_scalar(value) else default


def _get_bool(node: Node | None, key: str, default: bool) -> bool:
    value = subscript(node, key)
    return as_bool(value) if value is not None and is_scalar(value) else default


def _get_uint32(node: Node | None, key: str, default: int) -> int:
    value = subscript(node, key)
    return as_uint32(value) if value is not None and is_scalar(value) else default


def _get_string_array(node: Node | None, key: str) -> tuple[str, ...]:
    value = subscript(node, key)
    if value is None or not is_sequence(value):
        return ()
    return tuple(as_string(item) for item in sequence_items(value) if is_scalar(item))


# -- sections --------------------------------------------------------------------------------


def _parse_patterns(node: Node | None) -> dict[str, tuple[str, ...]]:
    patterns: dict[str, tuple[str, ...]] = {}
    if node is None or not is_map(node):
        return patterns
    for key, value in map_items(node):
        patterns[as_string(key)] = _get_string_array(value, "codes")  # a duplicate id: last wins
    return dict(sorted(patterns.items()))  # std::map order (UTF-8 byte order = code points)


def _pattern_refs(node: Node | None, *, with_inline: bool) -> tuple[list[str], list[str]]:
    pattern_ids: list[str] = []
    inline_codes: list[str] = []
    if node is None or not is_sequence(node):
        return pattern_ids, inline_codes
    for item in sequence_items(node):
        if not is_map(item):
            continue
        pattern = subscript(item, "pattern")
        if pattern is not None:  # a null `pattern:` still counts, as the id "null"
            pattern_ids.append(as_string(pattern))
            continue
        codes = subscript(item, "codes")
        if with_inline and codes is not None and is_sequence(codes):
            inline_codes.extend(as_string(c) for c in sequence_items(codes) if is_scalar(c))
    return pattern_ids, inline_codes


def _mode(node: Node) -> Mode:
    try:
        return string_to_mode(_get_string(node, "mode", "hierarchical"))
    except ValueError as exc:
        raise InvalidArgumentError(str(exc), _line_of_key(node, "mode")) from exc


def _representative(node: Node) -> Representative:
    try:
        return string_to_representative(_get_string(node, "representative", "highest_severity"))
    except ValueError as exc:
        raise InvalidArgumentError(str(exc), _line_of_key(node, "representative")) from exc


def _line_of_key(node: Node, key: str) -> int | None:
    value = subscript(node, key)
    return None if value is None else line_of(value)


def _parse_rule(node: Node, default_window_ms: int) -> CorrelationRule:
    rule_id = _get_string(node, "id")
    name = _get_string(node, "name", rule_id)
    mode = _mode(node)
    window_ms = _get_uint32(node, "window_ms", default_window_ms)
    if mode == "hierarchical":
        root_codes: tuple[str, ...] = ()
        root_cause = subscript(node, "root_cause")
        if root_cause is not None and subscript(root_cause, "codes") is not None:
            root_codes = _get_string_array(root_cause, "codes")
        symptom_ids, inline_codes = _pattern_refs(subscript(node, "symptoms"), with_inline=True)
        return CorrelationRule(
            id=rule_id,
            name=name,
            mode=mode,
            window_ms=window_ms,
            root_cause_codes=root_codes,
            symptom_pattern_ids=tuple(symptom_ids),
            inline_symptom_codes=tuple(inline_codes),
            mute_symptoms=_get_bool(node, "mute_symptoms", True),
            auto_clear_with_root=_get_bool(node, "auto_clear_with_root", True),
        )
    match_ids, _ = _pattern_refs(subscript(node, "match"), with_inline=False)
    min_count = _get_uint32(node, "min_count", 3)
    show_as_single = _get_bool(node, "show_as_single", True)
    representative = _representative(node)
    return CorrelationRule(
        id=rule_id,
        name=name,
        mode=mode,
        window_ms=window_ms,
        match_pattern_ids=tuple(match_ids),
        min_count=min_count,
        show_as_single=show_as_single,
        representative=representative,
    )


def parse_correlation_config(text: str | bytes) -> CorrelationConfig:
    """Upstream's parse_config_string (correlation.md §2).

    Raises YamlCppError where yaml-cpp throws (syntax, BadSubscript, bad conversion) and
    InvalidArgumentError (a ValueError with upstream's exact text) for a bad mode/representative.
    """
    return _parse_root(compose(text))


def _parse_root(root: Node | None) -> CorrelationConfig:
    correlation = subscript(root, "correlation")
    if correlation is None:
        return CorrelationConfig(enabled=False)
    if not _get_bool(correlation, "enabled", False):
        return CorrelationConfig(enabled=False)  # nothing else is read
    default_window_ms = _get_uint32(correlation, "default_window_ms", 500)
    patterns = _parse_patterns(subscript(correlation, "patterns"))
    rules_node = subscript(correlation, "rules")
    rules: list[CorrelationRule] = []
    if rules_node is not None and is_sequence(rules_node):
        rules = [_parse_rule(item, default_window_ms) for item in sequence_items(rules_node)]
    return CorrelationConfig(
        enabled=True,
        default_window_ms=default_window_ms,
        patterns=patterns,
        rules=tuple(rules),
    )


def _unknown_keys(root: Node | None, path: str) -> list[ConfigWarning]:
    """Keys upstream's parser does not read; a rule's keys of the other mode count as unknown
    there (upstream ignores them too). Only maps are looked into: this never throws."""
    found = unknown_map_keys(root, _TOP_KEYS, path, "correlation file")
    correlation = _map_at(root, "correlation")
    found += unknown_map_keys(correlation, _CORRELATION_KEYS, path, "correlation")
    patterns = _map_at(correlation, "patterns")
    for key, value in map_items(patterns) if patterns is not None else []:
        name = f"pattern '{shown_text(str(key.value))}'"
        found += unknown_map_keys(value, ("codes",), path, name)
    rules = _map_at(correlation, "rules", sequence=True)
    for item in sequence_items(rules) if rules is not None else []:
        if not is_map(item):
            continue
        rule = f"rule '{shown_text(_get_string(item, 'id'))}'"
        try:
            hierarchical = _mode(item) == "hierarchical"
        except InvalidArgumentError:
            continue  # the rule is refused whole
        modes = ("hierarchical", "auto_cluster")
        mode, other = modes if hierarchical else modes[::-1]
        others = _CLUSTER_KEYS if hierarchical else _HIERARCHICAL_KEYS
        for key, _ in map_items(item):
            if is_scalar(key) and key.value in others:
                found.append(
                    ConfigWarning(
                        f"{rule} ({mode}): '{key.value}' is read only by "
                        f"{other} rules; upstream ignores it here",
                        path=path,
                        line=line_of(key),
                    )
                )
        keys = _RULE_KEYS + _HIERARCHICAL_KEYS + _CLUSTER_KEYS
        found += unknown_map_keys(item, keys, path, f"{rule} ({mode})")
        if hierarchical:
            found += unknown_map_keys(_map_at(item, "root_cause"), ("codes",), path, rule)
        refs = _map_at(item, "symptoms" if hierarchical else "match", sequence=True)
        for ref in sequence_items(refs) if refs is not None else []:
            found += unknown_map_keys(ref, ("pattern", "codes"), path, rule)
    return found


def _map_at(node: Node | None, key: str, *, sequence: bool = False) -> Node | None:
    """``node[key]`` when ``node`` is a map and the value a map (or a sequence), else None."""
    if node is None or not is_map(node):
        return None
    value = subscript(node, key)
    wanted = is_sequence if sequence else is_map
    return value if value is not None and wanted(value) else None


def _no_engine(
    path: Path, message: str, line: int | None = None, *, unusable: bool = True
) -> tuple[ConfigWarning]:
    return (ConfigWarning(f"{message}; {_OFF}", path=str(path), line=line, unusable=unusable),)


def load_correlation(path: Path) -> CorrelationLoad:
    """The node's create_correlation_engine on a file: parse, validate, never fatal (§1.1).

    Every message is prefixed with the file path (and the line when one is known); a key the
    parser does not read is warned, with the closest known one.
    """
    try:
        data = read_limited(path, MAX_FILE_BYTES)
    except FileNotFoundError:
        return CorrelationLoad(None, _no_engine(path, "Correlation config file not found"))
    except OSError as exc:  # a FIFO, device or directory too: refused, never read
        what = f"Cannot open correlation config file: {path} ({exc.strerror or exc})"
        return CorrelationLoad(None, _no_engine(path, f"Failed to load correlation config: {what}"))
    try:
        root = compose(data)
        config = _parse_root(root)
    except (YamlCppError, InvalidArgumentError) as exc:
        failed = f"Failed to load correlation config: {exc}"
        return CorrelationLoad(None, _no_engine(path, failed, exc.line))
    unknown = _unknown_keys(root, str(path))
    if not config.enabled:
        off = _no_engine(path, "Correlation explicitly disabled in config", unusable=False)
        return CorrelationLoad(None, (*unknown, *off))
    validation = validate_config(config)
    messages: list[str] = [
        *unknown,
        *(
            ConfigWarning(f"Correlation config: {shown_text(warning, limit=400)}", path=str(path))
            for warning in validation.warnings
        ),
    ]
    if not validation.valid:
        messages.extend(
            ConfigWarning(
                f"Correlation config error: {shown_text(error, limit=400)}", path=str(path)
            )
            for error in validation.errors
        )
        count = len(validation.errors)
        messages.append(
            ConfigWarning(
                f"CORRELATION IS DISABLED FOR THIS RUN: {count} validation "
                f"error{'s' if count != 1 else ''} (upstream creates no correlation engine)",
                path=str(path),
                unusable=True,
            )
        )
        return CorrelationLoad(None, tuple(messages))
    return CorrelationLoad(config, tuple(messages))
