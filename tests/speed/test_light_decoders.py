"""Generated decoders against rosbags' deserializer on random messages, intact and damaged.

Random DiagnosticArrays, Logs, GoalStatusArrays, service events and FaultEvents are serialized
with rosbags and decoded both ways: the fields must agree one by one (a disagreement fails). A
damaged payload gets the same verdict both ways: refused by the generated decoder exactly when
rosbags refuses it, and decoded alike otherwise. A bug in generated code propagates, and its
traceback shows the generated line.
"""

from __future__ import annotations

import dataclasses
import traceback
from typing import TYPE_CHECKING, Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from medkit_replay.inputs.cdr import decoders as cdr, generator as cdr_generator
from medkit_replay.inputs.cdr.decoders import (
    REFUSALS,
    DiagnosticArrayView,
    generate,
    generated_decoder,
)
from medkit_replay.inputs.typestore import PLAIN_CDR, DecodeError, make_decoder
from medkit_replay.msgdefs import NO_DEFINITION, Definition, base_typestore
from tests.speed.support import plain

if TYPE_CHECKING:
    from collections.abc import Callable

GENERATED = cdr_generator.__name__
"""The module every generated record class says it comes from."""
TS = base_typestore()
DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"
LOG = "rcl_interfaces/msg/Log"
GOAL_STATUS_ARRAY = "action_msgs/msg/GoalStatusArray"
REPORT_FAULT_EVENT = "ros2_medkit_msgs/srv/ReportFault_Event"
CLEAR_FAULT_EVENT = "ros2_medkit_msgs/srv/ClearFault_Event"
FAULT_EVENT = "ros2_medkit_msgs/msg/FaultEvent"
TIME = "builtin_interfaces/msg/Time"
HOT_TYPES = (
    DIAGNOSTIC_ARRAY,
    LOG,
    GOAL_STATUS_ARRAY,
    REPORT_FAULT_EVENT,
    CLEAR_FAULT_EVENT,
    FAULT_EVENT,
)

# Texts: ASCII mostly, some UTF-8, and NUL in the middle (rosbags keeps it).
text = st.text(
    alphabet=st.one_of(st.characters(codec="ascii"), st.sampled_from("éß°→\x00")), max_size=12
)
u8 = st.integers(0, 255)
i8 = st.integers(-128, 127)
u32 = st.integers(0, 2**32 - 1)
i32 = st.integers(-(2**31), 2**31 - 1)


def new(msgtype: str, /, **fields: Any) -> object:
    return TS.types[msgtype](**fields)


def stamps() -> st.SearchStrategy[object]:
    return st.builds(lambda s, n: new("builtin_interfaces/msg/Time", sec=s, nanosec=n), i32, u32)


def key_values() -> st.SearchStrategy[object]:
    return st.builds(lambda k, v: new("diagnostic_msgs/msg/KeyValue", key=k, value=v), text, text)


def statuses() -> st.SearchStrategy[object]:
    return st.builds(
        lambda level, name, message, hardware_id, values: new(
            "diagnostic_msgs/msg/DiagnosticStatus",
            level=level,
            name=name,
            message=message,
            hardware_id=hardware_id,
            values=values,
        ),
        st.one_of(st.integers(0, 3), i8),
        text,
        text,
        text,
        st.lists(key_values(), max_size=3),
    )


def diagnostic_arrays() -> st.SearchStrategy[object]:
    return st.builds(
        lambda stamp, frame, status: new(
            DIAGNOSTIC_ARRAY,
            header=new("std_msgs/msg/Header", stamp=stamp, frame_id=frame),
            status=status,
        ),
        stamps(),
        text,
        st.lists(statuses(), max_size=6),
    )


def logs() -> st.SearchStrategy[object]:
    return st.builds(
        lambda stamp, level, name, msg, file, function, line: new(
            LOG,
            stamp=stamp,
            level=level,
            name=name,
            msg=msg,
            file=file,
            function=function,
            line=line,
        ),
        stamps(),
        st.one_of(st.sampled_from([10, 20, 30, 40, 50]), u8),
        text,
        text,
        text,
        text,
        u32,
    )


def goal_status_arrays() -> st.SearchStrategy[object]:
    goal = st.builds(
        lambda uuid, stamp, status: new(
            "action_msgs/msg/GoalStatus",
            goal_info=new(
                "action_msgs/msg/GoalInfo",
                goal_id=new(
                    "unique_identifier_msgs/msg/UUID", uuid=np.frombuffer(uuid, dtype=np.uint8)
                ),
                stamp=stamp,
            ),
            status=status,
        ),
        st.binary(min_size=16, max_size=16),
        stamps(),
        st.integers(-128, 127),
    )
    return st.builds(
        lambda goals: new(GOAL_STATUS_ARRAY, status_list=goals), st.lists(goal, max_size=5)
    )


def _info() -> st.SearchStrategy[object]:
    return st.builds(
        lambda event_type, stamp, gid, sequence: new(
            "service_msgs/msg/ServiceEventInfo",
            event_type=event_type,
            stamp=stamp,
            client_gid=np.frombuffer(gid, dtype=np.uint8),
            sequence_number=sequence,
        ),
        st.integers(0, 3),
        stamps(),
        st.binary(min_size=16, max_size=16),
        st.integers(-(2**63), 2**63 - 1),
    )


def report_fault_events() -> st.SearchStrategy[object]:
    request = st.builds(
        lambda code, event_type, severity, description, source: new(
            "ros2_medkit_msgs/srv/ReportFault_Request",
            fault_code=code,
            event_type=event_type,
            severity=severity,
            description=description,
            source_id=source,
        ),
        text,
        u8,
        u8,
        text,
        text,
    )
    response = st.builds(
        lambda accepted: new("ros2_medkit_msgs/srv/ReportFault_Response", accepted=accepted),
        st.booleans(),
    )
    return st.builds(
        lambda info, req, resp: new(REPORT_FAULT_EVENT, info=info, request=req, response=resp),
        _info(),
        st.lists(request, max_size=1),
        st.lists(response, max_size=1),
    )


def clear_fault_events() -> st.SearchStrategy[object]:
    request = st.builds(
        lambda code, skip: new(
            "ros2_medkit_msgs/srv/ClearFault_Request",
            fault_code=code,
            skip_correlation_auto_clear=skip,
        ),
        text,
        st.booleans(),
    )
    response = st.builds(
        lambda success, message, codes: new(
            "ros2_medkit_msgs/srv/ClearFault_Response",
            success=success,
            message=message,
            auto_cleared_codes=codes,
        ),
        st.booleans(),
        text,
        st.lists(text, max_size=3),
    )
    return st.builds(
        lambda info, req, resp: new(CLEAR_FAULT_EVENT, info=info, request=req, response=resp),
        _info(),
        st.lists(request, max_size=1),
        st.lists(response, max_size=1),
    )


def fault_events() -> st.SearchStrategy[object]:
    fault = st.builds(
        lambda code, severity, description, first, last, passed, count, status, sources: new(
            "ros2_medkit_msgs/msg/Fault",
            fault_code=code,
            severity=severity,
            description=description,
            first_occurred=first,
            last_occurred=last,
            last_passed=passed,
            occurrence_count=count,
            status=status,
            reporting_sources=sources,
        ),
        text,
        u8,
        text,
        stamps(),
        stamps(),
        stamps(),
        u32,
        text,
        st.lists(text, max_size=3),
    )
    return st.builds(
        lambda kind, f, stamp, codes: new(
            FAULT_EVENT, event_type=kind, fault=f, timestamp=stamp, auto_cleared_codes=codes
        ),
        text,
        fault,
        stamps(),
        st.lists(text, max_size=3),
    )


STRATEGIES: dict[str, Callable[[], st.SearchStrategy[object]]] = {
    DIAGNOSTIC_ARRAY: diagnostic_arrays,
    LOG: logs,
    GOAL_STATUS_ARRAY: goal_status_arrays,
    REPORT_FAULT_EVENT: report_fault_events,
    CLEAR_FAULT_EVENT: clear_fault_events,
    FAULT_EVENT: fault_events,
}


REFUSED = "refused"


def light(msgtype: str) -> Callable[[bytes], object]:
    decode = generated_decoder(msgtype, TS)
    assert decode is not None
    return decode


def both(msgtype: str, raw: bytes) -> tuple[object, object, object]:
    """What rosbags, the generated decoder and the product's Decoder make of a payload.

    A refusal is :data:`REFUSED`; anything else a generated decoder raises is a bug and
    propagates.
    """
    try:
        expected: object = plain(TS.deserialize_cdr(raw, msgtype))
    except Exception:  # rosbags' verdict, whatever its kind
        expected = REFUSED
    try:
        got: object = plain(light(msgtype)(raw))
    except REFUSALS:
        got = REFUSED
    decoder, _ = make_decoder(msgtype, NO_DEFINITION, pytest.fail)
    try:
        product: object = plain(decoder.decode(raw))
    except DecodeError:
        product = REFUSED
    return expected, got, product


def test_every_hot_type_has_a_generated_decoder() -> None:
    for msgtype in HOT_TYPES:
        assert generated_decoder(msgtype, TS) is not None
    array = new(
        DIAGNOSTIC_ARRAY,
        header=new("std_msgs/msg/Header", stamp=new(TIME, sec=1, nanosec=2), frame_id=""),
        status=[],
    )
    raw = bytes(TS.serialize_cdr(array, DIAGNOSTIC_ARRAY))
    assert isinstance(light(DIAGNOSTIC_ARRAY)(raw), DiagnosticArrayView)


@pytest.mark.parametrize("msgtype", HOT_TYPES)
@settings(max_examples=150, suppress_health_check=[HealthCheck.too_slow], deadline=None)
@given(data=st.data())
def test_light_decoders_agree_with_rosbags(msgtype: str, data: st.DataObject) -> None:
    message = data.draw(STRATEGIES[msgtype]())
    raw = bytes(TS.serialize_cdr(message, msgtype))
    expected, got, product = both(msgtype, raw)
    assert got == expected == product == plain(message)
    if msgtype == DIAGNOSTIC_ARRAY:
        view = light(msgtype)(raw)
        assert isinstance(view, DiagnosticArrayView)
        assert view.heads == [
            (s.level, s.name, s.message, s.hardware_id)
            for s in message.status  # type: ignore[attr-defined]
        ]
        assert view == light(msgtype)(raw)
    generic = generate(msgtype, TS)[0]
    assert plain(generic(raw)) == expected


@pytest.mark.parametrize("msgtype", HOT_TYPES)
@settings(max_examples=150, suppress_health_check=[HealthCheck.too_slow], deadline=None)
@given(data=st.data())
def test_damaged_payloads_are_refused_whenever_rosbags_refuses(
    msgtype: str, data: st.DataObject
) -> None:
    raw = bytearray(TS.serialize_cdr(data.draw(STRATEGIES[msgtype]()), msgtype))
    damage = data.draw(st.sampled_from(["flip", "cut", "grow", "set"]))
    at = data.draw(st.integers(0, max(len(raw) - 1, 0)))
    if damage == "flip":
        raw[at] ^= data.draw(st.integers(1, 255))
    elif damage == "cut":
        del raw[at:]
    elif damage == "grow":
        raw += bytes(data.draw(st.integers(1, 9)))
    else:
        raw[at : at + 4] = data.draw(st.integers(0, 2**32 - 1)).to_bytes(4, "little")
    expected, got, product = both(msgtype, bytes(raw))
    assert product == expected  # refused both ways, or decoded alike
    if raw[:2] == PLAIN_CDR:  # other encapsulations are rosbags' alone
        assert got == expected


@settings(max_examples=60, deadline=None)
@given(message=diagnostic_arrays())
def test_a_big_endian_payload_goes_to_rosbags(message: object) -> None:
    raw = bytes(TS.serialize_cdr(message, DIAGNOSTIC_ARRAY, little_endian=False))
    decoder, _ = make_decoder(DIAGNOSTIC_ARRAY, NO_DEFINITION, pytest.fail)
    decoded = decoder.decode(raw)
    assert not isinstance(decoded, DiagnosticArrayView)  # routed by its header, to rosbags
    assert not dataclasses.is_dataclass(decoded) or type(decoded).__module__ != GENERATED
    assert plain(decoded) == plain(TS.deserialize_cdr(raw, DIAGNOSTIC_ARRAY))


def test_a_definition_other_than_the_standard_gets_its_own_decoder() -> None:
    # A DiagnosticStatus without hardware_id: the hand-written decoder does not apply; the
    # generated one follows the recording's definition, as rosbags does.
    text = (
        "std_msgs/Header header\nDiagnosticStatus[] status\n"
        "================================================================================\n"
        "MSG: diagnostic_msgs/DiagnosticStatus\nbyte level\nstring name\nstring message\n"
        "================================================================================\n"
        "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n"
        "================================================================================\n"
        "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
    )
    decoder, problem = make_decoder(DIAGNOSTIC_ARRAY, Definition("ros2msg", text), pytest.fail)
    assert problem is None
    raw = bytes.fromhex("00010000") + bytes(8) + b"\x01\x00\x00\x00\x00\x00\x00\x00"
    raw += b"\x01\x00\x00\x00" + b"\x02\x00\x00\x00" + b"\x02\x00\x00\x00a\x00\x00\x00"
    raw += b"\x03\x00\x00\x00ok\x00"
    message = decoder.decode(raw)
    assert not isinstance(message, DiagnosticArrayView)
    assert type(message).__module__ == GENERATED  # a generated record, not rosbags' class
    assert plain(message)["status"] == [  # type: ignore[index]
        {"level": ("int", 2), "name": ("str", "a"), "message": ("str", "ok")}
    ]


def test_a_bug_in_generated_code_propagates(monkeypatch: pytest.MonkeyPatch) -> None:
    original = cdr_generator.Generator.prim

    def forgetful(self: cdr_generator.Generator, typ: str) -> str:
        key = original(self, typ)
        del self.names[key]  # the generated code now calls a name its namespace lacks
        return key

    monkeypatch.setattr(cdr_generator.Generator, "prim", forgetful)
    monkeypatch.setattr(cdr, "_CACHE", {})
    decoder, _ = make_decoder(TIME, NO_DEFINITION, pytest.fail)
    raw = bytes(TS.serialize_cdr(new(TIME, sec=1, nanosec=2), TIME))
    with pytest.raises(NameError):  # a bug, never a refusal nor a detour through rosbags
        decoder.decode(raw)


def test_a_traceback_through_a_generated_decoder_shows_its_line() -> None:
    decode, source = generate(TIME, TS)
    with pytest.raises(REFUSALS) as caught:
        decode(b"\x00\x01\x00\x00\x01")  # cut inside ``sec``
    frame = traceback.extract_tb(caught.value.__traceback__)[-1]
    assert frame.filename.startswith(f"<medkit-replay decoder of {TIME} #")
    assert frame.lineno is not None
    assert frame.line == source.splitlines()[frame.lineno - 1].strip()
    assert "(raw, p)" in frame.line
    assert "u_int32(raw, p)" in "".join(traceback.format_exception(caught.value))
