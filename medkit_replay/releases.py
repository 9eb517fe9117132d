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
    """

    name: str
    commit: str
    date: str
    max_fault_code_length: int
    # -- the fault manager's storage and status rules (engine) --
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
            # -- bridges --
            diagnostic_keyvalue_codes=False,
            diagnostic_hardware_id_sources=False,
            bridge_ints_read_as_int64=False,
            log_bridge_checks_coercions=False,
            action_bridge_defers_delivery=False,
            # -- evidence --
        ),
        # main at 505bc2d5 (2026-08-22) plus #591; tagged 2026-08-27.
        Release(
            name="0.7.0",
            commit="505bc2d5+#591",
            date="2026-08-27",
            max_fault_code_length=256,
            # -- engine --
            # -- bridges --
            diagnostic_keyvalue_codes=True,
            diagnostic_hardware_id_sources=True,
            bridge_ints_read_as_int64=True,
            log_bridge_checks_coercions=True,
            action_bridge_defers_delivery=True,
            # -- evidence --
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
