"""medkit-replay: what would ros2_medkit's fault manager have concluded during this recording?

Replays rosbag2/MCAP recordings and JSON-lines scripts through upstream's fault logic, offline.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.errors import ConfigError, InputError, MedkitReplayError
from medkit_replay.version import __version__

if TYPE_CHECKING:
    import pandas as pd

    from medkit_replay.pipeline import replay
    from medkit_replay.result import Result

__all__ = [
    "ConfigError",
    "InputError",
    "MedkitReplayError",
    "Result",
    "__version__",
    "replay",
    "tables",
]


def tables(result: Result) -> dict[str, pd.DataFrame]:
    """Every report table of ``result`` as a pandas DataFrame, keyed by the report's key names."""
    from medkit_replay.outputs.tables import result_tables  # noqa: PLC0415  # pandas is heavy

    return result_tables(result)


def __getattr__(name: str) -> object:
    # Lazy, so that importing the pure engine does not pull in YAML, rosbags or pandas.
    if name == "replay":
        from medkit_replay.pipeline import replay  # noqa: PLC0415

        return replay
    if name == "Result":
        from medkit_replay.result import Result  # noqa: PLC0415

        return Result
    raise AttributeError(name)
