"""Writing to standard output so that its failures never change a command's verdict.

A reader that went away (``| head``) ends the output quietly; a full disk is one line, exit 2.
"""

from __future__ import annotations

import os
import sys
from contextlib import contextmanager
from typing import TYPE_CHECKING

from medkit_replay.errors import MedkitReplayError

if TYPE_CHECKING:
    from collections.abc import Iterator


@contextmanager
def standard_output(what: str) -> Iterator[None]:
    """Write ``what`` to standard output inside this block.

    A closed pipe sends the rest of the output nowhere and the command goes on to its exit
    status (a failed check still exits 1 under ``| head``).

    Raises:
        MedkitReplayError: any other write failure (ENOSPC, EIO), naming ``what``.
    """
    try:
        yield
        sys.stdout.flush()
    except BrokenPipeError:
        discard_stdout()
    except OSError as err:
        discard_stdout()  # what is still buffered would fail again at exit
        raise MedkitReplayError(
            f"cannot write {what} to standard output: {err.strerror or err}"
        ) from None


def discard_stdout() -> None:
    """Send whatever is still written to standard output nowhere."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, sys.stdout.fileno())
    finally:
        os.close(devnull)
