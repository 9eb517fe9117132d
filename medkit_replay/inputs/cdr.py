"""Generated CDR decoders: straight-line Python generated from a recording's own definition.

A port of rosbags' deserializer generator (``rosbags.serde.cdr``, plain little-endian CDR) that
inlines nested messages and the string checks and builds plain slotted records with the same
field names, values and value types (numpy arrays for arrays of numbers, as rosbags). It follows
rosbags' alignment bookkeeping line by line and refuses exactly the payloads rosbags refuses
(tests/speed/test_light_decoders.py). Definitions it does not cover (wstring, float128, odd field
names) get no generated decoder: rosbags decodes those types.
"""

from __future__ import annotations

import keyword
import linecache
import struct
import sys
import weakref
from dataclasses import make_dataclass
from itertools import count, pairwise
from struct import Struct
from typing import TYPE_CHECKING, Any

import numpy
from rosbags.interfaces import Nodetype

from medkit_replay.inputs.rosbags_internals import (
    SIZEMAP,
    align,
    align_after,
    max_sequence_length,
    unpack_le,
)
from medkit_replay.msgdefs import base_typestore

if TYPE_CHECKING:
    from collections.abc import Callable

    from rosbags.interfaces.typing import FieldDesc
    from rosbags.typesys.store import Typestore

_PRIMITIVES = frozenset(
    (
        "bool",
        "byte",
        "char",
        "int8",
        "int16",
        "int32",
        "int64",
        "uint8",
        "uint16",
        "uint32",
        "uint64",
        "float32",
        "float64",
    )
)
_NDTYPE = {"bool": "bool_", "char": "uint8"}


class UnsupportedError(Exception):
    """The definition uses something the generator does not cover; rosbags decodes it."""


class RejectedError(Exception):
    """A payload that does not fit the definition (a check rosbags makes too)."""


REFUSALS = (RejectedError, struct.error, IndexError, UnicodeDecodeError, ValueError)
"""What a generated decoder raises on bytes that do not fit: its own checks, a read past the
end (struct, indexing), text that is not UTF-8, and numpy's buffer too small for an array.
Anything else it raises is a bug in the generated code."""


_NOT_PLAIN = "Invalid or unsupported CDR encapsulation."


def string_refusal(raw: bytes, p: int, length: int) -> str:
    """Why the string at ``p`` is refused, worded (and placed in the CDR body) as rosbags does."""
    end = p + 4 + length
    if length < 1 or end > len(raw):
        return f"Invalid string length {length} at offset {p - 4}."
    return f"Missing string terminator at offset {end - 5}."


def sequence_refusal(size: int, p: int) -> str:
    """Why a sequence count read before ``p`` is refused, worded as rosbags does."""
    return f"Invalid sequence length {size} at offset {p - 4}."


def _align(a: int, ind: str) -> list[str]:
    """Align ``p`` (an offset in the whole payload) to ``a`` relative to the CDR body at 4."""
    if a <= 1:
        return []
    if a == 2:
        return [f"{ind}p = (p + 1) & -2"]
    if a == 4:
        return [f"{ind}p = (p + 3) & -4"]
    return [f"{ind}p = ((p + {a - 5}) & -{a}) + 4"]


class _Generator:
    """Emits one decode function for one type and the record classes it builds."""

    def __init__(self, store: Typestore) -> None:
        self.store = store
        self.lines: list[str] = []
        self.names: dict[str, object] = {"numpy": numpy, "RejectedError": RejectedError}
        self.classes: dict[str, type] = {}
        self.counter = 0

    def var(self, stem: str) -> str:
        self.counter += 1
        return f"{stem}{self.counter}"

    def cls(self, typename: str) -> str:
        """The name (in the generated namespace) of the record class of ``typename``."""
        key = "C_" + typename.replace("/", "__")
        if key in self.names:
            return key
        msgdef = self.store.get_msgdef(typename)
        fields = [name for name, _ in msgdef.fields]
        consts = self.store.fielddefs[typename][0]
        for name in fields + [c[0] for c in consts]:
            if not name.isidentifier() or keyword.iskeyword(name) or name.startswith("__"):
                raise UnsupportedError(f"field name {name!r} of {typename}")
        if len({*fields, *(c[0] for c in consts)}) != len(fields) + len(consts):
            raise UnsupportedError(f"a constant of {typename} shadows a field")
        made = make_dataclass(
            typename.replace("/", "__"), [(name, object) for name in fields], slots=True
        )
        made.__module__ = __name__
        made.__msgtype__ = typename  # type: ignore[attr-defined]
        for name, _, value in consts:
            setattr(made, name, value)
        self.names[key] = made
        self.classes[typename] = made
        return key

    def prim(self, typ: str) -> str:
        if typ not in _PRIMITIVES:
            raise UnsupportedError(f"type {typ}")
        key = f"u_{typ}"
        self.names[key] = unpack_le(typ)
        return key

    def dtype(self, typ: str) -> str:
        if typ not in _PRIMITIVES:
            raise UnsupportedError(f"type {typ}")
        key = f"d_{typ}"
        self.names[key] = getattr(numpy, _NDTYPE.get(typ, typ))
        return key

    def string(self, target: str, ind: str) -> list[str]:
        """Decode one string into ``target``, checked as rosbags' ``check_string`` does."""
        self.names["u_uint32"] = unpack_le("uint32")
        self.names["string_refusal"] = string_refusal
        return [
            f"{ind}ln = u_uint32(raw, p)[0]",
            f"{ind}e = p + 4 + ln",
            f"{ind}if ln < 1 or e > n or raw[e - 1]:",
            f"{ind}    raise RejectedError(string_refusal(raw, p, ln))",
            f"{ind}{target} = raw[p + 4 : e - 1].decode()",
            f"{ind}p = e",
        ]

    def message(self, typename: str, target: str, ind: str) -> None:
        """Decode one ``typename`` into the variable ``target`` (rosbags' function, inlined)."""
        msgdef = self.store.get_msgdef(typename)
        cls = self.cls(typename)
        out = self.lines
        values: list[str] = []
        aligned = 8
        fields: list[Any] = [*msgdef.fields, None]  # rosbags' field descriptions
        for fcurr, fnext in pairwise(fields):
            assert fcurr is not None
            desc: Any = fcurr[1]
            value = self.var("v")
            values.append(value)
            kind = desc[0]
            if kind == Nodetype.NAME:
                self.message(desc[1], value, ind)
                aligned = align_after(desc, self.store)
            elif kind == Nodetype.BASE:
                typ = desc[1][0]
                if typ == "string":
                    out.extend(self.string(value, ind))
                    aligned = 1
                else:
                    out.append(f"{ind}{value} = {self.prim(typ)}(raw, p)[0]")
                    out.append(f"{ind}p += {SIZEMAP[typ]}")
                    aligned = SIZEMAP[typ]
            elif kind == Nodetype.ARRAY:
                aligned = self.array(desc, value, ind)
            elif kind == Nodetype.SEQUENCE:
                aligned = self.sequence(desc, value, ind, aligned)
            else:
                raise UnsupportedError(f"node type {kind}")
            if fnext and aligned < (anext := align(fnext[1], self.store)):
                out.extend(_align(anext, ind))
                aligned = anext
        out.append(f"{ind}{target} = {cls}({', '.join(values)})")

    def array(self, desc: Any, value: str, ind: str) -> int:
        subdesc, length = desc[1]
        out = self.lines
        if subdesc[0] == Nodetype.BASE:
            typ = subdesc[1][0]
            if typ == "string":
                # A loop, not one block per element: the code stays small whatever the length.
                # p is 4-aligned before the first element already, so each may align alike.
                out.append(f"{ind}{value} = []")
                out.append(f"{ind}for _ in range({length}):")
                inner = ind + "    "
                out.extend(_align(4, inner))
                item = self.var("s")
                out.extend(self.string(item, inner))
                out.append(f"{inner}{value}.append({item})")
                return 1
            size = length * SIZEMAP[typ] if typ in SIZEMAP else 0
            out.append(
                f"{ind}{value} = numpy.frombuffer(raw, dtype={self.dtype(typ)}, count={length}, "
                "offset=p)"
            )
            out.append(f"{ind}p += {size}")
            return SIZEMAP[typ]
        if subdesc[0] != Nodetype.NAME:
            raise UnsupportedError(f"array of {subdesc}")
        before, after = align(subdesc, self.store), align_after(subdesc, self.store)
        out.append(f"{ind}{value} = []")
        out.append(f"{ind}for _ in range({length}):")
        inner = ind + "    "
        if before > after:
            out.extend(_align(before, inner))
        item = self.var("m")
        self.message(subdesc[1], item, inner)
        out.append(f"{inner}{value}.append({item})")
        return after

    def sequence(self, desc: Any, value: str, ind: str, aligned: int) -> int:
        subdesc = desc[1][0]
        out = self.lines
        self.names["u_uint32"] = unpack_le("uint32")
        self.names["MAXSEQ"] = max_sequence_length(self.store)
        self.names["sequence_refusal"] = sequence_refusal
        size = self.var("n")
        out.append(f"{ind}{size} = u_uint32(raw, p)[0]")
        out.append(f"{ind}p += 4")
        aligned = 4
        if subdesc[0] == Nodetype.BASE:
            typ = subdesc[1][0]
            minimum = 5 if typ == "string" else SIZEMAP.get(typ, 1)
        else:
            minimum = 1
        out.append(f"{ind}if p + {size} * {minimum} > n or {size} > MAXSEQ:")
        out.append(f"{ind}    raise RejectedError(sequence_refusal({size}, p))")
        if subdesc[0] == Nodetype.BASE:
            typ = subdesc[1][0]
            if typ == "string":
                out.append(f"{ind}{value} = []")
                out.append(f"{ind}for _ in range({size}):")
                inner = ind + "    "
                out.extend(_align(4, inner))
                item = self.var("s")
                out.extend(self.string(item, inner))
                out.append(f"{inner}{value}.append({item})")
                aligned = 1
            else:
                if typ not in _PRIMITIVES:
                    raise UnsupportedError(f"type {typ}")
                before = align(subdesc, self.store)
                if aligned < before:
                    out.append(f"{ind}if {size}:")
                    out.extend(_align(before, ind + "    "))
                out.append(
                    f"{ind}{value} = numpy.frombuffer(raw, dtype={self.dtype(typ)}, "
                    f"count={size}, offset=p)"
                )
                out.append(f"{ind}p += {size} * {SIZEMAP[typ]}")
                aligned = before
        elif subdesc[0] == Nodetype.NAME:
            before = align(subdesc, self.store)
            out.append(f"{ind}{value} = []")
            out.append(f"{ind}for _ in range({size}):")
            inner = ind + "    "
            out.extend(_align(before, inner))
            item = self.var("m")
            self.message(subdesc[1], item, inner)
            out.append(f"{inner}{value}.append({item})")
            aligned = align_after(subdesc, self.store)
        else:
            raise UnsupportedError(f"sequence of {subdesc}")
        return min(4, aligned)


_SERIALS = count(1)


def generate(msgtype: str, store: Typestore) -> tuple[Callable[[bytes], object], str]:
    """The decoder of ``msgtype`` as ``store`` defines it, and its source (for tests).

    The source is registered with :mod:`linecache` under a name of its own, so tracebacks and
    debuggers show the generated lines.

    Raises:
        UnsupportedError: the definition uses something the generator does not cover.
    """
    gen = _Generator(store)
    body: list[str] = []
    gen.lines = body
    try:
        gen.message(msgtype, "result", "    ")
    except (KeyError, TypeError, ValueError) as exc:  # a type rosbags cannot resolve either
        raise UnsupportedError(str(exc)) from None
    bound = ", ".join(f"{name}={name}" for name in sorted(gen.names))  # globals as fast locals
    lines = [
        f"def decode(raw, {bound}):",
        "    n = len(raw)",
        "    if n < 4 or raw[0] or raw[1] != 1:",
        f"        raise RejectedError({_NOT_PLAIN!r})",
        "    p = 4",
        *body,
        "    if p + 3 < n:",
        f"        raise RejectedError({f'CDR message size mismatch for {msgtype!r}.'!r})",
        "    return result",
    ]
    source = "\n".join(lines) + "\n"
    filename = f"<medkit-replay decoder of {msgtype} #{next(_SERIALS)}>"
    linecache.cache[filename] = (len(source), None, source.splitlines(keepends=True), filename)
    namespace = dict(gen.names)
    exec(compile(source, filename, "exec"), namespace)
    decode: Callable[[bytes], object] = namespace["decode"]  # type: ignore[assignment]
    weakref.finalize(decode, linecache.cache.pop, filename, None)  # the lines live as it does
    return decode, source


DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"
_U32 = unpack_le("uint32")
_BYTE = unpack_le("byte")
_TIME = Struct("<iI").unpack_from
_MAX_HEADS = 4096


def _layout(store: Typestore, typename: str) -> tuple[object, ...]:
    """A type's fields with every referenced type expanded: what decoding depends on."""
    return tuple(
        (name, _layout(store, desc[1]) if desc[0] == Nodetype.NAME else _sublayout(store, desc))
        for name, desc in store.get_msgdef(typename).fields
    )


def _sublayout(store: Typestore, desc: FieldDesc) -> object:
    if desc[0] in (Nodetype.ARRAY, Nodetype.SEQUENCE):
        sub, bound = desc[1]
        inner = _layout(store, sub[1]) if sub[0] == Nodetype.NAME else sub
        return (desc[0], inner, bound)
    return desc


class DiagnosticArrayView:
    """A diagnostic_msgs/msg/DiagnosticArray decoded for the diagnostic bridge.

    ``heads`` holds each status's (level, name, message, hardware_id), shared between arrays
    whose statuses repeat those bytes. ``header`` and ``status`` (the full statuses, with
    their key/value pairs, already checked) are built when first read.
    """

    __slots__ = ("_built", "_header", "_raw", "_types", "heads")
    __msgtype__ = DIAGNOSTIC_ARRAY

    def __init__(
        self,
        stamp_and_frame: tuple[int, int, str],
        heads: list[tuple[int, str, str, str]],
        raw: bytes,
        types: tuple[type, type, type, type],
    ) -> None:
        self._header = stamp_and_frame
        self.heads = heads
        self._raw = raw
        self._types = types  # Header, Time, DiagnosticStatus, KeyValue
        self._built: list[object] | None = None

    @property
    def header(self) -> object:
        """std_msgs/msg/Header, as the generic generated decoder builds it."""
        header_cls, time_cls, _, _ = self._types
        sec, nanosec, frame_id = self._header
        return header_cls(time_cls(sec, nanosec), frame_id)

    @property
    def status(self) -> list[object]:
        """The statuses, as the generic generated decoder builds them."""
        if self._built is not None:
            return self._built
        _, _, status_cls, pair_cls = self._types
        raw = self._raw
        p = 12 + 4 + _U32(raw, 12)[0]  # after the frame id
        p = ((p + 3) & -4) + 4  # after the status count
        out: list[object] = []
        for level, name, message, hardware_id in self.heads:
            p = (p + 4) & -4
            for _ in range(3):  # name, message, hardware_id: known already
                p = ((p + 4 + _U32(raw, p)[0]) + 3) & -4
            count = _U32(raw, p)[0]
            p += 4
            pairs = []
            for _ in range(count):
                key, p = _text(raw, (p + 3) & -4)
                value, p = _text(raw, (p + 3) & -4)
                pairs.append(pair_cls(key, value))
            out.append(status_cls(level, name, message, hardware_id, pairs))
        self._built = out
        return out

    def __eq__(self, other: object) -> bool:
        if not hasattr(other, "header") or not hasattr(other, "status"):
            return NotImplemented
        return bool(self.header == other.header and self.status == other.status)

    __hash__ = None  # type: ignore[assignment]  # mutable, like rosbags' messages

    def __repr__(self) -> str:
        return f"{type(self).__name__}(header={self.header!r}, status={self.status!r})"


def _text(raw: bytes, p: int) -> tuple[str, int]:
    """One string already checked: its text and the position after it."""
    end = p + 4 + _U32(raw, p)[0]
    return raw[p + 4 : end - 1].decode(), end


def _diagnostic_array(store: Typestore) -> Callable[[bytes], object]:
    if sys.byteorder != "little":
        raise UnsupportedError("the DiagnosticArray decoder reads words natively")
    """The DiagnosticArray decoder of the standard layout, remembering repeated status heads.

    Checks every payload exactly as rosbags would (lengths, terminators, UTF-8, trailing
    bytes); a status's level, name, message and hardware_id are decoded once per distinct
    run of bytes, its key/value pairs only checked (they are decoded when ``status`` is read).
    """
    gen = _Generator(store)
    types: tuple[type, type, type, type] = tuple(  # type: ignore[assignment]
        gen.names[gen.cls(name)]
        for name in (
            "std_msgs/msg/Header",
            "builtin_interfaces/msg/Time",
            "diagnostic_msgs/msg/DiagnosticStatus",
            "diagnostic_msgs/msg/KeyValue",
        )
    )
    max_seq = max_sequence_length(store)
    heads_seen: dict[bytes, tuple[int, str, str, str]] = {}

    def checked(raw: bytes, p: int, n: int) -> tuple[str, int]:
        length = _U32(raw, p)[0]
        end = p + 4 + length
        if length < 1 or end > n or raw[end - 1]:
            raise RejectedError(string_refusal(raw, p, length))
        return raw[p + 4 : end - 1].decode(), end

    def head_refusal(raw: bytes, start: int, n: int) -> RejectedError:
        at = (start + 4) & -4
        for _ in range(3):  # the first text that does not fit raises, worded as rosbags does
            _, at = checked(raw, at, n)
            at = (at + 3) & -4
        return RejectedError(f"Invalid string length at offset {start - 4}.")

    def decode(raw: bytes) -> DiagnosticArrayView:  # straight for speed
        n = len(raw)
        if n < 4 or raw[0] or raw[1] != 1:
            raise RejectedError(_NOT_PLAIN)
        # Every length field sits 4-aligned: read them as native words (checked little-endian).
        u32 = memoryview(raw)[: n & -4].cast("I")
        sec, nanosec = _TIME(raw, 4)
        length = u32[3]
        p = 16 + length
        if not length or raw[p - 1]:
            raise RejectedError(string_refusal(raw, 12, length))
        frame_id = raw[16 : p - 1].decode()
        p = (p + 3) & -4
        count = u32[p >> 2]
        p += 4
        if p + count > n or count > max_seq:
            raise RejectedError(sequence_refusal(count, p))
        heads: list[tuple[int, str, str, str]] = []
        for _ in range(count):
            start = p
            p = (p + 4) & -4  # the level byte, then the name's alignment
            e1 = p + 4 + u32[p >> 2]
            p = (e1 + 3) & -4
            e2 = p + 4 + u32[p >> 2]
            p = (e2 + 3) & -4
            e3 = p + 4 + u32[p >> 2]
            if e3 > n:
                raise head_refusal(raw, start, n)
            key = raw[start:e3]
            head = heads_seen.get(key)
            if head is None:
                at = (start + 4) & -4
                name, at = checked(raw, at, n)
                message, at = checked(raw, (at + 3) & -4, n)
                hardware_id, at = checked(raw, (at + 3) & -4, n)
                head = (_BYTE(raw, start)[0], name, message, hardware_id)
                if len(heads_seen) >= _MAX_HEADS:
                    heads_seen.clear()
                heads_seen[key] = head
            heads.append(head)
            p = (e3 + 3) & -4
            pairs = u32[p >> 2]
            p += 4
            if p + pairs > n or pairs > max_seq:
                raise RejectedError(sequence_refusal(pairs, p))
            first = p
            for _ in range(pairs):
                # A text past the end fails at raw[e - 1] (IndexError): a refusal.
                p = (p + 3) & -4
                length = u32[p >> 2]
                e = p + 4 + length
                if not length or raw[e - 1]:
                    raise RejectedError(string_refusal(raw, p, length))
                q = (e + 3) & -4
                length = u32[q >> 2]
                p = q + 4 + length
                if not length or raw[p - 1]:
                    raise RejectedError(string_refusal(raw, q, length))
            if pairs and not raw[first:p].isascii():
                at = first
                for _ in range(2 * pairs):  # not all ASCII: check each text decodes
                    _, at = checked(raw, (at + 3) & -4, n)
        if p + 3 < n:
            raise RejectedError(f"CDR message size mismatch for {DIAGNOSTIC_ARRAY!r}.")
        return DiagnosticArrayView((sec, nanosec, frame_id), heads, raw, types)

    return decode


_SPECIAL: dict[str, Callable[[Typestore], Callable[[bytes], object]]] = {
    DIAGNOSTIC_ARRAY: _diagnostic_array,
}
"""Hand-written decoders, used when a recording's definition has the standard layout."""


def _standard(msgtype: str, store: Typestore) -> bool:
    try:
        return _layout(store, msgtype) == _layout(base_typestore(), msgtype)
    except (KeyError, TypeError, ValueError):
        return False


_CACHE: dict[tuple[str, int], tuple[Typestore, Callable[[bytes], object] | None]] = {}
_CACHE_SIZE = 1024


def generated_decoder(msgtype: str, store: Typestore) -> Callable[[bytes], object] | None:
    """The decoder of ``msgtype`` in ``store`` (cached per store), or None if unsupported.

    It takes plain little-endian CDR (encapsulation header ``00 01``) and raises one of
    :data:`REFUSALS` on a payload that does not fit the definition.
    """
    key = (msgtype, id(store))
    cached = _CACHE.get(key)
    if cached is None:
        try:
            special = _SPECIAL.get(msgtype)
            if special is not None and _standard(msgtype, store):
                decode: Callable[[bytes], object] | None = special(store)
            else:
                decode = generate(msgtype, store)[0]
        except UnsupportedError:
            decode = None
        if len(_CACHE) >= _CACHE_SIZE:
            _CACHE.clear()
        cached = _CACHE[key] = (store, decode)  # holding the store keeps its id unique
    return cached[1]
