"""--mcap at 0.6.0 beside 0.7.0 on the same replay: 0.6.0's ros2_medkit_msgs/Fault has no
``last_passed`` (added by cd8c19b0, #573), so the 0.6.0 file embeds and publishes that layout;
the JSON report keeps ``last_passed_ns`` at both (its schema does not change with the release).
"""

from __future__ import annotations

import json
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from medkit_replay.outputs.json_report import to_report
from medkit_replay.outputs.mcap_events import EVENTS_TOPIC, FAULT_EVENT_TYPE, schemas, write_mcap
from medkit_replay.pipeline import replay
from tests.outputs.test_mcap_events import correlated, ns, rosbags_messages

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.result import Result


def both(tmp_path: Path) -> dict[str, Result]:
    """The same replay as each release's Result (the engine's own differences left out)."""
    script, config = correlated(tmp_path)
    old = tmp_path / "release.yaml"
    old.write_text('medkit_replay:\n  ros__parameters:\n    upstream_release: "0.6.0"\n')
    assert replay([script], [config, old]).upstream_release == "0.6.0"
    new = replay([script], [config])
    return {"0.6.0": replace(new, upstream_release="0.6.0"), "0.7.0": new}


def fault_section(text: str) -> list[str]:
    """The field lines of the embedded ros2_medkit_msgs/Fault."""
    section = text.split("MSG: ros2_medkit_msgs/Fault\n")[1].split("=" * 80, maxsplit=1)[0]
    return [line for line in section.splitlines() if line and "=" not in line]


def test_the_060_file_embeds_and_publishes_060s_fault(tmp_path: Path) -> None:
    results = both(tmp_path)
    assert "last_passed" not in "\n".join(fault_section(schemas("0.6.0")[FAULT_EVENT_TYPE]))
    assert fault_section(schemas("")[FAULT_EVENT_TYPE]) == [
        *fault_section(schemas("0.6.0")[FAULT_EVENT_TYPE])[:5],
        "builtin_interfaces/Time last_passed",
        *fault_section(schemas("0.6.0")[FAULT_EVENT_TYPE])[5:],
    ]
    decoded: dict[str, list[tuple[int, Any]]] = {}
    for name, result in results.items():
        path = tmp_path / f"{name}.mcap"
        write_mcap(result, path)
        decoded[name] = rosbags_messages(path)[EVENTS_TOPIC]
    old, new = decoded["0.6.0"], decoded["0.7.0"]
    assert len(old) == len(new) > 0
    healed = [m.fault.last_passed for _, m in new if ns(m.fault.last_passed)]
    assert healed  # the fixture's LIDAR fault heals: 0.7.0 puts its PASSED time on the wire
    for (_, was), (_, now) in zip(old, new, strict=True):
        assert not hasattr(was.fault, "last_passed")
        assert (was.event_type, was.fault.fault_code, was.fault.occurrence_count) == (
            now.event_type,
            now.fault.fault_code,
            now.fault.occurrence_count,
        )


def test_the_json_report_keeps_last_passed_at_both(tmp_path: Path) -> None:
    for result in both(tmp_path).values():
        report: dict[str, Any] = json.loads(json.dumps(to_report(result)))
        assert all("last_passed_ns" in fault for fault in report["faults"])
        assert all("last_passed_ns" in event["fault"] for event in report["events"])
