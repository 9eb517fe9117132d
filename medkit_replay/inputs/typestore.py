"""Decoders for recorded messages: generated from the recording's own definitions or bundled ones.

rosbags decodes only types the generator does not cover and payloads not in plain little-endian
CDR; reads no bag files.
"""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING

from rosbags.interfaces import Nodetype
from rosbags.typesys import Stores, get_typestore

from medkit_replay.inputs.cdr.bounds import check_definition
from medkit_replay.inputs.cdr.decoders import REFUSALS, RejectedError, generated_decoder
from medkit_replay.msgdefs import (
    FAULT_TYPES,
    Definition,
    DefinitionError,
    base_typestore,
    layout_releases,
    missing_fields,
    types_from_definition,
)
from medkit_replay.releases import RELEASES

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator

    from rosbags.interfaces.typing import FieldDesc, Typesdict
    from rosbags.typesys.store import Typestore

    from medkit_replay.releases import Release

PLAIN_CDR = b"\x00\x01"
"""Encapsulation header of plain little-endian CDR: what generated decoders take."""


class DecodeError(Exception):
    """One payload could not be decoded."""


def _references(desc: FieldDesc) -> Iterator[str]:
    if desc[0] == Nodetype.NAME:
        yield desc[1]
    elif desc[0] in (Nodetype.ARRAY, Nodetype.SEQUENCE):
        yield from _references(desc[1][0])


def _complete(types: Typesdict, fallback: Callable[[], Typesdict]) -> Typesdict:
    """Add the types a definition references but does not carry, taken from the fallback store
    (built only when something is missing: a recording usually carries every type it uses).

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
        known = fallback()
        if name not in known:
            raise DefinitionError(f"definition refers to {name}, which it does not define")
        done[name] = known[name]
        pending.extend(ref for _, desc in done[name][1] for ref in _references(desc))
    return done


class Decoder:
    """Decodes one type's CDR payloads, trying the recording's definition, then the bundled one.

    Each candidate definition decodes with its generated decoder (``inputs.cdr.decoders``);
    rosbags decodes for a candidate that has none, and every payload whose encapsulation is not
    plain little-endian CDR (big-endian, parameter lists). A payload the first candidate refuses
    is tried with the next; the first that fits is used from then on.
    """

    def __init__(
        self,
        msgtype: str,
        candidates: list[tuple[str, Typestore]],
        note: Callable[[str], None],
        bundled: Callable[[], list[tuple[str, Typestore]]] | None = None,
    ) -> None:
        """``bundled``, if given, gives the last candidates when first needed (building rosbags'
        store costs a tenth of a second, and a recording's own definition usually fits)."""
        self.msgtype = msgtype
        self._candidates = [
            (label, store, generated_decoder(msgtype, store)) for label, store in candidates
        ]
        self._note = note
        self._bundled = bundled
        self._first = self._candidates[0][2]

    def _extend(self) -> bool:
        """Add the bundled candidates (once); False when there are none."""
        bundled, self._bundled = self._bundled, None
        found = bundled() if bundled is not None else []
        for label, store in found:
            self._candidates.append((label, store, generated_decoder(self.msgtype, store)))
        return bool(found)

    def decode(self, raw: bytes | memoryview) -> object:
        """Deserialize one payload.

        Raises:
            DecodeError: no candidate definition fits the payload.
        """
        if type(raw) is not bytes:
            raw = bytes(raw)
        first = self._first
        if first is not None and raw[:2] == PLAIN_CDR:
            try:
                return first(raw)
            except REFUSALS as exc:
                return self._each(raw, 1, _refused(self.msgtype, exc))
        return self._each(raw, 0, None)

    def _each(self, raw: bytes, start: int, first_error: Exception | None) -> object:
        """Try the candidates from ``start`` on; the first that fits moves to the front."""
        plain = raw[:2] == PLAIN_CDR
        index = start - 1
        while (index := index + 1) < len(self._candidates) or self._extend():
            label, store, generated = self._candidates[index]
            try:
                if generated is not None and plain:
                    try:
                        message = generated(raw)
                    except REFUSALS as exc:
                        raise _refused(self.msgtype, exc) from None
                else:
                    message = _rosbags_decode(store, raw, self.msgtype)
            except DecodeError as exc:
                first_error = first_error or exc
                continue
            if index:
                # Keep using the definition that fits; say once that the first choice did not.
                self._candidates.insert(0, self._candidates.pop(index))
                self._first = generated
                self._note(f"{self._candidates[1][0]} does not fit the data; used the {label}")
            return message
        raise DecodeError(str(first_error))


def _refused(msgtype: str, exc: Exception) -> DecodeError:
    """A generated decoder's refusal, worded as rosbags words its own."""
    if isinstance(exc, RejectedError):
        return DecodeError(str(exc))
    return DecodeError(f"Could not deserialize {msgtype!r}: {exc}")


def _rosbags_decode(store: Typestore, raw: bytes, msgtype: str) -> object:
    """rosbags' decoding of one payload.

    Raises:
        DecodeError: rosbags refuses the payload.
    """
    try:
        return store.deserialize_cdr(raw, msgtype)
    except ImportError:
        raise  # the environment, not the payload: never a silently skipped message
    except Exception as exc:  # rosbags raises SerdeError, IndexError, ... on bad bytes
        raise DecodeError(str(exc)) from None


@lru_cache(maxsize=256)
def _recorded_store(
    msgtype: str, definition: Definition, definitions: str = ""
) -> tuple[str, Typestore] | str:
    """A store holding a recorded definition (with what it lacks from the base of the release's
    ``definitions``), or why not.

    Cached: recordings of one fleet share their definitions, and compiling one costs ~10 ms.
    """
    try:
        types = types_from_definition(msgtype, definition)
        if msgtype not in types:
            raise DefinitionError(f"recorded definition does not define {msgtype}")
        complete = _complete(types, lambda: base_typestore(definitions).fielddefs)
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
    msgtype: str, definition: Definition, note: Callable[[str], None], definitions: str = ""
) -> tuple[Decoder, str | None]:
    """A decoder for ``msgtype`` and, if the recorded definition is unusable, why.

    Args:
        msgtype: the normalised type name.
        definition: what the recording stores for it (may be empty).
        note: told once if the recorded definition turns out not to fit the data.
        definitions: the modelled release's ros2_medkit_msgs (``Release.msg_definitions``),
            used where the recording stores none.

    Raises:
        DefinitionError: neither the recording nor the bundled types define ``msgtype``.
    """
    candidates: list[tuple[str, Typestore]] = []
    problem = None
    if definition.text.strip():
        recorded = _recorded_store(msgtype, definition, definitions)
        if isinstance(recorded, str):
            problem = recorded
        else:
            candidates.append(recorded)

    def bundled() -> tuple[str, Typestore] | None:
        store = base_typestore(definitions)
        return ("bundled definition", store) if msgtype in store.fielddefs else None

    def others() -> list[tuple[str, Typestore]]:
        """Other releases' layouts of a FaultEvent, tried when the modelled one's does not fit
        (a recording without definitions from a robot on another release)."""
        if msgtype not in FAULT_TYPES:
            return []
        found = {
            release.msg_definitions: release.name
            for release in RELEASES.values()
            if release.msg_definitions != definitions
        }
        return [
            (f"ros2_medkit {name} definition: the robot ran {name}; {select_hint(name)}", store)
            for folder, name in found.items()
            if msgtype in (store := base_typestore(folder)).fielddefs
        ]

    if candidates:

        def further() -> list[tuple[str, Typestore]]:
            found = bundled()
            return ([found] if found is not None else []) + others()

        return Decoder(msgtype, candidates, note, further), problem
    first = bundled()
    if first is None:
        reason = f" ({problem})" if problem else ""
        raise DefinitionError(f"no usable definition of {msgtype}{reason}")
    return Decoder(msgtype, [first], note, others), problem


def message_store(msgtype: str, definition: Definition) -> Typestore:
    """A rosbags store that decodes ``msgtype``: from the recorded definition, else bundled.

    Raises:
        DefinitionError: neither defines it.
    """
    if definition.text.strip():
        recorded = _recorded_store(msgtype, definition)
        if not isinstance(recorded, str):
            return recorded[1]
    if msgtype in base_typestore().fielddefs:
        return base_typestore()
    raise DefinitionError(f"no usable definition of {msgtype}")


@lru_cache(maxsize=64)
def other_release(definition: Definition, release: Release) -> str | None:
    """What to tell the user when a recorded FaultEvent definition is another release's
    layout than ``release``'s: which release the robot ran and how to select it (None: the
    definitions agree, or the recorded one matches no release).
    """
    try:
        types = types_from_definition("ros2_medkit_msgs/msg/FaultEvent", definition)
    except DefinitionError:
        return None
    matching = layout_releases(types)
    if not matching or release in matching:
        return None
    robot = matching[-1].name
    lacks = missing_fields(types, release.msg_definitions)
    why = f" (no {', '.join(lacks)})" if lacks else ""
    return (
        f"the recorded FaultEvent definition is ros2_medkit {robot}'s{why}: the robot ran "
        f"{robot} and this replay models {release.name}; {select_hint(robot)}"
    )


def select_hint(name: str) -> str:
    """How to model the release called ``name``."""
    return (
        f'to model {name}, set medkit_replay: ros__parameters: upstream_release: "{name}" '
        "in a --config file"
    )
