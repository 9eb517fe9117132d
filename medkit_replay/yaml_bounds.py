"""Bounds on a composed YAML document: how many nodes it expands to and how deep it nests.

PyYAML composes aliases as shared nodes, so a small file can stand for billions of nodes
(or for a cycle) once walked; every YAML the tool reads is checked here before it is walked.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from yaml import SafeLoader
from yaml.error import MarkedYAMLError, YAMLError
from yaml.nodes import MappingNode, Node, SequenceNode
from yaml.reader import Reader, ReaderError

from medkit_replay.errors import ConfigError
from medkit_replay.text import one_line

if TYPE_CHECKING:
    from collections.abc import Callable

# Real parameter files, correlation files, budgets and metadata hold hundreds of nodes.
MAX_YAML_NODES = 1_000_000
MAX_YAML_DEPTH = 64


class YamlBoundsError(Exception):
    """The document expands past the bounds, nests too deep or refers to itself."""

    def __init__(self, message: str, line: int | None) -> None:
        super().__init__(message)
        self.message = message
        self.line = line


def _children(node: Node) -> list[Node]:
    if isinstance(node, MappingNode):
        return [part for pair in node.value for part in pair]
    if isinstance(node, SequenceNode):
        return list(node.value)
    return []


def _line(node: Node) -> int | None:
    return None if node.start_mark is None else node.start_mark.line + 1


def check_graph(
    root: Node | None, *, max_nodes: int = MAX_YAML_NODES, max_depth: int = MAX_YAML_DEPTH
) -> None:
    """Refuse a document that expands past ``max_nodes`` or ``max_depth``, or is cyclic.

    Each distinct node is visited once (aliases are memoised), so a bomb costs its size in
    the file, not its expansion.

    Raises:
        YamlBoundsError: with the line of the node where the bound was crossed.
    """
    if root is None:
        return
    size: dict[int, int] = {}
    depth: dict[int, int] = {}
    on_path: set[int] = set()
    stack: list[tuple[Node, bool]] = [(root, False)]
    while stack:
        node, done = stack.pop()
        key = id(node)
        if done:
            kids = _children(node)
            total = 1 + sum(size[id(kid)] for kid in kids)
            deepest = 1 + max((depth[id(kid)] for kid in kids), default=0)
            on_path.discard(key)
            if total > max_nodes:
                raise YamlBoundsError(
                    f"the YAML expands to more than {max_nodes:,} nodes (an alias bomb?)",
                    _line(node),
                )
            if deepest > max_depth:
                raise YamlBoundsError(f"the YAML nests deeper than {max_depth} levels", _line(node))
            size[key] = total
            depth[key] = deepest
            continue
        if key in size:
            continue
        if key in on_path:
            raise YamlBoundsError("the YAML refers to itself through an alias", _line(node))
        on_path.add(key)
        stack.append((node, True))
        for kid in reversed(_children(node)):
            kid_key = id(kid)
            if kid_key in on_path:
                raise YamlBoundsError("the YAML refers to itself through an alias", _line(kid))
            if kid_key not in size:
                stack.append((kid, False))


def compose_bounded(compose: Callable[[], Node | None]) -> Node | None:
    """Run a composer and check what it built; nesting too deep for the composer is refused too.

    Raises:
        YamlBoundsError: the document is past the bounds.
    """
    try:
        root = compose()
    except RecursionError:
        raise YamlBoundsError(f"the YAML nests deeper than {MAX_YAML_DEPTH} levels", None) from None
    check_graph(root)
    return root


def describe_yaml_error(
    error: YAMLError, text: str | bytes | None = None
) -> tuple[str, int | None]:
    """A PyYAML error as one line of text and the 1-based line it points at (None if unknown).

    PyYAML's own str() spans several lines (the problem, then where); a reader error knows only
    a character position, turned into a line when the ``text`` it was read from is given.
    """
    line: int | None = None
    if isinstance(error, MarkedYAMLError):
        mark = error.problem_mark or error.context_mark
        # PyYAML splits one sentence in two: "expected a single document in the stream" /
        # "but found another document"; "found duplicate anchor 'x'; first occurrence" /
        # "second occurrence". Each half alone says too little.
        parts = [part for part in (error.context, error.problem) if part]
        problem = ", ".join(parts) if parts else "invalid YAML"
        line = None if mark is None else mark.line + 1
    elif isinstance(error, ReaderError):
        character = error.character
        code = character if isinstance(character, int) else ord(str(character)[:1] or "\0")
        problem = f"unacceptable character #x{code:04x}: {error.reason}"
        if isinstance(text, str):
            line = text.count("\n", 0, error.position) + 1
        elif isinstance(text, bytes):
            line = text.count(b"\n", 0, error.position) + 1
    else:
        problem = str(error)
    return shown_text(one_line(problem), limit=300), line


# Line and paragraph separators, and the bidirectional marks, embeddings and isolates.
_ESCAPED = frozenset(
    (0x2028, 0x2029, 0x200E, 0x200F, *range(0x202A, 0x202F), *range(0x2066, 0x206A))
)


def shown_text(text: str, *, limit: int = 80) -> str:
    """Text from a file for a one-line message: control, line-break and bidirectional
    characters escaped, and cut short past ``limit`` characters."""
    out: list[str] = []
    size = 0
    for char in text:
        point = ord(char)
        if point < 0x20 or 0x7F <= point <= 0x9F:
            piece = f"\\x{point:02x}"
        elif point in _ESCAPED or 0xD800 <= point <= 0xDFFF:
            piece = f"\\u{point:04x}"
        else:
            piece = char
        if size + len(piece) > limit:
            out.append("...")
            break
        out.append(piece)
        size += len(piece)
    return "".join(out)


def compose_bounded_at(reader: Reader, compose: Callable[[], Node | None]) -> Node | None:
    """``compose_bounded``, and nesting too deep for the composer gets the line it reached.

    ``reader`` is the loader ``compose`` runs on (every PyYAML loader is a Reader).

    Raises:
        YamlBoundsError: the document is past the bounds.
    """
    try:
        return compose_bounded(compose)
    except YamlBoundsError as err:
        if err.line is not None:
            raise
        raise YamlBoundsError(err.message, reader.get_mark().line + 1) from None


def compose_config(text: str, path: str) -> Node | None:
    """The single YAML document of a config file (parameters, budget), composed by PyYAML's
    safe loader within the bounds; None for an empty file.

    Raises:
        ConfigError: not YAML, or past the bounds, with ``path`` and the line.
    """
    try:
        loader = SafeLoader(text)
        try:
            return compose_bounded_at(loader, loader.get_single_node)
        finally:
            loader.dispose()
    except YamlBoundsError as err:
        raise ConfigError(err.message, path=path, line=err.line) from None
    except YAMLError as err:
        problem, line = describe_yaml_error(err, text)
        raise ConfigError(f"invalid YAML: {problem}", path=path, line=line) from None
