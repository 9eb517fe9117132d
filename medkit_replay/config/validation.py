"""Config files checked without a recording: each kind read by the replay's own readers, and
their warnings and errors turned into findings (file, line, severity, message, suggestion).

No rule lives here: a finding is what a reader said; this module only says which file it is about.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Literal

from yaml.nodes import MappingNode

from medkit_replay.config.correlation_file import load_correlation
from medkit_replay.config.entity_thresholds_file import load_entity_thresholds
from medkit_replay.config.fault_manager import fault_manager_config
from medkit_replay.config.kinds import DESCRIBED, guess_text_kind
from medkit_replay.config.params import load_parameters
from medkit_replay.config.reader import ParameterReader
from medkit_replay.config.referenced import FILE_PARAMETERS
from medkit_replay.config.release import release_of
from medkit_replay.config.replay_options import replay_options
from medkit_replay.config.snapshots import load_snapshot_file, snapshot_config
from medkit_replay.errors import ConfigError, ConfigWarning, at
from medkit_replay.evidence.graph import load_graph
from medkit_replay.files import read_limited_text
from medkit_replay.yaml_bounds import compose_config

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable

    from medkit_replay.config.kinds import Kind
    from medkit_replay.releases import Release

Severity = Literal["error", "warning", "info"]


@dataclass(frozen=True, slots=True)
class Finding:
    """One thing a reader said about a file (or, as ``info``, which kind it took it for)."""

    file: str
    line: int | None
    severity: Severity
    kind: Kind | None
    message: str
    suggestion: str | None = None

    def to_json(self) -> dict[str, object]:
        """The record ``validate --json`` writes."""
        return {
            "file": self.file,
            "line": self.line,
            "severity": self.severity,
            "kind": self.kind,
            "message": self.message,
            "suggestion": self.suggestion,
        }

    def render(self) -> str:
        """``file:line: severity: message``, one line."""
        return at(self.file, self.line, f"{self.severity}: {self.message}")


def said_kind(path: Path, kind: Kind, how: str = "") -> Finding:
    """The ``info`` finding naming the kind a file was taken for."""
    return Finding(str(path), None, "info", kind, f"read as {DESCRIBED[kind]}{how}")


def error_finding(err: ConfigError, path: Path, kind: Kind | None) -> Finding:
    """A reader's refusal: the file cannot be used as it is."""
    return Finding(err.path or str(path), err.line, "error", kind, err.problem)


def warning_findings(
    warnings: Iterable[str], path: Path, kind: Kind, kinds: dict[str, Kind] | None = None
) -> list[Finding]:
    """Findings of a reader's warnings. A located warning (ConfigWarning) is about its own
    file (``kinds`` says the kind of the files ``path`` names); any other is about ``path``."""
    found: list[Finding] = []
    for warning in warnings:
        if not isinstance(warning, ConfigWarning):
            found.append(Finding(str(path), None, "warning", kind, str(warning)))
            continue
        file = warning.path or str(path)
        severity: Severity = "error" if warning.unusable else "warning"
        own = (kinds or {}).get(file, kind)
        found.append(
            Finding(file, warning.line, severity, own, warning.message, warning.suggestion)
        )
    return found


def parameter_findings(path: Path, release: Release | None = None) -> list[Finding]:
    """A parameter file read as a replay reads it (with the files it names), for ``release``
    (the file's own ``upstream_release`` when None)."""
    try:
        params = load_parameters([path])
        own = release_of(params)
    except ConfigError as err:
        return [said_kind(path, "parameters"), error_finding(err, path, "parameters")]
    chosen = release or own
    found = [said_kind(path, "parameters", f" (release {chosen.name})")]
    named = params.node("fault_manager")
    kinds: dict[str, Kind] = {}
    for name, kind in FILE_PARAMETERS.items():  # the files it names, beside it
        param = named.get(name)
        if param is not None and isinstance(param.value, str) and param.value:
            referenced = str(param.path.parent / param.value)
            kinds[referenced] = kind
            found.append(said_kind(Path(referenced), kind, f" (named by {path}:{param.line})"))
    readers: tuple[Callable[[], tuple[object, list[str]]], ...] = (
        lambda: fault_manager_config(named, chosen),
        lambda: replay_options(params, chosen),
        lambda: snapshot_config(named, chosen),
    )
    for read in readers:  # as the replay reads them, in its order
        try:
            _, warnings = read()
        except ConfigError as err:
            found.append(error_finding(err, path, kinds.get(err.path or "", "parameters")))
            continue
        found += warning_findings(warnings, path, "parameters", kinds)
    return found


def correlation_findings(path: Path) -> list[Finding]:
    """A correlation file loaded as the fault manager loads it."""
    warnings = load_correlation(path).warnings
    return [said_kind(path, "correlation"), *warning_findings(warnings, path, "correlation")]


def entity_findings(path: Path) -> list[Finding]:
    """An entity-thresholds file loaded as the fault manager loads it."""
    _, warnings = load_entity_thresholds(path)
    kind: Kind = "entity_thresholds"
    return [said_kind(path, kind), *warning_findings(warnings, path, kind)]


def snapshot_findings(path: Path) -> list[Finding]:
    """A snapshot config file read as ``snapshots.config_file`` is."""
    found = [said_kind(path, "snapshots")]
    reader = ParameterReader("fault_manager", {})
    try:
        load_snapshot_file(path, reader)
    except ConfigError as err:
        found.append(error_finding(err, path, "snapshots"))
    return found + warning_findings(reader.warnings, path, "snapshots")


def strict_findings(path: Path, kind: Kind, read: Callable[[Path], object]) -> list[Finding]:
    """A file of a kind whose reader only refuses (a budget, a graph): its error, if any."""
    try:
        read(path)
    except ConfigError as err:
        return [said_kind(path, kind), error_finding(err, path, kind)]
    return [said_kind(path, kind)]


def graph_findings(path: Path) -> list[Finding]:
    """A ``--graph`` file read as analyze and explain read it."""
    return strict_findings(path, "graph", load_graph)


READERS: dict[Kind, Callable[[Path], list[Finding]]] = {
    "correlation": correlation_findings,
    "entity_thresholds": entity_findings,
    "snapshots": snapshot_findings,
    "graph": graph_findings,
}
"""The kinds read here without a release (parameters take one; budgets are read by checks)."""

NO_KIND = (
    "looks like no file medkit-replay reads (a ROS 2 parameter file, a correlation, "
    "entity-thresholds or snapshot config file, a fault budget, a node graph)"
)


def validate_files(
    paths: Iterable[Path], release: Release | None, budget: Callable[[Path], list[Finding]]
) -> list[Finding]:
    """The findings of every file, each once; a file a given parameter file names is read as
    the kind it is named for (a typo can hide what its content is)."""
    found = {path: file_findings(path, release, budget) for path in paths}
    named = {
        Path(f.file).resolve(): f.kind
        for path, findings in found.items()
        for f in findings
        if f.severity == "info" and f.file != str(path)
    }
    for path, findings in found.items():
        kind = named.get(path.resolve())
        if kind is not None and findings[0].kind != kind:
            findings = file_findings(path, release, budget, kind)
        if kind is not None:  # its kind is said where it is named
            found[path] = findings[1:]
    # A named file's findings after those of the file naming it, which has them too (once).
    order = sorted(found, key=lambda path: path.resolve() in named)
    return list(dict.fromkeys(f for path in order for f in found[path]))


def file_findings(
    path: Path,
    release: Release | None,
    budget: Callable[[Path], list[Finding]],
    kind: Kind | None = None,
) -> list[Finding]:
    """What the readers of ``path``'s kind (told from its content when None) say of it, first
    which kind it was taken for; ``budget`` reads a budget. A map of no known kind is read as a
    parameter file, whose reader says what is wrong with it."""
    try:
        text = read_limited_text(path)
    except FileNotFoundError:
        return [Finding(str(path), None, "error", None, "file not found")]
    except (OSError, UnicodeDecodeError) as err:
        return [Finding(str(path), None, "error", None, f"cannot be read: {err}")]
    kind = kind or guess_text_kind(text, str(path))
    if kind is None:
        try:
            root = compose_config(text, str(path))
        except ConfigError as err:
            return [error_finding(err, path, None)]
        if root is None:
            return [Finding(str(path), None, "warning", None, "empty: it sets nothing")]
        if not isinstance(root, MappingNode):
            return [Finding(str(path), None, "error", None, NO_KIND)]
        kind = "parameters"
    if kind == "parameters":
        return parameter_findings(path, release)
    if kind == "budget":
        return budget(path)
    return READERS[kind](path)
