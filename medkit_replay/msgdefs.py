"""Message definitions: parsing what recordings store, and the bundled ros2_medkit_msgs types.

Neutral: inputs decode with these types and outputs write them; reads no recording.
"""

from __future__ import annotations

import re
from functools import cache
from importlib import resources
from typing import TYPE_CHECKING, NamedTuple

from rosbags.interfaces import Nodetype
from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore

from medkit_replay.releases import RELEASES

if TYPE_CHECKING:
    from collections.abc import Iterator
    from importlib.resources.abc import Traversable

    from rosbags.interfaces.typing import BaseDesc, FieldDesc, NameDesc, Typesdict
    from rosbags.typesys.store import Typestore

    from medkit_replay.releases import Release

BASE_STORE = Stores.ROS2_JAZZY
"""rosbags' store for types a recording does not define (has service_msgs, action_msgs...)."""

MEDKIT_PACKAGE = "ros2_medkit_msgs"
REFERENCE_PACKAGES = ("builtin_interfaces", "std_msgs", "diagnostic_msgs")
_HEADER = re.compile(r"^(MSG|SRV|IDL|ACTION):\s*(\S+)\s*$")
_RULE = re.compile(r"^=+\s*$")
_SERVICE_SUFFIXES = ("_Event", "_Request", "_Response")
_OLD_STYLE = re.compile(r"^(?P<pkg>[^/]+)/(?P<name>[^/]+)$")
_SRV_AS_MSG = re.compile(r"^(?P<pkg>[^/]+)/srv/msg/(?P<name>[^/]+)$")
_SERVICE_PARTS = ("_Request", "_Response", "_Event")


class Definition(NamedTuple):
    """A message definition as a recording stores it (MCAP schema, sqlite3 message_definitions)."""

    encoding: str
    text: str


NO_DEFINITION = Definition("", "")


class DefinitionError(Exception):
    """A type can be decoded neither from the recording's definition nor from a bundled one."""


def _service_base(name: str) -> str:
    for suffix in _SERVICE_SUFFIXES:
        if name.endswith(suffix):
            return name[: -len(suffix)]
    return name


def _sections(text: str, name: str) -> Iterator[tuple[str, str, str]]:
    """Split a concatenated definition into (kind, type name, body); the first is ``name``."""
    kind, current = "MSG", name
    body: list[str] = []
    lines = text.splitlines()
    index = 0
    while index < len(lines):
        line = lines[index]
        header = _HEADER.match(lines[index + 1]) if index + 1 < len(lines) else None
        if _RULE.match(line) and header:
            yield kind, current, "\n".join(body)
            kind, current, body = header[1], header[2], []
            index += 2
            continue
        body.append(line)
        index += 1
    yield kind, current, "\n".join(body)


def _service_types(base: str, body: str) -> Typesdict:
    """Request, Response and Event types of a ``.srv`` body, as rosbag2 stores service events."""
    lines = body.splitlines()
    split = next((i for i, line in enumerate(lines) if line.strip() == "---"), len(lines))
    types: Typesdict = {}
    types.update(get_types_from_msg("\n".join(lines[:split]), f"{base}_Request"))
    types.update(get_types_from_msg("\n".join(lines[split + 1 :]), f"{base}_Response"))
    event = (
        "service_msgs/ServiceEventInfo info\n"
        f"{base}_Request[<=1] request\n{base}_Response[<=1] response\n"
    )
    types.update(get_types_from_msg(event, f"{base}_Event"))
    return types


def _fix_leaf(desc: BaseDesc | NameDesc) -> BaseDesc | NameDesc:
    if desc[0] == Nodetype.NAME:
        return (Nodetype.NAME, normalize_typename(desc[1]))
    return desc


def _fix_desc(desc: FieldDesc) -> FieldDesc:
    if desc[0] == Nodetype.ARRAY or desc[0] == Nodetype.SEQUENCE:
        return (desc[0], (_fix_leaf(desc[1][0]), desc[1][1]))
    return _fix_leaf(desc)


def _fix_names(types: Typesdict) -> Typesdict:
    """Rename types and references to the spelling bags use (see :func:`normalize_typename`)."""
    return {
        normalize_typename(name): (consts, [(field, _fix_desc(desc)) for field, desc in fields])
        for name, (consts, fields) in types.items()
    }


def types_from_definition(msgtype: str, definition: Definition) -> Typesdict:
    """Parse a recorded definition (``ros2msg`` or ``ros2idl``, dependencies appended).

    A ``.srv`` text (``---`` between request and response), which rosbag2 stores for service
    event topics, yields the ``_Request``, ``_Response`` and ``_Event`` types.

    Raises:
        DefinitionError: unknown encoding or text rosbags cannot parse.
    """
    types: Typesdict = {}
    try:
        if definition.encoding == "ros2msg":
            for kind, name, body in _sections(definition.text, msgtype):
                is_srv = kind == "SRV" or any(line.strip() == "---" for line in body.splitlines())
                if kind == "ACTION":
                    continue
                if is_srv:
                    types.update(_service_types(_service_base(normalize_typename(name)), body))
                else:
                    types.update(get_types_from_msg(body, normalize_typename(name)))
        elif definition.encoding == "ros2idl":
            for _, _, body in _sections(definition.text, msgtype):
                types.update(get_types_from_idl(body))
        else:
            raise DefinitionError(f"definition encoding {definition.encoding!r} is not supported")
    except DefinitionError:
        raise
    except Exception as exc:  # rosbags' parsers raise many kinds on bad text
        raise DefinitionError(f"definition of {msgtype} cannot be parsed: {exc}") from None
    return _fix_names(types)


def normalize_typename(name: str) -> str:
    """Spell a type name as rosbag2 does today: ``pkg/msg/Name`` or ``pkg/srv/Name_Event``.

    Old bags (before Foxy) store ``pkg/Name``; rosbags' parser files service parts under
    ``pkg/srv/msg/``. Both are mapped to the current spelling; anything else is kept.
    """
    name = name.strip()
    if match := _OLD_STYLE.match(name):
        return f"{match['pkg']}/msg/{match['name']}"
    if match := _SRV_AS_MSG.match(name):
        kind = "srv" if match["name"].endswith(_SERVICE_PARTS) else "msg"
        return f"{match['pkg']}/{kind}/{match['name']}"
    return name


def _interfaces(folder: str = "") -> Traversable:
    """``inputs/interfaces/`` (or a release's folder in it), reached from the top package so
    the inputs are not imported."""
    root = resources.files("medkit_replay").joinpath("inputs").joinpath("interfaces")
    return root.joinpath(folder) if folder else root


def _package_types(package: str, folder: str = "") -> Typesdict:
    """The types of one package bundled in ``inputs/interfaces/`` (or in a release's folder
    there: only the files that release has differently), services as Request/Response/Event."""
    root = _interfaces(folder).joinpath(package)
    types: Typesdict = {}
    msg = root.joinpath("msg")
    for entry in sorted(msg.iterdir() if msg.is_dir() else (), key=lambda e: e.name):
        if entry.name.endswith(".msg"):
            name = f"{package}/msg/{entry.name.removesuffix('.msg')}"
            types.update(get_types_from_msg(entry.read_text(encoding="utf-8"), name))
    srv = root.joinpath("srv")
    for entry in sorted(srv.iterdir() if srv.is_dir() else (), key=lambda e: e.name):
        if entry.name.endswith(".srv"):
            base = f"{package}/srv/{entry.name.removesuffix('.srv')}"
            types.update(_service_types(base, entry.read_text(encoding="utf-8")))
    return _fix_names(types)


@cache
def bundled_types(definitions: str = "") -> Typesdict:
    """The ros2_medkit_msgs types bundled in ``interfaces/``, services as Request/Response/Event.

    ``definitions``: a release's folder (``Release.msg_definitions``) whose files replace the
    newest ones ("" for the newest).
    """
    types = _package_types(MEDKIT_PACKAGE)
    if definitions:
        types = {**types, **_package_types(MEDKIT_PACKAGE, definitions)}
    return types


def bundled_text(name: str, definitions: str = "") -> str:
    """The bundled ``ros2_medkit_msgs/msg/<name>.msg`` text of a release (see bundled_types)."""
    for folder in (definitions, "") if definitions else ("",):
        entry = _interfaces(folder).joinpath(MEDKIT_PACKAGE).joinpath("msg").joinpath(f"{name}.msg")
        if entry.is_file():
            return entry.read_text(encoding="utf-8")
    raise FileNotFoundError(f"{MEDKIT_PACKAGE}/msg/{name}.msg is not bundled")


@cache
def reference_types() -> Typesdict:
    """The standard types the hand-written decoders are written for (DiagnosticArray and what it
    holds), bundled so that checking a recording against them needs no rosbags store."""
    types: Typesdict = {}
    for package in REFERENCE_PACKAGES:
        types.update(_package_types(package))
    return types


@cache
def base_typestore(definitions: str = "") -> Typestore:
    """rosbags' Jazzy store with the bundled ros2_medkit_msgs registered (shared, never changed);
    ``definitions`` names a release's folder of differing ones (see bundled_types)."""
    store = get_typestore(BASE_STORE)
    store.register(bundled_types(definitions))
    return store


FAULT_TYPES = (f"{MEDKIT_PACKAGE}/msg/FaultEvent", f"{MEDKIT_PACKAGE}/msg/Fault")
"""The published types whose layout tells one release from another."""


def layout_releases(types: Typesdict) -> list[Release]:
    """The releases whose FaultEvent and Fault have the fields (names and types) of ``types``,
    a recorded definition parsed (empty when it defines neither, or no release matches)."""
    recorded = {name: types[name][1] for name in FAULT_TYPES if name in types}
    if not recorded:
        return []
    return [
        release
        for release in RELEASES.values()
        if all(
            bundled_types(release.msg_definitions)[name][1] == fields
            for name, fields in recorded.items()
        )
    ]


def missing_fields(types: Typesdict, definitions: str = "") -> list[str]:
    """Fields of the bundled Fault and FaultEvent (of a release's ``definitions``) that the
    recorded ``types`` lack, as ``Type.field``."""
    bundled = bundled_types(definitions)
    missing = []
    for name in FAULT_TYPES:
        if name in types:
            have = {field for field, _ in types[name][1]}
            short = name.rsplit("/", 1)[-1]
            missing += [f"{short}.{f}" for f, _ in bundled[name][1] if f not in have]
    return missing
