"""Ports of upstream's LocalFilter tests (fault-manager.md §4.8, LF-01..LF-14 and the [I] ones).

Each scenario is a list of operations on one LocalFilter (fixture config: enabled, threshold 3,
window 10 s, bypass ERROR); the clock is bag time, advancing 1 ms per call unless told.
"""

from __future__ import annotations

from dataclasses import dataclass

import pytest

from medkit_replay.engine.local_filter import LocalFilter, LocalFilterConfig
from medkit_replay.model import NS_PER_MS, NS_PER_SEC
from tests.engine.upstream_support import CRITICAL, ERROR, INFO, upstream

TEST_FAULT = "TEST_FAULT"


@dataclass(frozen=True, kw_only=True)
class Op:
    """One call: fwd (should_forward), fwd_p (should_forward_passed), reset, reset_all,
    set_config, or wait (advance the clock by ``wait_ns``)."""

    kind: str
    code: str = TEST_FAULT
    severity: int = INFO
    expect: bool | None = None
    config: LocalFilterConfig | None = None
    wait_ns: int = 0


def fwd(expect: bool, code: str = TEST_FAULT, severity: int = INFO) -> Op:
    """should_forward(code, severity) must return ``expect``."""
    return Op(kind="fwd", code=code, severity=severity, expect=expect)


def fwd_p(expect: bool, code: str = TEST_FAULT) -> Op:
    """should_forward_passed(code) must return ``expect``."""
    return Op(kind="fwd_p", code=code, expect=expect)


def reset(code: str = TEST_FAULT) -> Op:
    """reset(code)."""
    return Op(kind="reset", code=code)


def reset_all() -> Op:
    """reset_all()."""
    return Op(kind="reset_all")


def set_config(config: LocalFilterConfig) -> Op:
    """set_config(config)."""
    return Op(kind="set_config", config=config)


def wait(ns: int) -> Op:
    """Let ``ns`` of bag time pass."""
    return Op(kind="wait", wait_ns=ns)


def fwds(*expected: bool, code: str = TEST_FAULT, severity: int = INFO) -> list[Op]:
    """Consecutive should_forward calls."""
    return [fwd(e, code, severity) for e in expected]


def run(ops: list[Op], start_ns: int = 1000 * NS_PER_SEC) -> None:
    """Apply the operations to a fixture-configured filter and check every returned value."""
    lf = LocalFilter(LocalFilterConfig())
    now = start_ns
    for index, op in enumerate(ops):
        where = f"op {index + 1}: {op}"
        if op.kind in ("fwd", "fwd_p"):
            result = (
                lf.should_forward(op.code, op.severity, now)
                if op.kind == "fwd"
                else lf.should_forward_passed(op.code, now)
            )
            assert result is op.expect, where
            now += NS_PER_MS
        elif op.kind == "reset":
            lf.reset(op.code)
        elif op.kind == "reset_all":
            lf.reset_all()
        elif op.kind == "set_config":
            assert op.config is not None
            lf.set_config(op.config)
        elif op.kind == "wait":
            now += op.wait_ns
        else:
            pytest.fail(f"unknown op {op.kind}")


DISABLED = LocalFilterConfig(enabled=False)

CASES = [
    pytest.param(
        [set_config(DISABLED), *fwds(True, True)], id="LF-01-FilterDisabledAlwaysForwards"
    ),
    pytest.param(fwds(False, False, True), id="LF-02-ThresholdNotMetFilters"),
    pytest.param(
        [
            fwd(False, "FAULT_A"),
            fwd(False, "FAULT_B"),
            fwd(False, "FAULT_A"),
            fwd(False, "FAULT_B"),
            fwd(True, "FAULT_A"),
            fwd(True, "FAULT_B"),
        ],
        id="LF-03-DifferentFaultCodesTrackedSeparately",
    ),
    pytest.param(
        [fwd(True, severity=ERROR), fwd(True, severity=CRITICAL)],
        id="LF-04-HighSeverityBypassesFilter",
    ),
    pytest.param(
        [
            set_config(
                LocalFilterConfig(default_threshold=3, default_window_sec=0.1, bypass_severity=3)
            ),
            *fwds(False, False),
            wait(150 * NS_PER_MS),
            *fwds(False, False, True),
        ],
        id="LF-05-TimeWindowExpiry",
    ),
    pytest.param(
        [*fwds(False, False), reset(), *fwds(False, False, True)], id="LF-06-ResetClearsTracking"
    ),
    pytest.param(
        [
            fwd(False, "FAULT_A"),
            fwd(False, "FAULT_B"),
            reset_all(),
            fwd(False, "FAULT_A"),
            fwd(False, "FAULT_B"),
        ],
        id="LF-07-ResetAllClearsAllTracking",
    ),
    pytest.param(
        [
            *fwds(False, False),
            set_config(
                LocalFilterConfig(default_threshold=2, default_window_sec=10.0, bypass_severity=3)
            ),
            *fwds(False, True),
        ],
        id="LF-09-SetConfigClearsState",
    ),
    pytest.param(
        [set_config(LocalFilterConfig(default_threshold=1, bypass_severity=3)), fwd(True)],
        id="LF-10-ThresholdOneForwardsImmediately",
    ),
    pytest.param(
        fwds(False, False, True, True, True), id="LF-11-ContinuousReportingAfterThreshold"
    ),
    pytest.param([fwd_p(False), fwd_p(False), fwd_p(True)], id="LF-12-PassedEventsAreFiltered"),
    pytest.param(
        [set_config(DISABLED), fwd_p(True)], id="LF-13-PassedFilterDisabledAlwaysForwards"
    ),
    pytest.param(
        [fwd(False), fwd_p(False), fwd(False), fwd_p(False), fwd(True), fwd_p(True)],
        id="LF-14-PassedAndFailedTrackedSeparately",
    ),
]


@upstream(
    "LF-01",
    "LF-02",
    "LF-03",
    "LF-04",
    "LF-05",
    "LF-06",
    "LF-07",
    "LF-09",
    "LF-10",
    "LF-11",
    "LF-12",
    "LF-13",
    "LF-14",
)
@pytest.mark.parametrize("ops", CASES)
def test_local_filter(ops: list[Op]) -> None:
    """LocalFilterTest.*: every should_forward / should_forward_passed result."""
    run(ops)


@upstream("LF-08")
def test_lf08_config_returns_current_config() -> None:
    """LF-08 ConfigReturnsCurrentConfig: enabled, threshold 3, window 10.0, bypass ERROR."""
    config = LocalFilter(LocalFilterConfig()).config
    assert config == LocalFilterConfig(
        enabled=True, default_threshold=3, default_window_sec=10.0, bypass_severity=ERROR
    )
    assert LocalFilter().config == config


# -- inferred additions [I] ---------------------------------------------------------------------


@upstream("LF-inferred")
def test_lf_inferred_bypassed_reports_are_not_tracked() -> None:
    """[I] INFO, ERROR, INFO → false, true, false: the bypassed ERROR does not count."""
    run([fwd(False), fwd(True, severity=ERROR), fwd(False)])


@upstream("LF-inferred")
def test_lf_inferred_threshold_zero_is_one() -> None:
    """[I] threshold 0 is treated as 1: the first report forwards."""
    run([set_config(LocalFilterConfig(default_threshold=0)), fwd(True), fwd_p(True)])
    assert LocalFilter(LocalFilterConfig(default_threshold=0)).config.default_threshold == 1


@upstream("LF-inferred")
@pytest.mark.parametrize("window", [0.0, -5.0])
def test_lf_inferred_non_positive_window_is_one_second(window: float) -> None:
    """[I] window <= 0 becomes 1.0 s (not the default 10 s)."""
    config = LocalFilterConfig(default_window_sec=window)
    assert LocalFilter(config).config.default_window_sec == 1.0
    second = NS_PER_SEC
    # Reports at 0, 0.5 s and 1.0 s: the first is exactly 1 s old and still counts.
    run([set_config(config), fwd(False), wait(second // 2 - NS_PER_MS), fwd(False)])
    run(
        [
            set_config(config),
            fwd(False),
            wait(second // 2 - NS_PER_MS),
            fwd(False),
            wait(second // 2 - NS_PER_MS),
            fwd(True),
        ]
    )
    # One nanosecond later the first report has left the 1 s window.
    run(
        [
            set_config(config),
            fwd(False),
            wait(second // 2 - NS_PER_MS),
            fwd(False),
            wait(second // 2 - NS_PER_MS + 1),
            fwd(False),
        ]
    )


@upstream("LF-inferred")
@pytest.mark.parametrize(("extra_ns", "third"), [(0, True), (1, False)])
def test_lf_inferred_timestamp_exactly_window_old_is_counted(extra_ns: int, third: bool) -> None:
    """[I] With the 10 s window, a report exactly 10 s old still counts; 1 ns older does not.
    Reports at 0, 5 s and 10 s (+ extra_ns), on both the FAILED and the PASSED tracker."""
    step = 5 * NS_PER_SEC - NS_PER_MS  # run() adds 1 ms after each call
    run([fwd(False), wait(step), fwd(False), wait(step + extra_ns), fwd(third)])
    run([fwd_p(False), wait(step), fwd_p(False), wait(step + extra_ns), fwd_p(third)])
