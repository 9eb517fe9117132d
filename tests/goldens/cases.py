"""The golden cases: every bundled recording and fixture under each bundled config.

A refactoring must leave every JSON report of these byte-identical (``record.py`` rewrites them).
"""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
GOLDENS = Path(__file__).with_name("reports.sha256.json")

RECORDINGS = [
    "sample_bags/nav2_mission_mcap",
    "sample_bags/nav2_mission_sqlite3",
    "sample_bags/service_calls.mcap",
    "sample_bags/nav2_mission_ros1.bag",
    "examples/nav2_mission.jsonl",
    *(
        f"tests/fixtures/rosbag2/{name}"
        for name in (
            "talker_mcap",
            "talker_sqlite3",
            "service_events_mcap",
            "service_events_sqlite3",
            "split_bag_mcap",
            "no_metadata_mcap",
            "old_type_names_mcap",
            "old_type_names_sqlite3",
            "cdr_test_mcap",
            "bare_files/only_services.mcap",
            "bare_files/only_topics.mcap",
            "bare_files/topics_and_services.db3",
            "bare_files/topics_and_services.mcap",
        )
    ),
]
CONFIGS = {
    "defaults": [],
    "nav2": ["rules/nav2/fault_manager.yaml", "rules/nav2/bridges.yaml"],
    "bringup": ["rules/bringup/fault_manager.yaml", "rules/nav2/bridges.yaml"],
}


def cases() -> list[tuple[str, list[str], list[str]]]:
    """(case id, inputs, configs), paths relative to the repository root."""
    found = [
        (f"{recording}@{name}", [recording], configs)
        for recording in RECORDINGS
        for name, configs in CONFIGS.items()
    ]
    merged = ["sample_bags/nav2_mission_mcap", "sample_bags/service_calls.mcap"]
    found.append(("merged@nav2", merged, CONFIGS["nav2"]))
    return found


def argv(inputs: list[str], configs: list[str], out: Path) -> list[str]:
    """The analyze command line of one case."""
    flags = [part for config in configs for part in ("--config", config)]
    return ["analyze", *inputs, *flags, "--json", str(out), "--quiet"]
