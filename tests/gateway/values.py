"""Small fault and recording values for the gateway body tests, built in code."""

from __future__ import annotations

from medkit_replay.captures import EvidenceRecording
from medkit_replay.model import FaultSnapshot, Status

T0 = 1_700_000_000_000_000_000  # 2023-11-14T22:13:20Z


def fault(
    code: str,
    status: Status = "CONFIRMED",
    sources: tuple[str, ...] = ("/robot/motor",),
    *,
    severity: int = 2,
    description: str = "too hot",
    last_passed_ns: int = 0,
) -> FaultSnapshot:
    return FaultSnapshot(
        fault_code=code,
        severity=severity,
        description=description,
        first_occurred_ns=T0 + 250_000_000,
        last_occurred_ns=T0 + 5_123_456_789,
        last_passed_ns=last_passed_ns,
        occurrence_count=3,
        status=status,
        reporting_sources=sources,
        muted=False,
        root_cause_code=None,
        cluster_ids=(),
    )


def recording(
    rid: str, codes: tuple[str, ...], end_s: int, *, path: str | None = "/ev/x"
) -> EvidenceRecording:
    return EvidenceRecording(
        recording_id=rid,
        fault_codes=codes,
        start_ns=T0 + (end_s - 6) * 10**9,
        end_ns=T0 + end_s * 10**9,
        topics=(),
        messages=10,
        bytes=4096,
        deleted_ns=None,
        deleted_reason=None,
        path=path,
    )
