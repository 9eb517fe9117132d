"""Builds the bundled sample recordings (a Nav2 mission, recorded fault-manager service calls).

The mission is also written as a ROS 1 bag: the same traffic in ROS 1 types, topics and codes.

Deterministic: fixed start time and seeds, no wall clock; every run writes the same messages.
"""

from __future__ import annotations

import argparse
import random
import shutil
import sys
import tempfile
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import Writer
from rosbags.rosbag2.enums import StoragePlugin
from rosbags.typesys import Stores, get_typestore

from medkit_replay.msgdefs import base_typestore

if TYPE_CHECKING:
    from collections.abc import Iterable, Sequence

    from rosbags.interfaces import Connection

TS = base_typestore()
HERE = Path(__file__).resolve().parent
NS = 1_000_000_000
MS = 1_000_000
T0_NS = 1_773_480_413 * NS
"""Bag time zero of every sample: 2026-03-14 09:26:53 UTC."""

NAV2_MCAP = "nav2_mission_mcap"
NAV2_SQLITE3 = "nav2_mission_sqlite3"
NAV2_ROS1 = "nav2_mission_ros1.bag"
SERVICE_CALLS = "service_calls.mcap"

DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"
GOAL_STATUS_ARRAY = "action_msgs/msg/GoalStatusArray"
LOG = "rcl_interfaces/msg/Log"
FAULT_EVENT = "ros2_medkit_msgs/msg/FaultEvent"

OK, WARN, ERROR = 0, 1, 2
ACCEPTED, EXECUTING, CANCELING, SUCCEEDED, CANCELED, ABORTED = 1, 2, 3, 4, 5, 6
INFO, LOG_WARN, LOG_ERROR, FATAL = 20, 30, 40, 50
FAILED, PASSED = 0, 1
REQUEST_SENT, REQUEST_RECEIVED, RESPONSE_SENT = 0, 1, 2


@dataclass(frozen=True, slots=True)
class Rec:
    """One message to write: topic, type, log time (ns), message object."""

    topic: str
    msgtype: str
    t_ns: int
    msg: object


def new(msgtype: str, /, **fields: Any) -> object:
    """A message of a type of the bundled typestore."""
    return TS.types[msgtype](**fields)


def stamp(t_ns: int) -> object:
    """builtin_interfaces/msg/Time of a bag time."""
    return new("builtin_interfaces/msg/Time", sec=t_ns // NS, nanosec=t_ns % NS)


def at(seconds: float) -> int:
    """Bag time of an instant given in seconds after T0 (rounded to the microsecond)."""
    return T0_NS + round(seconds * 1_000_000) * 1000


# -- /diagnostics -------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Episode:
    """A stretch of time [start, end) (seconds after T0) during which a status is not its usual."""

    start: float
    end: float
    level: int
    message: str
    value: str  # of the status's one KeyValue


@dataclass(frozen=True, slots=True)
class Check:
    """One DiagnosticStatus a publisher reports every cycle."""

    name: str
    hardware_id: str
    ok_message: str
    key: str  # the one KeyValue the status carries
    ok_value: str
    episodes: tuple[Episode, ...] = ()

    def state(self, seconds: float) -> tuple[int, str, str]:
        """Level, message and value at an instant."""
        for episode in self.episodes:
            if episode.start <= seconds < episode.end:
                return episode.level, episode.message, episode.value
        return OK, self.ok_message, self.ok_value


@dataclass(frozen=True, slots=True)
class Publisher:
    """A node publishing one DiagnosticArray per period, ``phase`` seconds into each second."""

    node: str
    phase: float
    checks: tuple[Check, ...]
    period: float = 1.0


def _wifi_episodes() -> tuple[Episode, ...]:
    weak = "RSSI -78 dBm below -75 dBm"
    dead = "RSSI -86 dBm below -75 dBm, packet loss 12 %"
    # Sporadic single WARNs (never three within 10 s: the reporter's local filter holds them).
    sporadic = [Episode(s, s + 1.0, WARN, weak, "-78") for s in (11.5, 18.5, 30.5, 37.5, 43.5)]
    # A four-second dip: the third WARN within 10 s gets through and confirms the fault.
    dip = [Episode(63.5, 67.5, WARN, weak, "-79")]
    # Flapping every other second after it healed: each WARN is one step, never enough.
    flap = [
        Episode(s, s + 1.0, WARN, weak, "-78") for s in (104.5, 106.5, 108.5, 110.5, 112.5, 114.5)
    ]
    # The dead zone at the far end of the warehouse, until the end of the recording.
    return (*sporadic, *dip, *flap, Episode(131.5, 1e9, WARN, dead, "-86"))


PUBLISHERS = (
    Publisher(
        "motor_driver",
        0.05,
        (
            Check(
                "motor_left: Overheat",
                "roboclaw_0x80/left",
                "winding 61.2 C",
                "winding_temp_c",
                "61.2",
                (
                    Episode(74.5, 76.5, WARN, "winding 87.4 C, near the 90.0 C limit", "87.4"),
                    Episode(76.5, 88.5, ERROR, "winding 96.5 C above the 90.0 C limit", "96.5"),
                    Episode(88.5, 95.5, WARN, "winding 88.1 C, cooling down", "88.1"),
                ),
            ),
            Check(
                "motor_right: Overheat",
                "roboclaw_0x80/right",
                "winding 58.7 C",
                "winding_temp_c",
                "58.7",
            ),
            Check(
                "motor_left: Comm Link",
                "roboclaw_0x80/left",
                "CAN heartbeat 100 Hz",
                "heartbeat_hz",
                "100.0",
                (
                    Episode(
                        78.5, 84.5, ERROR, "no CAN heartbeat from the left motor controller", "0.0"
                    ),
                ),
            ),
            Check(
                "motor_right: Comm Link",
                "roboclaw_0x80/right",
                "CAN heartbeat 100 Hz",
                "heartbeat_hz",
                "100.0",
            ),
        ),
    ),
    Publisher(
        "sensor_monitor",
        0.30,
        (
            Check(
                "lidar: Scan Rate",
                "rplidar_s2",
                "10.0 Hz",
                "rate_hz",
                "10.0",
                (Episode(113.9, 114.9, ERROR, "no scan for 1.2 s (USB hub reset)", "0.0"),),
            ),
            Check(
                "camera: Frame Rate",
                "realsense_d435",
                "30.0 Hz",
                "rate_hz",
                "30.0",
                (Episode(113.9, 115.9, ERROR, "no frame for 1.4 s (USB hub reset)", "0.0"),),
            ),
            Check(
                "imu: Data Rate",
                "bno085",
                "200.0 Hz",
                "rate_hz",
                "200.0",
                (Episode(113.9, 114.9, ERROR, "no sample for 1.1 s (USB hub reset)", "0.0"),),
            ),
        ),
    ),
    Publisher(
        "nav_monitor",
        0.55,
        (
            Check(
                "localization: Pose Confidence",
                "amcl",
                "pose covariance 0.08 m^2",
                "covariance_m2",
                "0.08",
                (
                    Episode(
                        23.5,
                        29.5,
                        ERROR,
                        "pose covariance 2.41 m^2 above 0.50 m^2, diverged",
                        "2.41",
                    ),
                ),
            ),
            Check(
                "wheel_odometry: Slip",
                "base_controller",
                "slip 2 %",
                "slip_pct",
                "2",
                (Episode(79.0, 81.0, ERROR, "left wheel slip 34 %, commanded 0.42 m/s", "34"),),
            ),
        ),
    ),
    Publisher(
        "system_monitor",
        0.80,
        (
            Check(
                "wifi: Signal Strength",
                "wlan0",
                "RSSI -58 dBm",
                "rssi_dbm",
                "-58",
                _wifi_episodes(),
            ),
            Check("battery: Charge", "bms", "charge 84 %", "charge_pct", "84"),
        ),
    ),
)


def diagnostics(end: float, rng: random.Random) -> list[Rec]:
    """Every publisher's arrays from T0 to ``end`` seconds, with a few ms of delivery jitter."""
    out: list[Rec] = []
    for publisher in PUBLISHERS:
        cycle = 0
        while (seconds := publisher.phase + cycle * publisher.period) < end:
            t_ns = at(seconds) + rng.randrange(-3 * MS, 3 * MS)
            statuses = []
            for check in publisher.checks:
                level, message, value = check.state(seconds)
                statuses.append(
                    new(
                        "diagnostic_msgs/msg/DiagnosticStatus",
                        level=level,
                        name=check.name,
                        message=message,
                        hardware_id=check.hardware_id,
                        values=[new("diagnostic_msgs/msg/KeyValue", key=check.key, value=value)],
                    )
                )
            header = new(
                "std_msgs/msg/Header", stamp=stamp(t_ns - rng.randrange(MS, 2 * MS)), frame_id=""
            )
            out.append(
                Rec(
                    "/diagnostics",
                    DIAGNOSTIC_ARRAY,
                    t_ns,
                    new(DIAGNOSTIC_ARRAY, header=header, status=statuses),
                )
            )
            cycle += 1
    return out


# -- action status ------------------------------------------------------------------------------

RESULT_TIMEOUT_S = 10.0
"""How long the sample's action servers keep a finished goal in their status array."""


@dataclass(slots=True)
class Goal:
    """One goal of an action server: id, acceptance time and its status changes."""

    uuid: bytes
    accepted: float
    changes: list[tuple[float, int]] = field(default_factory=list)

    def status_at(self, seconds: float) -> int | None:
        """The goal's status at an instant; None before acceptance or once the server forgot it."""
        if seconds < self.accepted:
            return None
        status = ACCEPTED
        for when, value in self.changes:
            if when <= seconds:
                status = value
        terminal = [when for when, value in self.changes if value >= SUCCEEDED]
        if terminal and seconds > terminal[0] + RESULT_TIMEOUT_S:
            return None
        return status


def goal_arrays(topic: str, goals: Sequence[Goal]) -> list[Rec]:
    """The status array an action server publishes at each change of one of its goals."""
    instants = sorted({g.accepted for g in goals} | {w for g in goals for w, _ in g.changes})
    out = []
    for seconds in instants:
        listed = []
        for goal in goals:
            status = goal.status_at(seconds)
            if status is None:
                continue
            info = new(
                "action_msgs/msg/GoalInfo",
                goal_id=new(
                    "unique_identifier_msgs/msg/UUID", uuid=np.frombuffer(goal.uuid, np.uint8)
                ),
                stamp=stamp(at(goal.accepted)),
            )
            listed.append(new("action_msgs/msg/GoalStatus", goal_info=info, status=status))
        msg = new(GOAL_STATUS_ARRAY, status_list=listed)
        out.append(Rec(topic, GOAL_STATUS_ARRAY, at(seconds) + 400_000, msg))
    return out


def actions(rng: random.Random) -> list[Rec]:
    """bt_navigator's /navigate_to_pose and controller_server's /follow_path goals."""

    def goal(accepted: float, *changes: tuple[float, int]) -> Goal:
        return Goal(rng.randbytes(16), accepted, [(accepted + 0.01, EXECUTING), *changes])

    navigate = [
        goal(2.0, (52.6, SUCCEEDED)),
        goal(58.0, (81.21, ABORTED)),  # the motor overheat stops the robot
        goal(122.0, (146.5, SUCCEEDED)),  # recovered: the last leg makes it
    ]
    follow = [
        goal(3.1, (26.4, ABORTED)),  # "Failed to make progress" while localization diverged
        goal(31.2, (52.45, SUCCEEDED)),
        goal(59.1, (81.15, CANCELING), (81.18, CANCELED)),  # halted by the navigator
        goal(123.1, (146.35, SUCCEEDED)),
    ]
    return goal_arrays("/navigate_to_pose/_action/status", navigate) + goal_arrays(
        "/follow_path/_action/status", follow
    )


# -- /rosout ------------------------------------------------------------------------------------

ROSOUT_LINES: tuple[tuple[float, int, str, str], ...] = (
    (
        2.003,
        INFO,
        "bt_navigator",
        "Begin navigating from current location (0.00, 0.00) to (14.20, 3.50)",
    ),
    (3.105, INFO, "controller_server", "Received a goal, begin computing control effort."),
    (23.61, LOG_WARN, "amcl", "Particle filter covariance above 0.5 m^2, localization unreliable"),
    (24.61, LOG_WARN, "amcl", "Particle filter covariance above 0.5 m^2, localization unreliable"),
    (25.61, LOG_WARN, "amcl", "Particle filter covariance above 0.5 m^2, localization unreliable"),
    (26.39, LOG_ERROR, "controller_server", "Failed to make progress"),
    (26.40, LOG_WARN, "controller_server", "[follow_path] [ActionServer] Aborting handle."),
    (26.61, LOG_WARN, "amcl", "Particle filter covariance above 0.5 m^2, localization unreliable"),
    (27.02, INFO, "behavior_server", "Running spin"),
    (28.90, LOG_ERROR, "controller_server", "Failed to make progress"),
    (31.205, INFO, "controller_server", "Received a goal, begin computing control effort."),
    (52.44, INFO, "controller_server", "Reached the goal!"),
    (52.61, INFO, "bt_navigator", "Goal succeeded"),
    (
        58.003,
        INFO,
        "bt_navigator",
        "Begin navigating from current location (14.20, 3.50) to (2.80, 21.00)",
    ),
    (59.105, INFO, "controller_server", "Received a goal, begin computing control effort."),
    (78.42, FATAL, "motor_driver", "Left motor driver entered thermal shutdown at 96.5 C"),
    (78.91, LOG_ERROR, "motor_driver", "Lost CAN heartbeat from left motor controller (node 0x11)"),
    (81.16, INFO, "controller_server", "Goal was canceled. Stopping the robot."),
    (81.22, LOG_ERROR, "bt_navigator", "Goal failed"),
    (96.20, INFO, "motor_driver", "Left motor driver back in operation, winding 87.9 C"),
    (114.31, LOG_WARN, "sensor_monitor", "USB hub reset detected on bus 2"),
    (
        122.003,
        INFO,
        "bt_navigator",
        "Begin navigating from current location (9.10, 12.70) to (0.00, 0.00)",
    ),
    (123.105, INFO, "controller_server", "Received a goal, begin computing control effort."),
    (146.34, INFO, "controller_server", "Reached the goal!"),
    (146.51, INFO, "bt_navigator", "Goal succeeded"),
)
_SOURCE_FILES = {
    "amcl": ("./src/amcl_node.cpp", "laserReceived"),
    "behavior_server": ("./include/nav2_behaviors/timed_behavior.hpp", "execute"),
    "bt_navigator": ("./src/navigators/navigate_to_pose.cpp", "goalCompleted"),
    "controller_server": ("./src/controller_server.cpp", "computeControl"),
    "motor_driver": ("./src/roboclaw_driver.cpp", "poll"),
    "sensor_monitor": ("./src/usb_watchdog.cpp", "check"),
}


def rosout(rng: random.Random) -> list[Rec]:
    """The log lines the nodes of the stack printed (INFO lines included, as a robot's /rosout)."""
    out = []
    for seconds, level, name, text in ROSOUT_LINES:
        t_ns = at(seconds)
        file, function = _SOURCE_FILES[name]
        msg = new(
            LOG,
            stamp=stamp(t_ns - rng.randrange(200_000, 900_000)),
            level=level,
            name=name,
            msg=text,
            file=file,
            function=function,
            line=rng.randrange(80, 900),
        )
        out.append(Rec("/rosout", LOG, t_ns, msg))
    return out


MISSION_END_S = 151.0


def nav2_mission() -> list[Rec]:
    """The whole mission, in log-time order (ties keep the order built)."""
    records = diagnostics(MISSION_END_S, random.Random(2026))
    records += actions(random.Random(7))
    records += rosout(random.Random(11))
    return sorted(records, key=lambda rec: rec.t_ns)


# -- recorded service calls and the live manager's FaultEvents ----------------------------------


@dataclass(slots=True)
class FaultState:
    """What the recorded manager held for one fault, as its FaultEvents carry it."""

    code: str
    severity: int
    description: str
    first_ns: int
    last_ns: int
    sources: tuple[str, ...]
    passed_ns: int = 0
    occurrences: int = 1
    status: str = "CONFIRMED"

    def message(self) -> object:
        """ros2_medkit_msgs/msg/Fault."""
        return new(
            "ros2_medkit_msgs/msg/Fault",
            fault_code=self.code,
            severity=self.severity,
            description=self.description,
            first_occurred=stamp(self.first_ns),
            last_occurred=stamp(self.last_ns),
            last_passed=stamp(self.passed_ns),
            occurrence_count=self.occurrences,
            status=self.status,
            reporting_sources=list(self.sources),
        )


Published = tuple[str, object, tuple[str, ...]]
"""A FaultEvent: event_type, the Fault message (state after the event), auto_cleared_codes."""


class ServiceRecorder:
    """Writes each call as rosbag2 service introspection (CONTENTS mode) records it.

    Three copies per call: the client's REQUEST_SENT, the server's REQUEST_RECEIVED and
    RESPONSE_SENT (the client's RESPONSE_RECEIVED copy is not recorded); the FaultEvents the
    manager published while handling the call come between the last two.
    """

    SERVER_DELAY_NS = 180_000  # client send → server receive
    PUBLISH_DELAY_NS = 240_000  # server receive → FaultEvent published
    REPLY_DELAY_NS = 90_000  # FaultEvent → response sent

    def __init__(self) -> None:
        self.records: list[Rec] = []
        self._sequence: dict[bytes, int] = {}

    @classmethod
    def handled_at(cls, seconds: float) -> int:
        """Bag time at which the manager handles a call its client sent at ``seconds``."""
        return at(seconds) + cls.SERVER_DELAY_NS

    def report(
        self,
        seconds: float,
        client_gid: bytes,
        request: tuple[str, int, int, str, str],
        *events: Published,
        accepted: bool = True,
    ) -> None:
        """A ReportFault call: (fault_code, event_type, severity, description, source_id)."""
        code, event_type, severity, description, source_id = request
        fields: dict[str, object] = {
            "fault_code": code,
            "event_type": event_type,
            "severity": severity,
            "description": description,
            "source_id": source_id,
        }
        self._call(seconds, client_gid, "ReportFault", fields, {"accepted": accepted}, events)

    def clear(
        self,
        seconds: float,
        client_gid: bytes,
        code: str,
        *events: Published,
        success: bool,
        message: str,
    ) -> None:
        """A ClearFault call (correlation auto-clear not skipped) and the manager's answer."""
        cleared = list(events[0][2]) if events else []
        response = {"success": success, "message": message, "auto_cleared_codes": cleared}
        request = {"fault_code": code, "skip_correlation_auto_clear": False}
        self._call(seconds, client_gid, "ClearFault", request, response, events)

    def _call(
        self,
        seconds: float,
        client_gid: bytes,
        srv: str,
        request: dict[str, object],
        response: dict[str, object],
        events: Sequence[Published],
    ) -> None:
        sequence = self._sequence.get(client_gid, 0) + 1
        self._sequence[client_gid] = sequence
        service = "report_fault" if srv == "ReportFault" else "clear_fault"
        topic = f"/fault_manager/{service}/_service_event"
        event_type = f"ros2_medkit_msgs/srv/{srv}_Event"
        sent = at(seconds)
        received = sent + self.SERVER_DELAY_NS
        published = received + self.PUBLISH_DELAY_NS
        replied = published + self.REPLY_DELAY_NS

        def copy(t_ns: int, which: int, req: list[object], resp: list[object]) -> Rec:
            info = new(
                "service_msgs/msg/ServiceEventInfo",
                event_type=which,
                stamp=stamp(t_ns - 40_000),
                client_gid=np.frombuffer(client_gid, np.uint8),
                sequence_number=sequence,
            )
            msg = new(event_type, info=info, request=req, response=resp)
            return Rec(topic, event_type, t_ns, msg)

        req = new(f"ros2_medkit_msgs/srv/{srv}_Request", **request)
        resp = new(f"ros2_medkit_msgs/srv/{srv}_Response", **response)
        self.records.append(copy(sent, REQUEST_SENT, [req], []))
        self.records.append(copy(received, REQUEST_RECEIVED, [req], []))
        for index, (kind, fault, cleared) in enumerate(events):
            t_ns = published + index * 20_000
            event = new(
                FAULT_EVENT,
                event_type=kind,
                fault=fault,
                timestamp=stamp(t_ns - 30_000),
                auto_cleared_codes=list(cleared),
            )
            self.records.append(Rec("/fault_manager/events", FAULT_EVENT, t_ns, event))
        self.records.append(copy(replied, RESPONSE_SENT, [], [resp]))


def service_calls() -> list[Rec]:
    """Fault-manager traffic of a short run, as a manager configured with rules/nav2 handled it.

    The FaultEvents are written out by hand from upstream's rules (confirmation_threshold -1,
    healing on with threshold 3, the motor_overheat_cascade correlation rule), not computed by
    the replay, so the parity check compares two independent accounts.
    """
    rng = random.Random(5)
    motor, odometry, bms, legacy, operator = (rng.randbytes(16) for _ in range(5))
    rec = ServiceRecorder()
    t = rec.handled_at
    left = "/powertrain/motor_left"

    def event(kind: str, state: FaultState, cleared: tuple[str, ...] = ()) -> Published:
        return (kind, state.message(), cleared)

    hot = "left motor winding 96.5 C"
    overheat = FaultState("MOTOR_OVERHEAT", 2, hot, t(1.0), t(1.0), (left,))
    # The root cause confirms at once (threshold -1) and opens a 5 s correlation window.
    rec.report(
        1.0, motor, ("MOTOR_OVERHEAT", FAILED, 2, hot, left), event("fault_confirmed", overheat)
    )
    # Two symptoms inside the window: confirmed, but muted, so the manager publishes nothing.
    no_heartbeat = "no CAN heartbeat from the left motor controller"
    rec.report(1.8, motor, ("MOTOR_LEFT_COMM_TIMEOUT", FAILED, 2, no_heartbeat, left))
    rec.report(
        2.5, odometry, ("WHEEL_SLIP_DETECTED", FAILED, 1, "left wheel slip 34 %", "/odometry")
    )
    # An unrelated fault.
    low = "charge 18 % below 20 %"
    battery = FaultState("BATTERY_LOW", 1, low, t(4.0), t(4.0), ("/power/bms",))
    rec.report(
        4.0, bms, ("BATTERY_LOW", FAILED, 1, low, "/power/bms"), event("fault_confirmed", battery)
    )
    # A request the manager rejects (a space in the code): accepted false, nothing published.
    rec.report(5.0, legacy, ("motor temp", FAILED, 2, "", "/legacy_monitor"), accepted=False)
    # One PASSED on a confirmed fault: counter -1 -> 0, still CONFIRMED, an update is published.
    overheat.passed_ns = t(6.0)
    rec.report(
        6.0, motor, ("MOTOR_OVERHEAT", PASSED, 0, "", left), event("fault_updated", overheat)
    )
    # The operator clears the root cause; its rule clears the symptoms it collected with it.
    overheat.status = "CLEARED"
    symptoms = ("MOTOR_LEFT_COMM_TIMEOUT", "WHEEL_SLIP_DETECTED")
    rec.clear(
        8.0,
        operator,
        "MOTOR_OVERHEAT",
        event("fault_cleared", overheat, symptoms),
        success=True,
        message="Fault cleared: MOTOR_OVERHEAT (auto-cleared 2 symptoms)",
    )
    # The battery recovers: three updates (counter 0, 1, 2), then HEALED at 3.
    for seconds in (9.0, 9.5, 10.0, 10.5):
        battery.passed_ns = t(seconds)
        kind = "fault_updated"
        if seconds == 10.5:
            battery.status, kind = "HEALED", "fault_cleared"
        rec.report(seconds, bms, ("BATTERY_LOW", PASSED, 0, "", "/power/bms"), event(kind, battery))
    # Clearing a code the manager never saw: success false, nothing published.
    rec.clear(
        11.0, operator, "LIDAR_TIMEOUT", success=False, message="Fault not found: LIDAR_TIMEOUT"
    )
    # The overheat comes back: a new occurrence of the cleared fault, and a new window, in which
    # the comm symptom (cleared with it) comes back muted.
    hotter = "left motor winding 97.0 C"
    overheat.status, overheat.occurrences = "CONFIRMED", 2
    overheat.first_ns = overheat.last_ns = t(12.0)
    overheat.description = hotter
    rec.report(
        12.0, motor, ("MOTOR_OVERHEAT", FAILED, 2, hotter, left), event("fault_confirmed", overheat)
    )
    rec.report(12.6, motor, ("MOTOR_LEFT_COMM_TIMEOUT", FAILED, 2, no_heartbeat, left))
    return sorted(rec.records, key=lambda r: r.t_ns)


# -- the mission as a ROS 1 bag ------------------------------------------------------------------

TS1 = get_typestore(Stores.ROS1_NOETIC)
ROS1_STATUS = {ACCEPTED: 0, EXECUTING: 1, CANCELING: 6, SUCCEEDED: 3, CANCELED: 2, ABORTED: 4}
"""action_msgs GoalStatus codes to the actionlib ones a ROS 1 server publishes for the same goal:
ACCEPTED is PENDING, EXECUTING ACTIVE, CANCELING PREEMPTING, CANCELED (once executing)
PREEMPTED."""
ROS1_LEVEL = {INFO: 2, LOG_WARN: 4, LOG_ERROR: 8, FATAL: 16}
"""rcl_interfaces/msg/Log levels to rosgraph_msgs/Log ones."""
DIAGNOSTIC_PUBLISHERS = {p.checks[0].name: f"/{p.node}" for p in PUBLISHERS}


@dataclass(frozen=True, slots=True)
class Rec1:
    """One ROS 1 message to write: topic, ROS 1 type, log time (ns), message, publishing node."""

    topic: str
    msgtype: str
    t_ns: int
    msg: object
    callerid: str


def new1(msgtype: str, /, **fields: Any) -> object:
    """A message of a ROS 1 Noetic type."""
    return TS1.types[msgtype](**fields)


def stamp1(stamp: Any) -> object:
    """ROS 1 time of a builtin_interfaces/msg/Time."""
    return new1("builtin_interfaces/msg/Time", sec=stamp.sec, nanosec=stamp.nanosec)


def header1(seq: int, stamp: Any, frame_id: str = "") -> object:
    """std_msgs/Header with its ROS 1 sequence number."""
    return new1("std_msgs/msg/Header", seq=seq, stamp=stamp1(stamp), frame_id=frame_id)


def ros1_mission() -> list[Rec1]:
    """The Nav2 mission as a ROS 1 robot records it, message for message.

    DiagnosticArrays get a header ``seq`` per publisher; each action's ``<action>/status``
    carries actionlib codes and string goal ids; /rosout lines carry ROS 1 levels and node names
    (``/amcl``), and the rosout node republishes each on /rosout_agg, as on a ROS 1 robot.
    """
    out: list[Rec1] = []
    seqs: dict[str, int] = {}
    goal_ids: dict[bytes, str] = {}

    def seq(key: str) -> int:
        seqs[key] = seqs.get(key, 0) + 1
        return seqs[key]

    for rec in nav2_mission():
        msg: Any = rec.msg
        if rec.msgtype == DIAGNOSTIC_ARRAY:
            node = DIAGNOSTIC_PUBLISHERS[msg.status[0].name]
            statuses = [
                new1(
                    "diagnostic_msgs/msg/DiagnosticStatus",
                    level=s.level,
                    name=s.name,
                    message=s.message,
                    hardware_id=s.hardware_id,
                    values=[
                        new1("diagnostic_msgs/msg/KeyValue", key=kv.key, value=kv.value)
                        for kv in s.values
                    ],
                )
                for s in msg.status
            ]
            array = new1(
                "diagnostic_msgs/msg/DiagnosticArray",
                header=header1(seq(node), msg.header.stamp),
                status=statuses,
            )
            out.append(
                Rec1("/diagnostics", "diagnostic_msgs/msg/DiagnosticArray", rec.t_ns, array, node)
            )
        elif rec.msgtype == GOAL_STATUS_ARRAY:
            action = rec.topic.removesuffix("/_action/status")
            server = "/bt_navigator" if action == "/navigate_to_pose" else "/controller_server"
            goals = []
            for goal in msg.status_list:
                key = bytes(goal.goal_info.goal_id.uuid)
                sent = goal.goal_info.stamp
                name = goal_ids.setdefault(
                    key, f"{server}-{len(goal_ids) + 1}-{sent.sec}.{sent.nanosec:09d}"
                )
                goal_id = new1("actionlib_msgs/msg/GoalID", stamp=stamp1(sent), id=name)
                goals.append(
                    new1(
                        "actionlib_msgs/msg/GoalStatus",
                        goal_id=goal_id,
                        status=ROS1_STATUS[goal.status],
                        text="",
                    )
                )
            now = stamp(rec.t_ns)
            array = new1(
                "actionlib_msgs/msg/GoalStatusArray",
                header=header1(seq(action), now),
                status_list=goals,
            )
            out.append(
                Rec1(
                    f"{action}/status",
                    "actionlib_msgs/msg/GoalStatusArray",
                    rec.t_ns,
                    array,
                    server,
                )
            )
        elif rec.msgtype == LOG:
            node = f"/{msg.name}"
            line = new1(
                "rosgraph_msgs/msg/Log",
                header=header1(seq(node), msg.stamp),
                level=ROS1_LEVEL[msg.level],
                name=node,
                msg=msg.msg,
                file=msg.file,
                function=msg.function,
                line=msg.line,
                topics=["/rosout", "/diagnostics"],
            )
            out.append(Rec1("/rosout", "rosgraph_msgs/msg/Log", rec.t_ns, line, node))
            out.append(
                Rec1("/rosout_agg", "rosgraph_msgs/msg/Log", rec.t_ns + 300_000, line, "/rosout")
            )
    return sorted(out, key=lambda r: r.t_ns)


def write_bag1(path: Path, records: Iterable[Rec1]) -> Path:
    """Write records as a ROS 1 bag with LZ4-compressed 16 KiB chunks, replacing ``path``."""
    path.unlink(missing_ok=True)
    writer = Writer1(path)
    writer.set_compression(Writer1.CompressionFormat.LZ4)
    writer.chunk_threshold = 16 * 1024
    connections: dict[tuple[str, str], Any] = {}
    with writer:
        for rec in records:
            key = (rec.topic, rec.callerid)
            if key not in connections:
                connections[key] = writer.add_connection(
                    rec.topic, rec.msgtype, typestore=TS1, callerid=rec.callerid
                )
            writer.write(
                connections[key], rec.t_ns, bytes(TS1.serialize_ros1(rec.msg, rec.msgtype))
            )
    return path


# -- writing ------------------------------------------------------------------------------------


def _interfaces_dir() -> Path:
    root = resources.files("medkit_replay.inputs").joinpath("interfaces")
    return Path(str(root)) / "ros2_medkit_msgs"


def definition(msgtype: str) -> str:
    """The message definition rosbag2 stores for a topic's type (a service event: the .srv)."""
    if "/srv/" in msgtype:
        name = msgtype.rsplit("/", 1)[-1].removesuffix("_Event")
        return (_interfaces_dir() / "srv" / f"{name}.srv").read_text(encoding="utf-8")
    return TS.generate_msgdef(msgtype, ros_version=2)[0]


def write_bag(path: Path, records: Iterable[Rec], storage: StoragePlugin) -> Path:
    """Write records as a rosbag2 directory, replacing what is at ``path``."""
    if path.exists():
        shutil.rmtree(path)
    writer = Writer(path, version=9, storage_plugin=storage)
    connections: dict[tuple[str, str], Connection] = {}
    with writer:
        for rec in records:
            key = (rec.topic, rec.msgtype)
            if key not in connections:
                connections[key] = writer.add_connection(
                    rec.topic,
                    rec.msgtype,
                    msgdef=definition(rec.msgtype),
                    rihs01=TS.hash_rihs01(rec.msgtype),
                )
            writer.write(connections[key], rec.t_ns, bytes(TS.serialize_cdr(rec.msg, rec.msgtype)))
    return path


def write_bare_mcap(path: Path, records: Iterable[Rec]) -> Path:
    """Write records as a single ``.mcap`` file, as the medkit gateway serves a recording."""
    with tempfile.TemporaryDirectory() as tmp:
        bag = write_bag(Path(tmp) / "bag", records, StoragePlugin.MCAP)
        storage = next(p for p in bag.iterdir() if p.suffix == ".mcap")
        shutil.copyfile(storage, path)
    return path


def build(out: Path) -> list[Path]:
    """Write every sample into ``out``; returns the paths written."""
    out.mkdir(parents=True, exist_ok=True)
    mission = nav2_mission()
    return [
        write_bag(out / NAV2_MCAP, mission, StoragePlugin.MCAP),
        write_bag(out / NAV2_SQLITE3, mission, StoragePlugin.SQLITE3),
        write_bare_mcap(out / SERVICE_CALLS, service_calls()),
        write_bag1(out / NAV2_ROS1, ros1_mission()),
    ]


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: ``python sample_bags/make_sample_bags.py [--out DIR]``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out", type=Path, default=HERE, help="output folder (default: beside this script)"
    )
    args = parser.parse_args(argv)
    for path in build(args.out):
        sys.stdout.write(f"wrote {path}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
