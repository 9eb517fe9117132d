"""The hand-written ROS 1 DiagnosticArray decoder against rosbags' ROS 1 deserializer.

Every payload, intact or damaged, either gives the heads rosbags' full decode gives, or fails
with rosbags' own error.
"""

from __future__ import annotations

import random
from typing import Any

import pytest

from medkit_replay.inputs.ros1_diagnostics import (
    Ros1DiagnosticArrayView,
    decode_diagnostic_array,
    full_decode,
)
from medkit_replay.inputs.ros1_messages import diagnostic_array
from tests.inputs.ros1_builders import TS1, diag1, header1, new1

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
