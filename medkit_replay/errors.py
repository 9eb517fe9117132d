"""Errors medkit-replay raises, each knowing the exit status the CLI turns it into, and the
located warnings config readers give. The library raises and returns these; the CLI prints them.
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
        return at(self.path, self.line, self.problem)


def at(path: str | None, line: int | None, text: str) -> str:
    """``path:line: text``, ``path: text`` or ``text``, as much as is known."""
    if path is None:
        return text
    return f"{path}:{line}: {text}" if line is not None else f"{path}: {text}"


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


class ConfigWarning(str):
    """A config reader's warning: the text every output shows, and what it is about.

    A ``str``, so that lists of warnings, reports and their bytes stay as they are;
    ``medkit-replay validate`` reads the fields instead of the text. ``path`` and ``line`` locate
    it (also when the text does not: ``shown_at=False`` keeps a text that never named them);
    ``suggestion`` is the name meant, for an unknown key; ``unusable`` says that the reader gave
    up on the file (upstream carries on without it); ``parameter`` names the ROS parameter it is
    about, so that the config layer, which knows where each value was written, can locate it.
    """

    message: str
    path: str | None
    line: int | None
    suggestion: str | None
    unusable: bool
    shown_at: bool
    parameter: str | None

    def __new__(
        cls,
        message: str,
        *,
        path: str | None = None,
        line: int | None = None,
        suggestion: str | None = None,
        unusable: bool = False,
        shown_at: bool = True,
        parameter: str | None = None,
    ) -> ConfigWarning:
        made = super().__new__(cls, at(path, line, message) if shown_at else message)
        made.message = message
        made.path = path
        made.line = line
        made.suggestion = suggestion
        made.unusable = unusable
        made.shown_at = shown_at
        made.parameter = parameter
        return made


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
