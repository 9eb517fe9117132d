"""A generated robot recording for the evidence tests: odometry, battery, TF, a camera, /rosout,
plus a JSON-lines script of ReportFault/ClearFault requests merged in as the same recording.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

if TYPE_CHECKING:
    from pathlib import Path

    from rosbags.interfaces import Connection

TS = get_typestore(Stores.ROS2_HUMBLE)
NS = 1_000_000_000
T0 = 1_700_000_000 * NS
CAMERA_BYTES = 320 * 240 * 3  # over the 64 KiB freeze-frame limit


def at(seconds: float) -> int:
    return T0 + round(seconds * 1_000_000) * 1000


def new(msgtype: str, /, **fields: Any) -> Any:
    return TS.types[msgtype](**fields)


def header(t_ns: int, frame: str) -> Any:
    stamp = new("builtin_interfaces/msg/Time", sec=t_ns // NS, nanosec=t_ns % NS)
    return new("std_msgs/msg/Header", stamp=stamp, frame_id=frame)


def odometry(t_ns: int, x: float) -> Any:
    point = new("geometry_msgs/msg/Point", x=x, y=0.5, z=0.0)
    orientation = new("geometry_msgs/msg/Quaternion", x=0.0, y=0.0, z=0.0, w=1.0)
    pose = new("geometry_msgs/msg/Pose", position=point, orientation=orientation)
    linear = new("geometry_msgs/msg/Vector3", x=0.25, y=0.0, z=0.0)
    angular = new("geometry_msgs/msg/Vector3", x=0.0, y=0.0, z=-0.1)
    return new(
        "nav_msgs/msg/Odometry",
        header=header(t_ns, "odom"),
        child_frame_id="base_link",
        pose=new(
            "geometry_msgs/msg/PoseWithCovariance",
            pose=pose,
            covariance=np.zeros(36, dtype=np.float64),
        ),
        twist=new(
            "geometry_msgs/msg/TwistWithCovariance",
            twist=new("geometry_msgs/msg/Twist", linear=linear, angular=angular),
            covariance=np.zeros(36, dtype=np.float64),
        ),
    )


def battery(t_ns: int, percentage: float) -> Any:
    return new(
        "sensor_msgs/msg/BatteryState",
        header=header(t_ns, "battery"),
        voltage=24.5,
        temperature=math.nan,
        current=-1.25,
        charge=math.nan,
        capacity=math.nan,
        design_capacity=20.0,
        percentage=percentage,
        power_supply_status=2,
        power_supply_health=1,
        power_supply_technology=3,
        present=True,
        cell_voltage=np.array([], dtype=np.float32),
        cell_temperature=np.array([], dtype=np.float32),
        location="base",
        serial_number="12345",
    )


def tf(t_ns: int) -> Any:
    translation = new("geometry_msgs/msg/Vector3", x=1.0, y=2.0, z=0.0)
    rotation = new("geometry_msgs/msg/Quaternion", x=0.0, y=0.0, z=0.0, w=1.0)
    transform = new(
        "geometry_msgs/msg/TransformStamped",
        header=header(t_ns, "map"),
        child_frame_id="odom",
        transform=new("geometry_msgs/msg/Transform", translation=translation, rotation=rotation),
    )
    return new("tf2_msgs/msg/TFMessage", transforms=[transform])


def image(t_ns: int) -> Any:
    return new(
        "sensor_msgs/msg/Image",
        header=header(t_ns, "camera"),
        height=240,
        width=320,
        encoding="rgb8",
        is_bigendian=0,
        step=960,
        data=np.zeros(CAMERA_BYTES, dtype=np.uint8),
    )


def log(t_ns: int, name: str, level: int, text: str) -> Any:
    return new(
        "rcl_interfaces/msg/Log",
        stamp=new("builtin_interfaces/msg/Time", sec=t_ns // NS, nanosec=t_ns % NS),
        level=level,
        name=name,
        msg=text,
        file="driver.cpp",
        function="tick",
        line=42,
    )


@dataclass(frozen=True)
class Robot:
    """Where the generated inputs are."""

    bag: Path
    script: Path
    graph: Path


def records(seconds: float = 30.0) -> list[tuple[str, str, int, Any]]:
    out: list[tuple[str, str, int, Any]] = []
    ticks = round(seconds * 20)
    for i in range(ticks):
        t = at(i / 20)
        out.append(("/odom", "nav_msgs/msg/Odometry", t, odometry(t, i / 20)))
        if i % 2 == 0:
            out.append(("/tf", "tf2_msgs/msg/TFMessage", t + 1000, tf(t + 1000)))
        if i % 4 == 1:
            out.append(("/camera/image_raw", "sensor_msgs/msg/Image", t, image(t)))
        if i % 20 == 3:
            pct = 0.9 - i / 20 / 100
            out.append(("/battery", "sensor_msgs/msg/BatteryState", t, battery(t, pct)))
    out.append(
        (
            "/rosout",
            "rcl_interfaces/msg/Log",
            at(15.02),
            log(at(15.02), "battery_monitor", 40, "cell undervoltage"),
        )
    )
    out.append(
        ("/rosout", "rcl_interfaces/msg/Log", at(5.0), log(at(5.0), "planner", 20, "goal accepted"))
    )
    out.sort(key=lambda r: r[2])
    return out


SCRIPT = [
    {
        "t_ns": at(10.0),
        "op": "report",
        "fault_code": "MOTOR_OVERCURRENT",
        "event_type": "FAILED",
        "severity": 2,
        "source_id": "/motor_driver",
    },
    {
        "t_ns": at(14.0),
        "op": "report",
        "fault_code": "MOTOR_OVERCURRENT",
        "event_type": "PASSED",
        "source_id": "/motor_driver",
    },
    {
        "t_ns": at(14.5),
        "op": "report",
        "fault_code": "MOTOR_OVERCURRENT",
        "event_type": "PASSED",
        "source_id": "/motor_driver",
    },
    # back inside the 60 s cooldown: the live manager captures nothing
    {
        "t_ns": at(20.0),
        "op": "report",
        "fault_code": "MOTOR_OVERCURRENT",
        "event_type": "FAILED",
        "severity": 2,
        "source_id": "/motor_driver",
    },
    {
        "t_ns": at(20.1),
        "op": "report",
        "fault_code": "MOTOR_OVERCURRENT",
        "event_type": "FAILED",
        "severity": 2,
        "source_id": "/motor_driver",
    },
    {"t_ns": at(22.0), "op": "clear", "fault_code": "MOTOR_OVERCURRENT"},
    # the clear reset the cooldown
    {
        "t_ns": at(25.0),
        "op": "report",
        "fault_code": "MOTOR_OVERCURRENT",
        "event_type": "FAILED",
        "severity": 2,
        "source_id": "/motor_driver",
    },
]

GRAPH = """\
/battery_monitor
  Subscribers:
    /parameter_events: rcl_interfaces/msg/ParameterEvent
  Publishers:
    /battery: sensor_msgs/msg/BatteryState
    /rosout: rcl_interfaces/msg/Log
  Service Servers:
    /battery_monitor/describe_parameters: rcl_interfaces/srv/DescribeParameters
/motor_driver
  Subscribers:
    /cmd_vel: geometry_msgs/msg/Twist
  Publishers:
    /odom: nav_msgs/msg/Odometry
    /rosout: rcl_interfaces/msg/Log
"""


def write_robot(
    root: Path,
    storage: StoragePlugin = StoragePlugin.MCAP,
    extra: list[tuple[str, str, int, Any]] | None = None,
) -> Robot:
    """Write the bag, the script and the node graph under ``root``."""
    bag = root / ("robot_mcap" if storage == StoragePlugin.MCAP else "robot_sqlite3")
    connections: dict[str, Connection] = {}
    with Writer(bag, version=9, storage_plugin=storage) as writer:
        for topic, msgtype, t_ns, msg in sorted(records() + (extra or []), key=lambda r: r[2]):
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=TS)
            writer.write(connections[topic], t_ns, bytes(TS.serialize_cdr(msg, msgtype)))
    script = root / "requests.jsonl"
    script.write_text("".join(json.dumps(line) + "\n" for line in SCRIPT))
    graph = root / "graph.txt"
    graph.write_text(GRAPH)
    return Robot(bag, script, graph)


CONFIG = """\
fault_manager:
  ros__parameters:
    healing_enabled: true
    healing_threshold: 1
    snapshots:
      config_file: snapshots.yaml
      rosbag:
        enabled: true
        topics: all
        format: {fmt}
log_bridge:
  ros__parameters: {{}}
"""

SNAPSHOTS = """\
fault_specific:
  MOTOR_OVERCURRENT: [/odom, /battery, /tf, /camera/image_raw, /not_recorded]
"""


def write_config(root: Path, fmt: str = "mcap", extra: str = "") -> Path:
    """The capture config (and its snapshot file) under ``root``."""
    (root / "snapshots.yaml").write_text(SNAPSHOTS)
    path = root / f"capture_{fmt}.yaml"
    path.write_text(CONFIG.format(fmt=fmt) + extra)
    return path
