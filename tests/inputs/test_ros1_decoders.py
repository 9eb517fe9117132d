"""The hand-written ROS 1 DiagnosticArray and Log decoders against rosbags' ROS 1 deserializer.

Every payload, intact or damaged, either gives the heads rosbags' full decode gives, or fails
with rosbags' own error.
"""

from __future__ import annotations

import random
from typing import TYPE_CHECKING, Any

import pytest

from medkit_replay.inputs.ros1.decoders import (
    Ros1DiagnosticArrayView,
    decode_diagnostic_array,
    decode_log,
    full_decode,
    full_decode_log,
)
from medkit_replay.inputs.ros1.messages import diagnostic_array, log, log_level
from tests.inputs.ros1_builders import TS1, diag1, header1, new1

if TYPE_CHECKING:
    from collections.abc import Callable

T = 1_700_000_000 * 10**9


def payload(msg: object) -> bytes:
    return bytes(TS1.serialize_ros1(msg, "diagnostic_msgs/msg/DiagnosticArray"))


def array(statuses: int, pairs: int, level: int = 1) -> object:
    return new1(
        "diagnostic_msgs/msg/DiagnosticArray",
        header=header1(T),
        status=[
            new1(
                "diagnostic_msgs/msg/DiagnosticStatus",
                level=level,
                name=f"n{k} ü",
                message="m" * k,
                hardware_id=f"hw/{k}",
                values=[
                    new1("diagnostic_msgs/msg/KeyValue", key=f"k{j}", value="v")
                    for j in range(pairs)
                ],
            )
            for k in range(statuses)
        ],
    )


def outcome(raw: bytes) -> tuple[str, object]:
    """What decoding gives: the heads and full message, or the error's text."""
    try:
        got: Any = decode_diagnostic_array(raw)
    except Exception as exc:  # compared with rosbags' own
        return "error", str(exc)
    heads = [(s.level, s.name, s.message, s.hardware_id) for s in got.status]
    if isinstance(got, Ros1DiagnosticArrayView):
        assert got.heads == heads
    return "ok", repr(got.status) + repr(got.header)


def reference(raw: bytes) -> tuple[str, object]:
    try:
        full: Any = diagnostic_array(full_decode(raw))
    except Exception as exc:
        return "error", str(exc)
    return "ok", repr(full.status) + repr(full.header)


@pytest.mark.parametrize(
    ("statuses", "pairs", "level"), [(0, 0, 0), (1, 0, 2), (5, 3, 3), (3, 1, -3)]
)
def test_intact_payloads_decode_as_rosbags_does(statuses: int, pairs: int, level: int) -> None:
    raw = payload(array(statuses, pairs, level))
    got = decode_diagnostic_array(raw)
    assert isinstance(got, Ros1DiagnosticArrayView)
    assert outcome(raw) == reference(raw)


def test_damaged_payloads_fail_or_decode_as_rosbags_does() -> None:
    rng = random.Random(15)
    raws = [payload(array(4, 2)), payload(diag1(T).msg)]
    for _ in range(3000):
        raw = bytearray(rng.choice(raws))
        kind = rng.randrange(4)
        if kind == 0:  # flip a byte
            raw[rng.randrange(len(raw))] ^= 1 << rng.randrange(8)
        elif kind == 1:  # cut
            raw = raw[: rng.randrange(len(raw))]
        elif kind == 2:  # a hostile length somewhere
            at = rng.randrange(len(raw) - 4)
            raw[at : at + 4] = rng.choice([0xFFFFFFFF, 0x7FFFFFFF, 1000]).to_bytes(4, "little")
        else:  # trailing bytes
            raw += bytes(rng.randrange(1, 5))
        assert outcome(bytes(raw)) == reference(bytes(raw))


# -- rosgraph_msgs/Log ---------------------------------------------------------------------------


def log_payload(level: int, topics: int, text: str = "lost it ü") -> bytes:
    msg = new1(
        "rosgraph_msgs/msg/Log",
        header=header1(T),
        level=level,
        name="/ns/node",
        msg=text,
        file="a.cpp",
        function="f",
        line=7,
        topics=[f"/t{k}" for k in range(topics)],
    )
    return bytes(TS1.serialize_ros1(msg, "rosgraph_msgs/msg/Log"))


def log_outcome(decode: Callable[[bytes], object], raw: bytes) -> tuple[str, str]:
    try:
        return "ok", repr(decode(raw))
    except Exception as exc:  # compared with rosbags' own
        return "error", str(exc)


@pytest.mark.parametrize(("level", "topics"), [(1, 0), (8, 2), (16, 1), (-128, 0), (127, 3)])
def test_intact_logs_decode_as_rosbags_does(level: int, topics: int) -> None:
    raw = log_payload(level, topics)
    assert log_outcome(decode_log, raw) == log_outcome(lambda r: log(full_decode_log(r)), raw)
    assert decode_log(raw).level == log_level(level)  # type: ignore[attr-defined]


def test_damaged_logs_fail_or_decode_as_rosbags_does() -> None:
    rng = random.Random(16)
    raws = [log_payload(8, 2), log_payload(2, 0, "")]
    for _ in range(3000):
        raw = bytearray(rng.choice(raws))
        kind = rng.randrange(4)
        if kind == 0:
            raw[rng.randrange(len(raw))] ^= 1 << rng.randrange(8)
        elif kind == 1:
            raw = raw[: rng.randrange(len(raw))]
        elif kind == 2:
            at = rng.randrange(len(raw) - 4)
            raw[at : at + 4] = rng.choice([0xFFFFFFFF, 0x7FFFFFFF, 1000]).to_bytes(4, "little")
        else:
            raw += bytes(rng.randrange(1, 5))
        reference_decode = lambda r: log(full_decode_log(r))  # noqa: E731
        assert log_outcome(decode_log, bytes(raw)) == log_outcome(reference_decode, bytes(raw))
