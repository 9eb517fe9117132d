"""Hand-written decoders for the two ROS 1 types read most, DiagnosticArray and Log.

Each checks a payload as rosbags would and leaves any payload it refuses to rosbags' own error.
"""

from __future__ import annotations

import struct
from typing import TYPE_CHECKING

from medkit_replay.inputs.ros1.messages import (
    ROS1_DIAGNOSTIC_ARRAY,
    ROS1_LOG,
    diagnostic_array,
    log,
    ros1_typestore,
    ros2_log,
)

if TYPE_CHECKING:
    from collections.abc import Callable

_U32 = struct.Struct("<I").unpack_from
_SEQ_AND_STAMP = struct.Struct("<IiI").unpack_from  # as rosbags: Time.sec int32, nanosec uint32
_HEADER_BYTES = 12  # seq, stamp.sec, stamp.nsec
_MIN_STATUS_BYTES = 1 + 4 * 4  # level, three empty strings, no values
_MIN_PAIR_BYTES = 2 * 4


class Ros1DiagnosticArrayView:
    """A ROS 1 DiagnosticArray decoded for the diagnostic bridge, as a ROS 2 one reads.

    ``heads`` holds each status's (level, name, message, hardware_id); ``header`` and ``status``
    are those of the ROS 2 message the conversion builds (:func:`diagnostic_array`), made when
    first read.
    """

    __slots__ = ("_built", "_raw", "heads")
    __msgtype__ = "diagnostic_msgs/msg/DiagnosticArray"

    def __init__(self, heads: list[tuple[int, str, str, str]], raw: bytes) -> None:
        self.heads = heads
        self._raw = raw
        self._built: object | None = None

    def _full(self) -> object:
        if self._built is None:
            self._built = diagnostic_array(full_decode(self._raw))
        return self._built

    @property
    def header(self) -> object:
        """std_msgs/msg/Header (ROS 2: no ``seq``)."""
        return self._full().header  # type: ignore[attr-defined]

    @property
    def status(self) -> object:
        """The diagnostic_msgs/msg/DiagnosticStatus list."""
        return self._full().status  # type: ignore[attr-defined]


def full_decode(raw: bytes) -> object:
    """rosbags' decoding of the payload (its errors are the ones reported)."""
    return ros1_typestore().deserialize_ros1(raw, ROS1_DIAGNOSTIC_ARRAY)


def decode_diagnostic_array(raw: bytes) -> object:
    """A payload's statuses' heads, checked as rosbags checks the whole payload.

    A payload the walk refuses is decoded by rosbags, which raises its own error for it.
    """
    try:
        return Ros1DiagnosticArrayView(_heads(raw), raw)
    except (ValueError, IndexError, struct.error):  # UnicodeDecodeError is a ValueError
        return diagnostic_array(full_decode(raw))


def _heads(raw: bytes) -> list[tuple[int, str, str, str]]:
    # Inlined string reads: this loop runs for every status of every array. A length running
    # past the end fails the next unpack_from, or the final check; every string is decoded, as
    # rosbags decodes it, so that the walk refuses exactly what rosbags refuses.
    u32 = _U32
    end = len(raw)
    (size,) = u32(raw, _HEADER_BYTES)
    pos = _HEADER_BYTES + 4 + size
    raw[_HEADER_BYTES + 4 : pos].decode()  # frame_id
    (count,) = u32(raw, pos)
    pos += 4
    if count > (end - pos) // _MIN_STATUS_BYTES:
        raise ValueError("more statuses than bytes")
    heads: list[tuple[int, str, str, str]] = []
    append = heads.append
    for _ in range(count):
        level = raw[pos]
        (size,) = u32(raw, pos + 1)
        start = pos + 5
        pos = start + size
        name = raw[start:pos].decode()
        (size,) = u32(raw, pos)
        start = pos + 4
        pos = start + size
        message = raw[start:pos].decode()
        (size,) = u32(raw, pos)
        start = pos + 4
        pos = start + size
        hardware_id = raw[start:pos].decode()
        (pairs,) = u32(raw, pos)
        pos += 4
        if pairs > (end - pos) // _MIN_PAIR_BYTES:
            raise ValueError("more key/value pairs than bytes")
        for _ in range(2 * pairs):
            (size,) = u32(raw, pos)
            start = pos + 4
            pos = start + size
            raw[start:pos].decode()
        # rosbags decodes a ROS 1 byte signed.
        append((level - 256 if level > 127 else level, name, message, hardware_id))
    if pos != end:
        raise ValueError("bytes left after the last status")
    return heads


def _string(raw: bytes, pos: int, end: int) -> tuple[str, int]:
    (size,) = _U32(raw, pos)
    start = pos + 4
    stop = start + size
    if stop > end:
        raise ValueError("string past the end")
    return raw[start:stop].decode(), stop


def _skip_string(raw: bytes, pos: int, end: int) -> int:
    return _string(raw, pos, end)[1]


def full_decode_log(raw: bytes) -> object:
    """rosbags' decoding of a rosgraph_msgs/Log payload (its errors are the ones reported)."""
    return ros1_typestore().deserialize_ros1(raw, ROS1_LOG)


def decode_log(raw: bytes) -> object:
    """A rosgraph_msgs/Log payload as rcl_interfaces/msg/Log (:func:`ros2_log`), walked by hand.

    A payload the walk refuses is decoded by rosbags, which raises its own error for it.
    """
    try:
        return _log(raw)
    except (ValueError, IndexError, struct.error):  # UnicodeDecodeError is a ValueError
        return log(full_decode_log(raw))


def _log(raw: bytes) -> object:
    end = len(raw)
    _, sec, nanosec = _SEQ_AND_STAMP(raw, 0)
    pos = _skip_string(raw, _HEADER_BYTES, end)  # frame_id
    level = raw[pos]
    name, pos = _string(raw, pos + 1, end)
    msg, pos = _string(raw, pos, end)
    file, pos = _string(raw, pos, end)
    function, pos = _string(raw, pos, end)
    line, topics = _U32(raw, pos)[0], _U32(raw, pos + 4)[0]
    pos += 8
    if topics > (end - pos) // 4:
        raise ValueError("more topics than bytes")
    for _ in range(topics):
        pos = _skip_string(raw, pos, end)
    if pos != end:
        raise ValueError("bytes left after the topics")
    return ros2_log(sec, nanosec, level, name, msg, file, function, line)


DECODERS: dict[str, Callable[[bytes], object]] = {
    ROS1_DIAGNOSTIC_ARRAY: decode_diagnostic_array,
    ROS1_LOG: decode_log,
}
"""Hand-written decoders by ROS 1 type: payload to the message the bridges read."""
