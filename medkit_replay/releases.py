"""The upstream ros2_medkit releases the replay models, and what each one does differently.

A Release is decided once, at configuration time, from ``medkit_replay.upstream_release``; every
rule that differs between releases reads one of its fields (never the release's name).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["DEFAULT_RELEASE", "RELEASES", "Release", "default_release", "release_named"]


@dataclass(frozen=True, slots=True, kw_only=True)
class Release:
    """One upstream release: its name, the commit modelled, and its behaviour switches.

    Attributes:
        name: the version users see (``ros2 pkg xml ros2_medkit_fault_manager``).
        commit: the upstream commit whose code the replay follows for this release.
        date: when that commit was made (the release date for a tagged release).
        max_fault_code_length: the longest ``fault_code`` the fault manager accepts
            (128 up to 505bc2d5; 256 from #591, in 0.7.0).
        clamp_counter: the debounce counter is kept within ``[confirmation, healing]``
            thresholds (49b2ec56, #484; the stored one per reporting band: b48c9052); without it
            it only saturates at the int32 bounds.
        latch_confirmed_healed: CONFIRMED and HEALED hold until the counter reaches the
            opposite threshold (49b2ec56, #484); without it the status follows the counter.
        backends_share_status_rule: the sqlite3 and in-memory storages decide a status the
            same way (6920ba42); without it ``storage_type`` matters: SQLite checks only
            confirmation on a FAILED and only healing on a PASSED.
        occurrences_on_edges: ``occurrence_count`` counts a fault's creation and each
            reactivation after a clear only (67bdb9cb); without it every FAILED counts.
        passed_sets_last_occurred: a PASSED moves ``last_occurred`` as well as ``last_passed``
            (true until d27fc3eb, #573).
        reactivation_resets_first_occurred: a FAILED that reactivates a CLEARED fault sets
            ``first_occurred`` again (67bdb9cb).
        heal_event: a fault that becomes HEALED publishes ``fault_cleared`` (d27fc3eb).
        sanitize_thresholds: ``confirmation_threshold >= 0`` becomes -1 and
            ``healing_threshold < 0`` becomes 3, globally, per entity and on every report
            (6920ba42, e9697424); without it 0 stays 0.
        near_misses: FAILED reports that leave a fault unconfirmed are kept as a near-miss
            series with ``near_miss.max_per_fault`` (aeb1e9d7, #629); 0.6.0 has neither.
    """

    name: str
    commit: str
    date: str
    max_fault_code_length: int
    # -- the fault manager's storage and status rules (engine) --
    clamp_counter: bool
    latch_confirmed_healed: bool
    backends_share_status_rule: bool
    occurrences_on_edges: bool
    passed_sets_last_occurred: bool
    reactivation_resets_first_occurred: bool
    heal_event: bool
    sanitize_thresholds: bool
    near_misses: bool
    # -- the bridges and the reporter (bridges, config) --
    diagnostic_keyvalue_codes: bool
    """The diagnostic bridge reads ``keyvalue_codes`` (a status's code from one of its
    KeyValues; 71b1a79e, #527). False: the parameter does not exist, codes come from names."""
    diagnostic_hardware_id_sources: bool
    """The diagnostic bridge reads ``use_hardware_id_as_source_id`` and ``max_tracked_sources``
    (one reporter per source; 56d85b83, #622). False: neither exists, every status reports
    as the bridge itself through one reporter."""
    bridge_ints_read_as_int64: bool
    """The log and action status bridges read ``severity_floor``, ``max_tracked_nodes``,
    ``aborted_severity`` and ``dedup_capacity`` as int64 and range-check them before narrowing
    (5ea42890, 26611619). False: narrowed to a 32-bit int first, so a large value wraps."""
    log_bridge_checks_coercions: bool
    """The log bridge replaces a negative or non-finite ``report_cooldown_sec`` by 5.0 and warns
    of it and of a clamped ``max_tracked_nodes`` (91035bfe). False: a negative cooldown becomes
    0.0 (off), both silently; a non-finite one reaches an undefined conversion."""
    action_bridge_defers_delivery: bool
    """The action status bridge keeps a verdict it cannot deliver pending and retries it every
    ``retry_period_sec`` (ab3a90f8, 243a2f4a). False: the verdict is acted on and committed at
    once, and the request is lost while the manager's service is not ready."""
    # -- messages, freeze frames and black-box recordings (evidence, outputs, parity) --
    msg_definitions: str
    """Where this release's ros2_medkit_msgs differ from the newest: a folder under
    ``medkit_replay/inputs/interfaces/`` whose files replace the bundled ones ("" for none).
    0.6.0's Fault has no ``last_passed`` (added by cd8c19b0, #573) and its GetRosbag and
    ListRosbags have no recording ids (afc13244, 869067ba, #620)."""
    freeze_frame_row: bool
    """A capture also keeps the fault's compact freeze frame, retained on clear (579b39db,
    822ebba6, b77cde21, #491)."""
    entity_default_snapshots: bool
    """``snapshots.entity_default`` exists: with no configured topic, capture the reporting
    node's own topics; empty ``default_topics`` entries are dropped (a702f94f, 8f30e127,
    ede2a62e)."""
    snapshot_sets: bool
    """A capture is stored as one set and ``snapshots.max_per_fault`` evicts whole sets, oldest
    first (df421024, ee00c000); before, a fault's first ``max_per_fault`` rows were kept and
    every later one refused."""
    retain_on_clear: bool
    """``snapshots.retain_on_clear`` exists (b066d5b3, 5af97631); before, a clear always
    deleted the fault's snapshots."""
    default_bag_format: str
    """``snapshots.rosbag.format`` when unset: sqlite3 until 054a41a5 (#610) made it mcap."""
    bag_history: bool
    """``snapshots.rosbag.max_bags_per_fault`` exists (f35c88a3, afc13244, #620); before, a
    fault held one recording, replaced by its next one."""
    post_roll_sharing: bool
    """A fault confirmed during another's post-roll joins that recording (5a58259f, 9ac52873,
    86c35f17, #561); before, it was skipped and got no recording."""
    post_roll_only_bags: bool
    """A fault confirmed with nothing buffered still gets a recording of its post-roll
    (0374f5fe, #594); before, an empty buffer meant no recording."""
    cleanup_in_post_roll: bool
    """A fault cleared during its own post-roll gets no recording row (6e5d2797, 5af97631);
    before, the row was stored when the post-roll ended and the recording kept."""


RELEASES: dict[str, Release] = {
    release.name: release
    for release in (
        # The bloom release apt installs on Humble, Jazzy and Lyrical.
        Release(
            name="0.6.0",
            commit="bdcc4ed0",
            date="2026-06-22",
            max_fault_code_length=128,
            # -- engine --
            clamp_counter=False,
            latch_confirmed_healed=False,
            backends_share_status_rule=False,
            occurrences_on_edges=False,
            passed_sets_last_occurred=True,
            reactivation_resets_first_occurred=False,
            heal_event=False,
            sanitize_thresholds=False,
            near_misses=False,
            # -- bridges --
            diagnostic_keyvalue_codes=False,
            diagnostic_hardware_id_sources=False,
            bridge_ints_read_as_int64=False,
            log_bridge_checks_coercions=False,
            action_bridge_defers_delivery=False,
            # -- evidence --
            msg_definitions="0.6.0",
            freeze_frame_row=False,
            entity_default_snapshots=False,
            snapshot_sets=False,
            retain_on_clear=False,
            default_bag_format="sqlite3",
            bag_history=False,
            post_roll_sharing=False,
            post_roll_only_bags=False,
            cleanup_in_post_roll=False,
        ),
        # main at 505bc2d5 (2026-08-22) plus #591; tagged 2026-08-27.
        Release(
            name="0.7.0",
            commit="505bc2d5+#591",
            date="2026-08-27",
            max_fault_code_length=256,
            # -- engine --
            clamp_counter=True,
            latch_confirmed_healed=True,
            backends_share_status_rule=True,
            occurrences_on_edges=True,
            passed_sets_last_occurred=False,
            reactivation_resets_first_occurred=True,
            heal_event=True,
            sanitize_thresholds=True,
            near_misses=True,
            # -- bridges --
            diagnostic_keyvalue_codes=True,
            diagnostic_hardware_id_sources=True,
            bridge_ints_read_as_int64=True,
            log_bridge_checks_coercions=True,
            action_bridge_defers_delivery=True,
            # -- evidence --
            msg_definitions="",
            freeze_frame_row=True,
            entity_default_snapshots=True,
            snapshot_sets=True,
            retain_on_clear=True,
            default_bag_format="mcap",
            bag_history=True,
            post_roll_sharing=True,
            post_roll_only_bags=True,
            cleanup_in_post_roll=True,
        ),
    )
}
"""Every release the replay models, oldest first."""

DEFAULT_RELEASE = "0.7.0"
"""The newest release: modelled unless a config says otherwise."""


def release_named(name: str) -> Release:
    """The release called ``name``.

    Raises:
        KeyError: no release of that name is modelled (the message lists those that are).
    """
    try:
        return RELEASES[name]
    except KeyError:
        known = ", ".join(RELEASES)
        raise KeyError(
            f"upstream_release {name!r} is not a release the replay models ({known})"
        ) from None


def default_release() -> Release:
    """The release modelled when no config names one (DEFAULT_RELEASE)."""
    return RELEASES[DEFAULT_RELEASE]
