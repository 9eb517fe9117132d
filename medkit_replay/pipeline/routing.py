"""Which bridge takes a message, and the double-counting rule between bridges and recorded calls.

Recorded ReportFault traffic wins per fault code: a pre-pass finds those codes, the gate holds back
the bridges' requests for them.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.bridges.action_status import ActionStatusBridge
from medkit_replay.bridges.diagnostic import DiagnosticBridge
from medkit_replay.bridges.log import LogBridge
from medkit_replay.bridges.service_calls import ServiceCallReplayer
from medkit_replay.inputs import Message, open_recording
from medkit_replay.model import ClearRequest, ReportRequest
from medkit_replay.parity import RecordedEvent, recorded_event
from medkit_replay.pipeline.meter import Meter
from medkit_replay.spool import Spool

if TYPE_CHECKING:
    from collections.abc import Sequence

    from medkit_replay.config.replay_options import ReplayOptions
    from medkit_replay.inputs.remote.store import Tally
    from medkit_replay.model import Origin, Progress, ReportSink

Request = ReportRequest | ClearRequest
Handler = Callable[[int, str, object, "ReportSink"], None]
BRIDGE_ORIGINS = ("diagnostic_bridge", "action_status_bridge", "log_bridge")


class Router:
    """Hands each message to the bridge for its role and collects what they say."""

    def __init__(self, options: ReplayOptions) -> None:
        self.diagnostic = DiagnosticBridge(options.diagnostic)
        self.action = ActionStatusBridge(
            options.action_status, action_sources=options.action_sources, release=options.release
        )
        self.log = LogBridge(options.log) if options.log_bridge else None
        self.services = ServiceCallReplayer()
        self.recorded_events: Spool[RecordedEvent] = Spool()
        self.release = options.release  # its message layouts decode the recording

    def requests(self, message: Message) -> Sequence[Request]:
        """What a message without a bridge handler carries: script requests, recorded service
        calls; recorded FaultEvents are kept for parity."""
        role, t_ns, topic, msg = message.role, message.t_ns, message.topic, message.msg
        if role == "script":
            assert isinstance(msg, ReportRequest | ClearRequest)
            return (msg,)
        if role in ("report_fault", "clear_fault"):
            return self.services.on_message(t_ns, topic, message.msgtype, msg)
        if role == "fault_events":
            self.recorded_events.append(recorded_event(t_ns, topic, msg))
        return ()

    def handler(self, role: str, topic: str, msgtype: str) -> Handler | None:
        """The bridge that takes messages of this role, topic and type, if any (None: the
        message goes to :meth:`requests`)."""
        if role == "diagnostics" and self.diagnostic.wants(topic, msgtype):
            return self.diagnostic.feed
        if role == "rosout" and self.log is not None and self.log.wants(topic, msgtype):
            return self.log.feed
        if role == "action_status":
            return self.action.feed
        return None


def recorded_report_codes(
    inputs: Sequence[str | Path],
    progress: Callable[[Progress], None] | None,
    every: int,
    tallies: dict[str, Tally] | None = None,
) -> set[str]:
    """Fault codes present in recorded ReportFault traffic (a pre-pass over those topics only)."""
    services = ServiceCallReplayer()
    codes: set[str] = set()
    bags = [p for p in inputs if Path(p).suffix != ".jsonl"]
    if not bags:
        return codes
    with open_recording(bags, only_roles=("report_fault",), tallies=tallies) as recording:
        meter = Meter(progress, "prescan", recording, every) if progress is not None else None
        next_at = meter.next_at if meter is not None else 0
        messages = 0
        last_t: int | None = None
        for message in recording.messages():
            messages += 1
            last_t = message.t_ns
            if messages == next_at and meter is not None:
                meter.tick(messages, last_t)
                next_at = meter.next_at
            for request in services.on_message(
                message.t_ns, message.topic, message.msgtype, message.msg
            ):
                codes.add(request.fault_code)
        if meter is not None:
            meter.finish(messages, last_t)
    return codes


class Gate:
    """The double-counting rule between bridges and the manager: recorded service traffic wins.

    A bridge's request for a code also present in recorded ReportFault calls is withheld.
    What passes goes to ``apply`` (request objects: a Timeline's) or ``report_fields`` (a
    bridge's fields: a manager's, or a sweep's fan-out to several). With ``learn`` (a
    recording followed while written, which cannot be scanned ahead) the codes are learnt as
    the recorded calls arrive; ``late_codes`` are those some bridge had already reported
    before, which the rule would have withheld.
    """

    def __init__(
        self,
        apply: Callable[[Request], object],
        report_fields: ReportSink,
        recorded_codes: set[str],
        *,
        learn: bool = False,
    ) -> None:
        self._apply = apply
        self.recorded_codes = recorded_codes
        self.withheld: Counter[str] = Counter()
        self.withheld_codes: dict[str, set[str]] = {}
        self.on_withheld: Callable[[str, str], None] | None = None
        """Told (origin, fault code) of every request held back (``explain`` listens)."""
        self.learn = learn
        self.bridge_codes: set[str] = set()
        self.late_codes: set[str] = set()
        gated = recorded_codes or learn
        self.report: ReportSink = self._report_gated if gated else report_fields
        self._report_fields = report_fields

    def _learn(self, fault_code: str) -> None:
        if fault_code not in self.recorded_codes:
            self.recorded_codes.add(fault_code)
            if fault_code in self.bridge_codes:
                self.late_codes.add(fault_code)

    def _withhold(self, origin: str, fault_code: str) -> None:
        self.withheld[origin] += 1
        self.withheld_codes.setdefault(origin, set()).add(fault_code)
        if self.on_withheld is not None:
            self.on_withheld(origin, fault_code)

    def apply(self, request: Request) -> None:
        """One request object (a script's, a recorded service call's)."""
        if self.learn and request.origin == "report_fault" and isinstance(request, ReportRequest):
            self._learn(request.fault_code)
        if request.origin in BRIDGE_ORIGINS and request.fault_code in self.recorded_codes:
            self._withhold(request.origin, request.fault_code)
        elif isinstance(request, ReportRequest):
            self._report_fields(*request.as_fields())
        else:
            self._apply(request)

    def _report_gated(
        self,
        t_ns: int,
        origin: Origin,
        topic: str | None,
        fault_code: str,
        event_type: int,
        severity: int,
        description: str,
        source_id: str,
    ) -> None:
        """The gate's ReportSink for bridges (fields named, not ``*request``: it runs per
        request when gated, and forwarding a packed tuple costs more per call)."""
        # Only bridges report through here.
        if fault_code in self.recorded_codes:
            self._withhold(origin, fault_code)
            return
        if self.learn:
            self.bridge_codes.add(fault_code)
        self._report_fields(
            t_ns, origin, topic, fault_code, event_type, severity, description, source_id
        )
