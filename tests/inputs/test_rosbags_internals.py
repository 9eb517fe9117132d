"""What medkit-replay relies on in rosbags' internals, pinned: one test per internal.

A rosbags release that moves or changes one fails here, before a generated decoder misreads.
"""

from __future__ import annotations

import struct
from typing import Any

import pytest
from rosbags.interfaces import Nodetype
from rosbags.typesys.store import Typestore

from medkit_replay.inputs.cdr import rosbags_internals as internals
from medkit_replay.msgdefs import base_typestore

PRIMITIVES = {
    "bool": "?",
    "byte": "b",
    "char": "B",
    "int8": "b",
    "int16": "<h",
    "int32": "<i",
    "int64": "<q",
    "uint8": "B",
    "uint16": "<H",
    "uint32": "<I",
    "uint64": "<Q",
    "float32": "<f",
    "float64": "<d",
}


@pytest.mark.parametrize(("typ", "fmt"), PRIMITIVES.items())
def test_unpack_le_reads_one_little_endian_primitive_at_an_offset(typ: str, fmt: str) -> None:
    size = struct.calcsize(fmt)
    raw = bytes(range(1, 3 + size))
    assert internals.unpack_le(typ)(raw, 2) == struct.unpack_from(fmt, raw, 2)
    with pytest.raises(struct.error):  # past the end: struct's error, a refusal to the decoder
        internals.unpack_le(typ)(raw, len(raw) - size + 1)


def test_sizemap_holds_the_cdr_size_of_every_primitive() -> None:
    for typ, fmt in PRIMITIVES.items():
        assert internals.SIZEMAP[typ] == struct.calcsize(fmt)


def test_align_and_align_after_follow_cdr() -> None:
    store = base_typestore()
    base: Any = (Nodetype.BASE, ("float64", 0))
    assert internals.align(base, store) == 8
    assert internals.align_after(base, store) == 8
    text: Any = (Nodetype.BASE, ("string", 0))
    assert (internals.align(text, store), internals.align_after(text, store)) == (4, 1)
    header: Any = (Nodetype.NAME, "std_msgs/msg/Header")  # Time (int32, uint32), then a string
    assert (internals.align(header, store), internals.align_after(header, store)) == (4, 1)
    sequence: Any = (Nodetype.SEQUENCE, ((Nodetype.BASE, ("uint16", 0)), 0))
    assert (internals.align(sequence, store), internals.align_after(sequence, store)) == (4, 2)


def test_max_sequence_length_is_what_rosbags_refuses_past() -> None:
    store = base_typestore()
    assert internals.max_sequence_length(store) == 2**32 - 1
    msgtype = "std_msgs/msg/String"
    names = [msgtype, "std_msgs/msg/MultiArrayLayout", "std_msgs/msg/MultiArrayDimension"]
    small = Typestore(max_sequence_length=2)
    small.register({name: store.fielddefs[name] for name in names})
    assert internals.max_sequence_length(small) == 2
    layout = "std_msgs/msg/MultiArrayLayout"
    dim: Any = store.types["std_msgs/msg/MultiArrayDimension"]
    make: Any = store.types[layout]
    message = make(dim=[dim(label="x", size=1, stride=1)] * 3, data_offset=0)
    raw = bytes(store.serialize_cdr(message, layout))
    with pytest.raises(Exception, match="sequence length 3"):
        small.deserialize_cdr(raw, layout)
    assert len(store.deserialize_cdr(raw, layout).dim) == 3  # type: ignore[attr-defined]
