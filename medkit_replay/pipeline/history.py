"""Fills a FaultHistory from the one replay: each fault's state after every change, and the
correlation view after every step that can change it (``medkit-replay serve``).

Only listens, like the tracer: it wraps the row sinks the manager already writes through.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.history import CorrelationState

if TYPE_CHECKING:
    from collections.abc import Callable

    from medkit_replay.bridges.log import LogBridge
    from medkit_replay.engine.manager import FaultManager, Row
    from medkit_replay.history import FaultHistory
    from medkit_replay.model import ClearRequest, ReportSink
    from medkit_replay.pipeline.routing import Handler


class HistoryRecorder:
    """Attach to the manager (after any tracer) before the replay runs."""

    def __init__(
        self, history: FaultHistory, manager: FaultManager, log: LogBridge | None = None
    ) -> None:
        self.history = history
        self.manager = manager
        if log is not None:  # the logging nodes, also those whose lines report nothing
            log.feed = self._logged(log.feed)  # type: ignore[method-assign,assignment]
        report, event, transition = manager.report_row, manager.event_row, manager.transition_row
        manager.set_row_sinks(self._report(report), event, self._transition(transition))
        # The cleanup timer is not watched: it drops pending roots and clusters, never a muted
        # entry or an active cluster (the view recorded).
        self._cleared = manager.clear
        manager.clear = self._clear  # type: ignore[method-assign]

    def _note(self, t_ns: int, code: str) -> None:
        fault = self.manager.storage.faults.get(code)
        if fault is not None:
            self.history.put(t_ns, self.manager.snapshot(fault))

    def _note_correlation(self, t_ns: int) -> None:
        correlation = self.manager.correlation
        if correlation is not None:
            state = CorrelationState(
                tuple(correlation.muted_faults()), tuple(correlation.clusters())
            )
            self.history.put_correlation(t_ns, state)

    def _report(self, inner: Callable[[Row], None]) -> Callable[[Row], None]:
        # (t_ns, origin, topic, code, event name, severity, description, source, accepted, ...)
        sources = self.history.sources

        def sink(row: Row) -> None:
            inner(row)
            source = row[7]
            if isinstance(source, str):
                sources.add(source)
            if row[8]:
                t_ns, code = row[0], row[3]
                assert isinstance(t_ns, int) and isinstance(code, str)
                self._note(t_ns, code)
                if row[4] == "FAILED":
                    self._note_correlation(t_ns)

        return sink

    def _transition(self, inner: Callable[[Row], None]) -> Callable[[Row], None]:
        # (t_ns, code, before, after, cause, source): clears, auto-clears and the timer
        def sink(row: Row) -> None:
            inner(row)
            t_ns, code = row[0], row[1]
            assert isinstance(t_ns, int) and isinstance(code, str)
            self._note(t_ns, code)

        return sink

    def _clear(self, request: ClearRequest) -> bool:
        # A clear changes the muted map even when the code is unknown or already cleared.
        success = self._cleared(request)
        self._note_correlation(request.t_ns)
        return success

    def _logged(self, feed: Handler) -> Handler:
        sources = self.history.sources

        def logged(t_ns: int, topic: str, msg: object, report: ReportSink) -> None:
            name = getattr(msg, "name", "")
            if isinstance(name, str) and name:
                # A logger's name is its node's, namespace segments joined by dots.
                sources.add("/" + name.replace(".", "/"))
            feed(t_ns, topic, msg, report)

        return logged
