"""Decoders for recorded messages: rosbags typestores built from the recording's own definitions.

Falls back to rosbags' ROS 2 Jazzy store plus the bundled ros2_medkit_msgs; reads no bag files.
"""

from __future__ import annotations

import re
from functools import cache, lru_cache
from importlib import resources
from typing import TYPE_CHECKING, NamedTuple

from rosbags.interfaces import Nodetype
from rosbags.typesys import Stores, get_types_from_idl, get_types_from_msg, get_typestore

from medkit_replay.inputs.cdr import light_decoder
from medkit_replay.inputs.definition_bounds import check_definition
from medkit_replay.inputs.selection import normalize_typename

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator

    from rosbags.interfaces.typing import BaseDesc, FieldDesc, NameDesc, Typesdict
    from rosbags.typesys.store import Typestore

BASE_STORE = Stores.ROS2_JAZZY
"""rosbags' store for types a recording does not define (has service_msgs, action_msgs...)."""

MEDKIT_PACKAGE = "ros2_medkit_msgs"
_HEADER = re.compile(r"^(MSG|SRV|IDL|ACTION):\s*(\S+)\s*$")
_RULE = re.compile(r"^=+\s*$")
_SERVICE_SUFFIXES = ("_Event", "_Request", "_Response")


class Definition(NamedTuple):
    """A message definition as a recording stores it (MCAP schema, sqlite3 message_definitions)."""

    encoding: str
    text: str


NO_DEFINITION = Definition("", "")


class DefinitionError(Exception):
    """A type can be decoded neither from the recording's definition nor from a bundled one."""


class DecodeError(Exception):
    """One payload could not be decoded."""


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


def _references(desc: FieldDesc) -> Iterator[str]:
    if desc[0] == Nodetype.NAME:
        yield desc[1]
    elif desc[0] in (Nodetype.ARRAY, Nodetype.SEQUENCE):
        yield from _references(desc[1][0])


def _complete(types: Typesdict, fallback: Typesdict) -> Typesdict:
    """Add the types a definition references but does not carry, taken from the fallback store.

    Raises:
        DefinitionError: a referenced type is defined nowhere.
    """
    done = dict(types)
    pending = [
        ref for _, fields in types.values() for _, desc in fields for ref in _references(desc)
    ]
    while pending:
        name = pending.pop()
        if name in done:
            continue
        if name not in fallback:
            raise DefinitionError(f"definition refers to {name}, which it does not define")
        done[name] = fallback[name]
        pending.extend(ref for _, desc in done[name][1] for ref in _references(desc))
    return done


@cache
def bundled_types() -> Typesdict:
    """The ros2_medkit_msgs types bundled in ``interfaces/``, services as Request/Response/Event."""
    root = resources.files("medkit_replay.inputs").joinpath("interfaces").joinpath(MEDKIT_PACKAGE)
    types: Typesdict = {}
    for entry in sorted(root.joinpath("msg").iterdir(), key=lambda e: e.name):
        if entry.name.endswith(".msg"):
            name = f"{MEDKIT_PACKAGE}/msg/{entry.name.removesuffix('.msg')}"
            types.update(get_types_from_msg(entry.read_text(encoding="utf-8"), name))
    for entry in sorted(root.joinpath("srv").iterdir(), key=lambda e: e.name):
        if entry.name.endswith(".srv"):
            base = f"{MEDKIT_PACKAGE}/srv/{entry.name.removesuffix('.srv')}"
            types.update(_service_types(base, entry.read_text(encoding="utf-8")))
    return _fix_names(types)


@cache
def base_typestore() -> Typestore:
    """rosbags' Jazzy store with the bundled ros2_medkit_msgs registered (shared, never changed)."""
    store = get_typestore(BASE_STORE)
    store.register(bundled_types())
    return store


class Decoder:
    """Decodes one type's CDR payloads, trying the recording's definition, then the bundled one.

    With ``light``, a payload is first given to the light decoder generated from the definition
    tried first (:mod:`medkit_replay.inputs.cdr`); whatever it does not take goes to rosbags.
    """

    def __init__(
        self,
        msgtype: str,
        candidates: list[tuple[str, Typestore]],
        note: Callable[[str], None],
        *,
        light: bool = False,
    ) -> None:
        self.msgtype = msgtype
        self._candidates = candidates
        self._note = note
        self._light = light
        self._fast = light_decoder(msgtype, candidates[0][1]) if light else None

    @property
    def is_light(self) -> bool:
        """Whether payloads are tried with a light decoder first."""
        return self._fast is not None

    def light_decode(self, raw: bytes | memoryview) -> object | None:
        """The light decoder's message, or None when it has none (then :meth:`decode`)."""
        fast = self._fast
        if fast is None or type(raw) is not bytes:
            return None
        try:
            return fast(raw)
        except Exception:  # rosbags decides, and says why
            return None

    def decode(self, raw: bytes | memoryview) -> object:
        """Deserialize one payload.

        Raises:
            DecodeError: no candidate definition fits the payload.
        """
        fast = self._fast
        if fast is not None and type(raw) is bytes:
            try:
                return fast(raw)
            except Exception:  # rosbags below decides, and says why
                pass
        first_error: Exception | None = None
        for index, (label, store) in enumerate(self._candidates):
            try:
                message = store.deserialize_cdr(raw, self.msgtype)
            except ImportError:
                raise  # the environment, not the payload: never a silently skipped message
            except Exception as exc:  # rosbags raises SerdeError, IndexError, ... on bad bytes
                first_error = first_error or exc
                continue
            if index:
                # Keep using the definition that fits; say once that the first choice did not.
                self._candidates.insert(0, self._candidates.pop(index))
                self._note(f"{self._candidates[1][0]} does not fit the data; used the {label}")
                if self._light:
                    self._fast = light_decoder(self.msgtype, store)
            return message
        raise DecodeError(str(first_error))


@lru_cache(maxsize=256)
def _recorded_store(msgtype: str, definition: Definition) -> tuple[str, Typestore] | str:
    """A store holding a recorded definition (with what it lacks from the base), or why not.

    Cached: recordings of one fleet share their definitions, and compiling one costs ~10 ms.
    """
    try:
        types = types_from_definition(msgtype, definition)
        if msgtype not in types:
            raise DefinitionError(f"recorded definition does not define {msgtype}")
        complete = _complete(types, base_typestore().fielddefs)
        check_definition(msgtype, complete)  # before rosbags writes code proportional to it
        store = get_typestore(Stores.EMPTY)
        store.register(complete)
        store.get_msgdef(msgtype)  # compile now, so a bad definition fails here
    except ImportError:
        raise  # the environment, not the recording (numpy imported twice once emptied a replay)
    except Exception as exc:  # DefinitionError, DefinitionBoundsError, rosbags' own errors
        return str(exc)
    return ("recorded definition", store)


def make_decoder(
    msgtype: str, definition: Definition, note: Callable[[str], None], *, light: bool = False
) -> tuple[Decoder, str | None]:
    """A decoder for ``msgtype`` and, if the recorded definition is unusable, why.

    Args:
        msgtype: the normalised type name.
        definition: what the recording stores for it (may be empty).
        note: told once if the recorded definition turns out not to fit the data.
        light: try a light decoder first (plain records, not rosbags' classes).

    Raises:
        DefinitionError: neither the recording nor the bundled types define ``msgtype``.
    """
    candidates: list[tuple[str, Typestore]] = []
    problem = None
    if definition.text.strip():
        recorded = _recorded_store(msgtype, definition)
        if isinstance(recorded, str):
            problem = recorded
        else:
            candidates.append(recorded)
    if msgtype in base_typestore().fielddefs:
        candidates.append(("bundled definition", base_typestore()))
    if not candidates:
        reason = f" ({problem})" if problem else ""
        raise DefinitionError(f"no usable definition of {msgtype}{reason}")
    return Decoder(msgtype, candidates, note, light=light), problem
