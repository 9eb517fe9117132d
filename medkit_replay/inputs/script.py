"""A JSON-lines script as an input of a recording: each line one message carrying its request.

Plugs into READERS beside the bag readers; parsing and checking live in jsonl.py.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.inputs.jsonl import open_script
from medkit_replay.inputs.merge import Timed
from medkit_replay.inputs.source import InputContext, Message
from medkit_replay.model import InputSummary

if TYPE_CHECKING:
    from collections.abc import Iterator
    from pathlib import Path

SCRIPT_TYPE = "medkit_replay/script"


class ScriptInput:
    """One script; its summary is complete once its messages have been read."""

    def __init__(self, path: Path, context: InputContext) -> None:
        self.path = path
        self.context = context
        self._count = 0
        self._start: int | None = None
        self._end: int | None = None

    def messages(self) -> Iterator[Timed[Message]]:
        """Every request in file order (times never decrease; checked by the parser)."""
        index = self.context.input_index
        only = self.context.selection.only_roles
        if only is not None and "script" not in only:
            return
        for line in open_script(self.path):
            t_ns = line.request.t_ns
            if self._start is None:
                self._start = t_ns
            self._end = t_ns
            self._count += 1
            yield Timed(
                t_ns, (line.line,), Message(t_ns, index, "", SCRIPT_TYPE, "script", line.request)
            )

    def summary(self) -> InputSummary:
        """The script's span and line count."""
        return InputSummary(
            path=str(self.path),
            storage="jsonl",
            start_ns=self._start,
            end_ns=self._end,
            message_count=self._count,
        )

    def close(self) -> None:
        """Nothing stays open between reads."""


def open_script_input(path: Path, context: InputContext) -> ScriptInput:
    """The READERS opener for ``.jsonl`` files."""
    return ScriptInput(path, context)
