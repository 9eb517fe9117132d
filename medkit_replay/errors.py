"""Errors medkit-replay raises; each knows the exit status the CLI turns it into.

The library raises these; only the CLI prints them.
"""

from __future__ import annotations

import signal
from typing import ClassVar


class MedkitReplayError(Exception):
    """Base of every error the CLI reports as one line."""

    exit_code: ClassVar[int] = 2

    def __init__(self, problem: str, *, path: str | None = None, line: int | None = None) -> None:
        self.problem = problem
        self.path = path
        self.line = line
        super().__init__(self.render())

    def render(self) -> str:
        """``path:line: problem`` with whatever location is known."""
        where = ""
        if self.path is not None:
            where = f"{self.path}:{self.line}: " if self.line is not None else f"{self.path}: "
        return f"{where}{self.problem}"


class InputError(MedkitReplayError):
    """An input recording or script cannot be used (exit 2)."""


class ConfigError(MedkitReplayError):
    """A config file is missing, unparsable or holds a value upstream would refuse (exit 2).

    ``parameter`` names the ROS parameter at fault, so that the config layer, which knows
    where each value was written, can add the file and line.
    """

    def __init__(
        self,
        problem: str,
        *,
        path: str | None = None,
        line: int | None = None,
        parameter: str | None = None,
    ) -> None:
        self.parameter = parameter
        super().__init__(problem, path=path, line=line)


class Terminated(BaseException):  # like KeyboardInterrupt: not an Exception
    """A termination signal (SIGTERM, SIGHUP) turned into an exception that unwinds the stack.

    A BaseException, so that ``except Exception`` handlers never swallow it and every
    ``finally`` on the way out runs (temporary files are removed there).
    """

    def __init__(self, signum: int) -> None:
        self.signum = signum
        super().__init__(signum)

    def __str__(self) -> str:
        try:
            name = signal.Signals(self.signum).name
        except ValueError:
            name = f"signal {self.signum}"
        return f"terminated by {name}"
