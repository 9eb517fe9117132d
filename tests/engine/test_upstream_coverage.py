"""Every upstream scenario of fault-manager.md §4 is ported by a test here or listed as not ported.

IDs come from the upstream_support registry that the test_upstream_* modules fill on import.
"""

from __future__ import annotations

import importlib

from tests.engine.upstream_support import REGISTRY

MODULES = (
    "tests.engine.test_upstream_storage",
    "tests.engine.test_upstream_storage_healing",
    "tests.engine.test_upstream_sqlite",
    "tests.engine.test_upstream_node",
    "tests.engine.test_upstream_node_params",
    "tests.engine.test_upstream_integration",
    "tests.engine.test_upstream_near_miss",
    "tests.engine.test_upstream_entity_thresholds",
    "tests.engine.test_upstream_local_filter",
)


def _ids(prefix: str, first: int, last: int) -> tuple[str, ...]:
    return tuple(f"{prefix}-{n:02d}" for n in range(first, last + 1))


ALL_IDS: tuple[str, ...] = (
    *_ids("S", 1, 42),  # §4.1
    *_ids("N", 1, 12),  # §4.2
    "N-inferred",
    *_ids("E", 1, 15),  # §4.3
    *_ids("M", 1, 5),
    "SC-01",
    *_ids("A", 1, 10),
    *_ids("NM", 1, 28),  # §4.4
    *_ids("SQ", 1, 13),  # §4.5
    *_ids("R", 1, 8),  # §4.6
    *_ids("Y", 1, 4),
    "Y-inferred",
    *_ids("PE", 1, 6),
    *_ids("EI", 1, 6),
    *_ids("I", 1, 27),  # §4.7
    *_ids("RI", 2, 4),
    *_ids("LF", 1, 14),  # §4.8
    "LF-inferred",
    # §4.9 evidence storage scenarios (unnumbered upstream; one ID per bullet here)
    "EV-clear-retention",
    "EV-snapshot-cap",
    "EV-freeze-frame",
    "EV-getfault-readout",
    "EV-rosbag-rows",
)

_SNAPSHOTS = "snapshot/freeze-frame capture and storage are not modelled by medkit-replay"
NOT_PORTED: dict[str, str] = {
    "N-07": "capture pool parameters (capture_pool_size, capture_queue_depth, policy)",
    "N-12": "capture_queue_full_policy parsing (capture pool)",
    "A-05": "audit log file creation (audit log not modelled)",
    "A-09": "audit log fail-open infrastructure (poisoned sequence)",
    "A-10": "audit log fail-closed infrastructure (poisoned sequence)",
    "I-16": f"GetSnapshots on a nonexistent fault: {_SNAPSHOTS}",
    "I-17": f"GetSnapshots with an empty code: {_SNAPSHOTS}",
    "I-18": f"snapshot capture on confirmation: {_SNAPSHOTS}",
    "I-19": f"snapshot topic filter: {_SNAPSHOTS}",
    "I-20": f"snapshot pattern config: {_SNAPSHOTS}",
    "I-25": "ListFaults include_muted/include_clusters response shaping: the replay reports "
    "muted faults and clusters unconditionally",
    "EV-clear-retention": f"snapshot retention on clear and reclassification: {_SNAPSHOTS}",
    "EV-snapshot-cap": f"snapshots.max_per_fault eviction: {_SNAPSHOTS}",
    "EV-freeze-frame": f"freeze-frame storage and replacement: {_SNAPSHOTS}",
    "EV-getfault-readout": f"GetFault/GetSnapshots evidence readout: {_SNAPSHOTS}",
    "EV-rosbag-rows": "rosbag recording rows and storage caps: rosbag capture is not modelled",
}

PARTIALLY_PORTED: dict[str, str] = {
    "S-36": "reaching HEALED is ported; startup reclassification needs a persisted database",
    "N-01": "an empty manager is ported; node name and storage type are ROS plumbing",
    "E-10": "the unknown code is ported; the 'Fault not found' text belongs to GetFault",
    "E-11": "the fault is found; environment data (snapshots) is not modelled",
    "A-01": "events and the transitions behind the rows; the hash chain is not modelled",
    "A-02": "events and the transitions behind the rows; the hash chain is not modelled",
    "A-03": "events and the single CONFIRMED transition; the hash chain is not modelled",
    "A-04": "events and the transitions behind the rows; the hash chain is not modelled",
    "A-06": "timer confirmation without a FaultEvent; the audit row is not modelled",
    "A-07": "the HEALED seed; restart reclassification needs a persisted database",
    "A-08": "the HEALED seed; restart reclassification needs a persisted database",
    "SC-01": "statuses and events; the capture cooldown is not modelled",
    "SQ-01": "PASSED never inflates last_occurred; the reopen repair is SQLite-only",
    "SQ-12": "confirmed_at of a new confirmation; the column migration is SQLite-only",
    "SQ-13": "the healing walk; snapshots and reclassification are not modelled",
    "NM-13": "the first entry of a new series; the table migration is SQLite-only",
    "NM-14": "series survives HEALED and a clear; restart reclassification is not modelled",
    "NM-25": "new entries carry PREFAILED; the old-row column migration is SQLite-only",
    "I-27": "all storm faults accepted and confirmed; the capture queue is not modelled",
}


def _covered() -> dict[str, list[str]]:
    for module in MODULES:
        importlib.import_module(module)
    return REGISTRY


def test_ids_are_unique() -> None:
    assert len(set(ALL_IDS)) == len(ALL_IDS)


def test_every_scenario_is_ported_or_listed_as_not_ported() -> None:
    covered = _covered()
    missing = [sid for sid in ALL_IDS if sid not in covered and sid not in NOT_PORTED]
    assert missing == []


def test_no_scenario_is_both_ported_and_not_ported() -> None:
    covered = _covered()
    assert sorted(set(covered) & set(NOT_PORTED)) == []


def test_registered_ids_are_known() -> None:
    covered = _covered()
    known = set(ALL_IDS)
    assert sorted(set(covered) - known) == []
    assert sorted(set(NOT_PORTED) - known) == []
    assert sorted(set(PARTIALLY_PORTED) - set(covered)) == []


def test_every_registered_test_is_a_collected_test_function() -> None:
    covered = _covered()
    for names in covered.values():
        for name in names:
            module_name, _, function = name.rpartition(".")
            module = importlib.import_module(module_name)
            assert function.startswith("test_"), name
            assert callable(getattr(module, function)), name
