"""The freeze frame's ``data``: a message as ros2_medkit_serialization renders it.

Upstream's own tests (test_json_serializer.cpp) fix the YAML-to-JSON typing of scalars (bool,
integer, float, string, lists, objects); the rest follows its dynmsg configuration (values only,
8-bit integers as text) and yaml-cpp's float text (max_digits10, .nan/.inf), as read there.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from medkit_replay.evidence.render import float_text, render, scalar

TS = get_typestore(Stores.ROS2_HUMBLE)

SCALARS = [
    # upstream's YamlToJson cases
    ("true", True),
    ("42", 42),
    ("3.14", 3.14),
    ("hello", "hello"),
    # the spellings it takes for booleans, and one it does not
    ("yes", True),
    ("No", False),
    ("False", False),
    ("on", "on"),
    # integers: a leading digit or minus, the whole text, within int64
    ("-7", -7),
    ("007", 7),
    ("+5", "+5"),
    ("0x1A", "0x1A"),
    (str(2**63), 9.223372036854776e18),
    # floats: a leading digit, minus or dot, the whole text
    (".5", 0.5),
    ("1e+20", 1e20),
    ("-2.5E-3", -0.0025),
    ("1e999", "1e999"),
    # yaml-cpp's non-finite spellings are not numbers to C++'s stod: they stay text
    (".nan", ".nan"),
    (".inf", ".inf"),
    ("-.inf", "-.inf"),
    ("", ""),
    ("12345", 12345),
    (" 1", " 1"),
]


@pytest.mark.parametrize(("text", "value"), SCALARS)
def test_scalar_typing(text: str, value: object) -> None:
    got = scalar(text)
    assert got == value and type(got) is type(value)


FLOATS = [
    (1.0, False, "1"),
    (0.1, False, "0.10000000000000001"),
    (0.1, True, "0.100000001"),
    (1e20, False, "1e+20"),
    (-0.0, False, "-0"),
    (math.nan, False, ".nan"),
    (math.inf, True, ".inf"),
    (-math.inf, False, "-.inf"),
]


@pytest.mark.parametrize(("value", "single", "text"), FLOATS)
def test_float_text(value: float, single: bool, text: str) -> None:
    single_value = float(np.float32(value)) if single else value
    assert float_text(single_value, single=single) == text


def test_a_message_renders_with_sorted_keys_and_upstreams_quirks() -> None:
    msg = TS.types["sensor_msgs/msg/BatteryState"](
        header=TS.types["std_msgs/msg/Header"](
            stamp=TS.types["builtin_interfaces/msg/Time"](sec=5, nanosec=7), frame_id="yes"
        ),
        voltage=12.0,
        temperature=math.nan,
        current=math.inf,
        charge=-math.inf,
        capacity=0.1,
        design_capacity=1e20,
        percentage=0.5,
        power_supply_status=1,
        power_supply_health=0,
        power_supply_technology=255,
        present=False,
        cell_voltage=np.array([3.5, 3.25], dtype=np.float32),
        cell_temperature=np.array([], dtype=np.float32),
        location="3.5",
        serial_number="",
    )
    kind = "sensor_msgs/msg/BatteryState"
    data = render(TS, kind, TS.deserialize_cdr(TS.serialize_cdr(msg, kind), kind))
    assert data == {
        "capacity": 0.100000001,  # float32's nine digits
        "cell_temperature": None,  # an empty list is YAML null
        "cell_voltage": [3.5, 3.25],
        "charge": "-.inf",
        "current": ".inf",
        "design_capacity": 1.00000002e20,  # float32's nine digits in exponent form
        "header": {"frame_id": True, "stamp": {"nanosec": 7, "sec": 5}},
        "location": 3.5,
        "percentage": 0.5,
        "power_supply_health": 0,
        "power_supply_status": 1,
        "power_supply_technology": 255,
        "present": False,
        "serial_number": "",
        "temperature": ".nan",
        "voltage": 12,
    }
    assert list(data or {}) == sorted(data or {})
    json.dumps(data, allow_nan=False)  # strict JSON


def test_bytes_render_as_integers() -> None:
    msg = TS.types["std_msgs/msg/UInt8MultiArray"](
        layout=TS.types["std_msgs/msg/MultiArrayLayout"](dim=[], data_offset=0),
        data=np.array([0, 7, 255], dtype=np.uint8),
    )
    assert render(TS, "std_msgs/msg/UInt8MultiArray", msg) == {
        "data": [0, 7, 255],
        "layout": {"data_offset": 0, "dim": None},
    }
