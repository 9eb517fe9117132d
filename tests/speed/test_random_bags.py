"""Random recordings replayed, and by the plain oracle: the same conclusions.

The bags mix diagnostics, logs, action status, recorded service calls and FaultEvents with a
large unselected topic (so MCAP chunks are read through their message indexes), in MCAP or
sqlite3 storage, chunk-compressed or not.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from hypothesis import HealthCheck, given, settings, strategies as st

from tests.inputs.builders import (
    TS,
    Rec,
    clear_fault,
    diag,
    fault_event,
    goal_status,
    log,
    report_fault,
    stamp,
    write_bag,
)
from tests.speed.support import RULES, report_both_ways

if TYPE_CHECKING:
    from pathlib import Path

SEC = 1_000_000_000


def image(t_ns: int, size: int) -> Rec:
    """A large message on a topic the replay does not read (filler between the wanted ones)."""
    header: Any = TS.types["std_msgs/msg/Header"](stamp=stamp(t_ns), frame_id="camera")  # type: ignore[arg-type]
    msg = TS.types["sensor_msgs/msg/CompressedImage"](
        header=header, format="jpeg", data=np.zeros(size, dtype=np.uint8)
    )
    return Rec("/camera/compressed", "sensor_msgs/msg/CompressedImage", t_ns, msg)


def _record(kind: str, t_ns: int, pick: int) -> Rec:
    names = ("motor: Temp", "lidar: Rate", "wifi: Signal", "MOTOR_LEFT_OVERHEAT")
    if kind == "diag":
        return diag(t_ns, names[pick % 4], (0, 0, 1, 2, 3)[pick % 5], ("OK", "hot")[pick % 2])
    if kind == "log":
        return log(t_ns, (20, 30, 40, 50)[pick % 4], ("boom", "late 5")[pick % 2], "planner")
    if kind == "action":
        return goal_status(
            t_ns, (2, 4, 5, 6)[pick % 4], ("/a/_action/status", "/b/_action/status")[pick % 2]
        )
    if kind == "report":
        return report_fault(t_ns, ("MOTOR_HOT", "LIDAR_SCAN_RATE")[pick % 2], 1, sequence=pick)
    if kind == "clear":
        return clear_fault(t_ns, ("MOTOR_HOT", "WIFI_SIGNAL")[pick % 2], sequence=pick)
    if kind == "event":
        return fault_event(t_ns, ("MOTOR_HOT", "LIDAR_SCAN_RATE")[pick % 2])
    return image(t_ns, 20_000 + 1000 * (pick % 30))


kinds = st.sampled_from(
    ["diag"] * 6 + ["log"] * 3 + ["action", "image", "image", "report", "clear", "event"]
)
records = st.lists(
    st.tuples(kinds, st.integers(0, 3 * SEC // 10), st.integers(0, 1000)), min_size=1, max_size=80
)


def _bag(tmp_path: Path, steps: list[tuple[str, int, int]], storage: str, compression: str) -> Path:
    t_ns = 1_700_000_000 * SEC
    recs = []
    for kind, dt, pick in steps:
        t_ns += dt
        recs.append(_record(kind, t_ns, pick))
    return write_bag(
        tmp_path / f"bag_{storage}_{compression}_{len(list(tmp_path.iterdir()))}",
        recs,
        storage=storage,  # type: ignore[arg-type]
        compression=compression,  # type: ignore[arg-type]
        chunk_every=12,
    )


@settings(
    max_examples=25,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(
    steps=records,
    storage=st.sampled_from(["mcap", "mcap", "sqlite3"]),
    compression=st.sampled_from(["none", "none", "chunk"]),
    configs=st.sampled_from(["defaults", "nav2"]),
)
def test_random_bags_give_the_same_report_both_ways(
    tmp_path: Path, steps: list[tuple[str, int, int]], storage: str, compression: str, configs: str
) -> None:
    if storage == "sqlite3":
        compression = "none"
    bag = _bag(tmp_path, steps, storage, compression)
    chosen = [RULES / "fault_manager.yaml", RULES / "bridges.yaml"] if configs == "nav2" else []
    reference, fast = report_both_ways([bag], chosen)
    assert fast == reference
