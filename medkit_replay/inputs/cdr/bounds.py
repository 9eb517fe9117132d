"""Bounds on recorded message definitions: what decoding a type may cost before data is seen.

A definition is refused when building or running its decoders costs more than payloads pay for.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from rosbags.interfaces import Nodetype
from rosbags.serde.utils import SIZEMAP

if TYPE_CHECKING:
    from rosbags.interfaces.typing import Typesdict

MAX_UNROLLED = 256
"""Elements of fixed arrays of strings or messages a definition may hold in all: rosbags writes
its decoders one line per such element (about 2 ms each to compile)."""
MAX_FIXED_WORK = 4096
"""Decoding steps one message may take that no payload byte pays for (fixed arrays of messages)."""
WORK_PER_BYTE = 64
"""Decoding steps a sequence element may take per byte it needs at least."""
MAX_DEPTH = 64
"""Nesting of message types."""
MAX_MESSAGE = 1 << 30
"""A type needing more bytes than this (fixed arrays) can never be decoded from a record."""
_SATURATE = 1 << 64
_SIZES: dict[str, int] = {str(name): size for name, size in SIZEMAP.items()}


class DefinitionBoundsError(Exception):
    """A definition whose decoding would cost more than any payload pays for."""


class _Walk:
    """Decoding steps and minimum payload bytes of each type, computed once per type."""

    def __init__(self, types: Typesdict) -> None:
        self.types = types
        self.done: dict[str, tuple[int, int]] = {}
        self.open: set[str] = set()
        self.unrolled = 0

    def type_cost(self, name: str, depth: int) -> tuple[int, int]:
        """(steps, minimum bytes) of one ``name``."""
        if name in self.done:
            return self.done[name]
        if name in self.open:
            raise DefinitionBoundsError(f"{name} contains itself")
        if depth > MAX_DEPTH:
            raise DefinitionBoundsError(f"types nest deeper than {MAX_DEPTH} levels at {name}")
        if name not in self.types:
            raise DefinitionBoundsError(f"{name} is not defined")  # _complete says so first
        self.open.add(name)
        work, size = 1, 0
        for field, desc in self.types[name][1]:
            field_work, field_size = self.field_cost(name, field, desc, depth)
            work, size = min(work + field_work, _SATURATE), min(size + field_size, _SATURATE)
        self.open.discard(name)
        if work > MAX_FIXED_WORK + WORK_PER_BYTE * size:
            raise DefinitionBoundsError(
                f"{name} takes {work} decoding steps per message from at least {size} bytes"
            )
        if size > MAX_MESSAGE:
            raise DefinitionBoundsError(f"{name} needs at least {size} bytes per message")
        self.done[name] = (work, size)
        return work, size

    def field_cost(self, owner: str, field: str, desc: Any, depth: int) -> tuple[int, int]:
        """(steps, minimum bytes) of one field; ``desc`` is rosbags' field description."""
        kind = desc[0]
        if kind == Nodetype.BASE:
            return 1, _base_size(desc[1][0])
        if kind == Nodetype.NAME:
            return self.type_cost(desc[1], depth + 1)
        sub, length = desc[1]
        if kind == Nodetype.SEQUENCE:
            if sub[0] == Nodetype.NAME:
                work, size = self.type_cost(sub[1], depth + 1)
                if size < 1 or work > WORK_PER_BYTE * size:
                    raise DefinitionBoundsError(
                        f"sequence {owner}.{field} of {sub[1]}: {work} decoding steps per "
                        f"element of at least {size} bytes"
                    )
            return 1, 4
        if sub[0] == Nodetype.BASE and sub[1][0] not in ("string", "wstring"):
            return 1, min(length * _base_size(sub[1][0]), _SATURATE)
        self.unrolled += length
        if length > MAX_UNROLLED or self.unrolled > MAX_UNROLLED:
            raise DefinitionBoundsError(
                f"fixed array {owner}.{field} of {length} elements; at most {MAX_UNROLLED} "
                "string or message elements are decoded from fixed arrays"
            )
        work, size = (1, 5) if sub[0] == Nodetype.BASE else self.type_cost(sub[1], depth + 1)
        return min(length * work, _SATURATE), min(length * size, _SATURATE)


def _base_size(typ: str) -> int:
    if typ in ("string", "wstring"):
        return 4 + (typ == "string")  # the length, and rosbags' required terminator
    return _SIZES.get(typ, 1)


def check_definition(msgtype: str, types: Typesdict) -> None:
    """Refuse ``msgtype``'s definition (with the types it uses) if decoding it costs too much.

    Fixed arrays of strings or messages are bounded in all (rosbags unrolls them); a message's
    steps beyond what its bytes pay for are bounded; a sequence's elements must each need at
    least one byte, so no sequence loops on nothing.

    Raises:
        DefinitionBoundsError: the definition passes one of these bounds; says where.
    """
    _Walk(types).type_cost(msgtype, 0)
