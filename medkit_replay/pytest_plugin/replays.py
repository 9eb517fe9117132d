"""The ``replay_recording`` fixture: recordings replayed with parameter files, once a session.

The replay is imported on first use only, its modules kept for later sessions of the process.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from medkit_replay.pytest_plugin.session import keeping_modules

if TYPE_CHECKING:
    from collections.abc import Sequence

    from medkit_replay.result import Result

PathLike = str | Path


class RecordingReplayer:
    """Replays recordings, each (inputs, configs) once per session."""

    def __init__(self) -> None:
        self._cache: dict[tuple[tuple[str, ...], tuple[str, ...]], Result] = {}

    def __call__(
        self,
        inputs: PathLike | Sequence[PathLike],
        configs: PathLike | Sequence[PathLike] = (),
    ) -> Result:
        """Replay ``inputs`` (merged as one recording) with the parameter files ``configs``
        (later ones overriding earlier ones); a path alone stands for a list of one.

        Raises:
            medkit_replay.errors.MedkitReplayError: an input or config cannot be used.
        """
        paths = [inputs] if isinstance(inputs, str | Path) else list(inputs)
        files = [configs] if isinstance(configs, str | Path) else list(configs)
        key = (
            tuple(str(Path(p).resolve()) for p in paths),
            tuple(str(Path(c).resolve()) for c in files),
        )
        if key not in self._cache:  # replayed with the paths as given, as the report shows them
            with keeping_modules():
                from medkit_replay.pipeline import replay  # noqa: PLC0415  # only when used

                self._cache[key] = replay(paths, files)
        return self._cache[key]


@pytest.fixture(scope="session")
def replay_recording() -> RecordingReplayer:
    """``replay_recording(inputs, configs=())`` -> Result, cached for the session."""
    return RecordingReplayer()
