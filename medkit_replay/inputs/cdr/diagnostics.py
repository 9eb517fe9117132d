"""A hand-written decoder for the standard diagnostic_msgs/msg/DiagnosticArray, the hottest type.

It checks every payload as rosbags would and hands the bridge each status's head, decoded once.
"""

from __future__ import annotations

import sys
from struct import Struct
from typing import TYPE_CHECKING

from rosbags.interfaces import Nodetype

from medkit_replay.inputs.cdr.generator import Generator
from medkit_replay.inputs.cdr.refusals import (
    NOT_PLAIN,
    RejectedError,
    UnsupportedError,
    sequence_refusal,
    string_refusal,
)
from medkit_replay.inputs.cdr.rosbags_internals import max_sequence_length, unpack_le

if TYPE_CHECKING:
    from collections.abc import Callable

    from rosbags.interfaces.typing import FieldDesc, Typesdict
    from rosbags.typesys.store import Typestore


DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"
_U32 = unpack_le("uint32")
_BYTE = unpack_le("byte")
_TIME = Struct("<iI").unpack_from
_MAX_HEADS = 4096


def layout(types: Typesdict, typename: str) -> tuple[object, ...]:
    """A type's fields with every referenced type expanded: what decoding depends on.

    ``types`` maps names to (constants, fields), as a store's ``fielddefs`` does.
    """
    return tuple(
        (name, layout(types, desc[1]) if desc[0] == Nodetype.NAME else _sublayout(types, desc))
        for name, desc in types[typename][1]
    )


def _sublayout(types: Typesdict, desc: FieldDesc) -> object:
    if desc[0] in (Nodetype.ARRAY, Nodetype.SEQUENCE):
        sub, bound = desc[1]
        inner = layout(types, sub[1]) if sub[0] == Nodetype.NAME else sub
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


def diagnostic_array(store: Typestore) -> Callable[[bytes], object]:
    """The DiagnosticArray decoder of the standard layout, remembering repeated status heads.

    Checks every payload exactly as rosbags would (lengths, terminators, UTF-8, trailing
    bytes); a status's level, name, message and hardware_id are decoded once per distinct
    run of bytes, its key/value pairs only checked (they are decoded when ``status`` is read).
    """
    if sys.byteorder != "little":
        raise UnsupportedError("the DiagnosticArray decoder reads words natively")
    gen = Generator(store)
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
            raise RejectedError(NOT_PLAIN)
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
