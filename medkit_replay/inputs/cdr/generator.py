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
import weakref
from dataclasses import make_dataclass
from itertools import count, pairwise
from typing import TYPE_CHECKING, Any

import numpy
from rosbags.interfaces import Nodetype

from medkit_replay.inputs.cdr.refusals import (
    NOT_PLAIN,
    RejectedError,
    UnsupportedError,
    sequence_refusal,
    string_refusal,
)
from medkit_replay.inputs.cdr.rosbags_internals import (
    SIZEMAP,
    align,
    align_after,
    max_sequence_length,
    unpack_le,
)

if TYPE_CHECKING:
    from collections.abc import Callable

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


def _align(a: int, ind: str) -> list[str]:
    """Align ``p`` (an offset in the whole payload) to ``a`` relative to the CDR body at 4."""
    if a <= 1:
        return []
    if a == 2:
        return [f"{ind}p = (p + 1) & -2"]
    if a == 4:
        return [f"{ind}p = (p + 3) & -4"]
    return [f"{ind}p = ((p + {a - 5}) & -{a}) + 4"]


class Generator:
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

    def items(
        self, value: str, count: int | str, ind: str, each: int, typename: str | None
    ) -> None:
        """``value`` = a list of ``count`` strings (``typename`` None) or messages, decoded in a
        loop, ``p`` aligned to ``each`` before every element."""
        out = self.lines
        out.append(f"{ind}{value} = []")
        out.append(f"{ind}for _ in range({count}):")
        inner = ind + "    "
        out.extend(_align(each, inner))
        if typename is None:
            item = self.var("s")
            out.extend(self.string(item, inner))
        else:
            item = self.var("m")
            self.message(typename, item, inner)
        out.append(f"{inner}{value}.append({item})")

    def array(self, desc: Any, value: str, ind: str) -> int:
        subdesc, length = desc[1]
        out = self.lines
        if subdesc[0] == Nodetype.BASE:
            typ = subdesc[1][0]
            if typ == "string":
                # A loop, not one block per element: the code stays small whatever the length.
                # p is 4-aligned before the first element already, so each may align alike.
                self.items(value, length, ind, 4, None)
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
        self.items(value, length, ind, before if before > after else 1, subdesc[1])
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
                self.items(value, size, ind, 4, None)
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
            self.items(value, size, ind, align(subdesc, self.store), subdesc[1])
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
    gen = Generator(store)
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
        f"        raise RejectedError({NOT_PLAIN!r})",
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
