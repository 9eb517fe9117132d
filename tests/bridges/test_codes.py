"""The exact code vectors of bridges.md §1.5 (action), §2.3 (diagnostic) and §3.2 (log).

Every expected string was produced upstream by the original C++ (the spec's "verified" values).
"""

from __future__ import annotations

import re

import pytest

from medkit_replay.bridges.codes import (
    action_code_prefix,
    action_fault_code,
    fnv1a32_hex,
    hash_bounded,
    libstdcxx_string_hash,
    log_code_prefix,
    log_fault_code,
    log_message_template,
    truncate_code,
    upper_snake,
)

WELL_FORMED_ACTION = re.compile(r"[A-Z0-9_]{1,64}")
WELL_FORMED_LOG = re.compile(r"[A-Z0-9_]+_[0-9a-f]{8}")

# --- libstdc++ std::hash<std::string> (Appendix A vectors) ---


@pytest.mark.parametrize(
    ("data", "expected"),
    [(b"", 0x553E93901E462A6E), (b"a", 0x454DDEE488C1ED6B), (b"foobar", 0x0DF632C12592DB33)],
)
def test_libstdcxx_string_hash(data: bytes, expected: int) -> None:
    assert libstdcxx_string_hash(data) == expected


def test_libstdcxx_string_hash_covers_whole_blocks_and_tails() -> None:
    # 80 bytes (ten whole blocks) and 81 (a tail): the tags §1.5 pins for "/"+"a"*80.
    assert libstdcxx_string_hash(b"A" * 80) & 0xFFFF == 0x4A4E
    assert libstdcxx_string_hash(b"A" * 80) != libstdcxx_string_hash(b"A" * 81)


# --- §1.5 action status bridge ---

ACTION_VECTORS = [
    ("/navigate_to_pose", "ACTION_NAVIGATE_TO_POSE_ABORTED", "ACTION_NAVIGATE_TO_POSE_CANCELED"),
    ("/move_action", "ACTION_MOVE_ACTION_ABORTED", "ACTION_MOVE_ACTION_CANCELED"),
    ("/test_action", "ACTION_TEST_ACTION_ABORTED", "ACTION_TEST_ACTION_CANCELED"),
    ("/nav", "ACTION_NAV_ABORTED", "ACTION_NAV_CANCELED"),
    ("/arm", "ACTION_ARM_ABORTED", "ACTION_ARM_CANCELED"),
    (
        "/robot1/navigate_to_pose",
        "ACTION_ROBOT1_NAVIGATE_TO_POSE_ABORTED",
        "ACTION_ROBOT1_NAVIGATE_TO_POSE_CANCELED",
    ),
    ("/MoveGroup", "ACTION_MOVEGROUP_ABORTED", "ACTION_MOVEGROUP_CANCELED"),
    ("/a__b--c", "ACTION_A_B_C_ABORTED", "ACTION_A_B_C_CANCELED"),
    ("/café_action", "ACTION_CAF_ACTION_ABORTED", "ACTION_CAF_ACTION_CANCELED"),
    (
        "/follow_joint_trajectory_controller/follow_joint_trajectory",
        "ACTION_FOLLOW_JOINT_TRAJECTORY_CONTROLLER_FOLLOW_27D0_ABORTED",
        "ACTION_FOLLOW_JOINT_TRAJECTORY_CONTROLLER_FOLLOW_27D0_CANCELED",
    ),
    (
        "/" + "a" * 80,
        "ACTION_" + "A" * 42 + "_4A4E_ABORTED",
        "ACTION_" + "A" * 42 + "_4A4E_CANCELED",
    ),
]


@pytest.mark.parametrize(("action", "aborted", "canceled"), ACTION_VECTORS)
def test_action_fault_code_vectors(action: str, aborted: str, canceled: str) -> None:
    assert action_fault_code("ACTION", action, canceled=False) == aborted
    assert action_fault_code("ACTION", action, canceled=True) == canceled
    for code in (aborted, canceled):
        assert WELL_FORMED_ACTION.fullmatch(code)


@pytest.mark.parametrize(
    ("suffix", "tag"), [("_alpha", "3997"), ("_bravo", "0972")], ids=["alpha", "bravo"]
)
def test_action_fault_code_shared_long_head_gets_distinct_tags(suffix: str, tag: str) -> None:
    code = action_fault_code("ACTION", "/" + "x" * 60 + suffix, canceled=False)
    assert code == "ACTION_" + "X" * 42 + f"_{tag}_ABORTED"
    assert len(code) <= 64


@pytest.mark.parametrize(
    ("raw", "expected"),
    [
        ("ACTION", "ACTION"),
        ("my-prefix", "MY_PREFIX"),
        ("nav2 actions", "NAV2_ACTIONS"),
        ("!!!", ""),  # the config falls back to ACTION (and warns)
        ("p" * 60, "P" * 43 + "_4B1E"),
    ],
)
def test_action_code_prefix_normalisation(raw: str, expected: str) -> None:
    assert action_code_prefix(raw) == expected


def test_action_fault_code_long_prefix_leaves_a_hash_only_action_part() -> None:
    prefix = "P" * 43 + "_4B1E"
    code = action_fault_code(prefix, "/navigate_to_pose", canceled=False)
    assert code == prefix + "__0121_ABORTED"
    assert len(code) <= 64


def test_action_fault_code_empty_action_part_has_no_separator() -> None:
    assert action_fault_code("ACTION", "/", canceled=True) == "ACTION_CANCELED"


def test_hash_bounded_keeps_short_codes_and_tags_long_ones() -> None:
    assert hash_bounded("SHORT", 48) == "SHORT"
    assert hash_bounded("A" * 48, 48) == "A" * 48
    bounded = hash_bounded("A" * 49, 48)
    assert len(bounded) == 48
    assert bounded.startswith("A" * 43 + "_")
    assert hash_bounded("ABCDEFGH", 5) == f"_{libstdcxx_string_hash(b'ABCDEFGH') & 0xFFFF:04X}"


# --- §2.3 diagnostic bridge (generate_fault_code = upper_snake, no prefix, no cap) ---


@pytest.mark.parametrize(
    ("name", "code"),
    [
        ("motor temp", "MOTOR_TEMP"),
        ("motor_temperature", "MOTOR_TEMPERATURE"),
        ("motor: Status", "MOTOR_STATUS"),
        ("/robot/sensor", "ROBOT_SENSOR"),
        ("motor::temp", "MOTOR_TEMP"),
        ("motor  temp", "MOTOR_TEMP"),
        ("motor - temp", "MOTOR_TEMP"),
        ("/motor", "MOTOR"),
        ("motor/", "MOTOR"),
        ("  motor  ", "MOTOR"),
        ("Battery Level Monitor", "BATTERY_LEVEL_MONITOR"),
        ("lidar_driver: Frequency (Hz)", "LIDAR_DRIVER_FREQUENCY_HZ"),
        ("café x", "CAF_X"),
        ("", ""),
        ("---", ""),
    ],
)
def test_diagnostic_generated_codes(name: str, code: str) -> None:
    assert upper_snake(name) == code


def test_upper_snake_has_no_length_cap() -> None:
    assert upper_snake("x" * 300) == "X" * 300


# --- §3.2 log bridge ---

LOG_VECTORS = [
    ("/planner_server", "failed to create plan to (100.0, 100.0)", "LOG_PLANNER_SERVER_ac8dd4db"),
    ("/planner_server", "failed to create plan to (5.0, 5.0)", "LOG_PLANNER_SERVER_ac8dd4db"),
    ("/ctrl", "oops 42", "LOG_CTRL_0bf0b26e"),
    ("/ctrl", "command interface not available", "LOG_CTRL_6fc3f7e3"),
    ("/ctrl", "could not find controller", "LOG_CTRL_8c6d058e"),
    ("/ctrl", "", "LOG_CTRL_a9b1099a"),
    ("/ctrl", "!!!", "LOG_CTRL_a9b1099a"),
    ("/ctrl", "actual failure", "LOG_CTRL_81cad281"),
    ("/robot1/planner_server", "no plan", "LOG_ROBOT1_PLANNER_SERVER_7631a035"),
    ("/robot2/planner_server", "no plan", "LOG_ROBOT2_PLANNER_SERVER_7631a035"),
    ("/" + "x" * 200 + "/planner_server", "boom", "LOG_" + "X" * 48 + "_c79493aa"),
    ("/planner_server", "failed to compute path", "LOG_PLANNER_SERVER_09fef28f"),
    ("/controller", "goal tolerance exceeded", "LOG_CONTROLLER_2e4c897a"),
    ("/chatter", "all good", "LOG_CHATTER_5a2f8611"),
    ("/bt_navigator", "Goal failed", "LOG_BT_NAVIGATOR_4fc83613"),
]


@pytest.mark.parametrize(("source_id", "message", "code"), LOG_VECTORS)
def test_log_fault_code_vectors(source_id: str, message: str, code: str) -> None:
    assert log_fault_code("LOG", source_id, message) == code
    assert len(code) <= 64
    assert WELL_FORMED_LOG.fullmatch(code)


@pytest.mark.parametrize(
    ("message", "template"),
    [
        ("failed to create plan to (100.0, 100.0)", "failed to create plan to"),
        ("oops 42", "oops"),
        ("worldToMap failed: mx,my: 2200,2200", "worldtomap failed mx my"),
        ("Failed to open /dev/ttyACM0 (errno 0x19)", "failed to open dev ttyacm errno"),
        ("Failed to open /dev/ttyACM5 (errno 0x05)", "failed to open dev ttyacm errno"),
        ("Failed to open /dev/ttyUSB0 (errno 0x19)", "failed to open dev ttyusb errno"),
        ("connection lost to host A", "connection lost to host"),
        ("Sensor_Timeout on x-axis", "sensor timeout on axis"),
        ("", ""),
        ("12345", ""),
        ("--- 0x1f ::", ""),
    ],
)
def test_log_message_template(message: str, template: str) -> None:
    assert log_message_template(message) == template


@pytest.mark.parametrize(
    ("text", "digest"),
    [
        ("", "811c9dc5"),
        ("a", "e40c292c"),
        ("foobar", "bf9cf968"),
        ("oops", "0bf0b26e"),
        ("_NOMSG", "a9b1099a"),
        ("boom", "c79493aa"),
    ],
)
def test_fnv1a32_hex(text: str, digest: str) -> None:
    assert fnv1a32_hex(text) == digest


@pytest.mark.parametrize(
    ("raw", "expected"),
    [("LOG", "LOG"), ("my prefix", "MY_PREFIX"), ("q" * 40, "Q" * 32), ("!!!", "LOG"), ("", "LOG")],
)
def test_log_code_prefix_normalisation(raw: str, expected: str) -> None:
    assert log_code_prefix(raw) == expected


def test_log_fault_code_node_part_is_cut_to_fit_a_long_prefix() -> None:
    prefix = "Q" * 32
    code = log_fault_code(prefix, "/" + "n" * 100, "boom")
    assert code == prefix + "_" + "N" * 22 + "_c79493aa"
    assert len(code) == 64


def test_log_fault_code_without_node_part() -> None:
    assert log_fault_code("LOG", "/", "boom") == "LOG_c79493aa"


def test_truncate_code_strips_a_dangling_separator() -> None:
    assert truncate_code("AB_CD", 3) == "AB"
    assert truncate_code("ABC", 3) == "ABC"
