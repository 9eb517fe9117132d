"""The files a set of parameter files makes the replay read: themselves and the files they name.

Commands protect all of them from being overwritten by an output.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.config.fault_manager import fault_manager_config
from medkit_replay.config.params import load_parameters
from medkit_replay.config.release import release_of
from medkit_replay.config.replay_options import replay_options

if TYPE_CHECKING:
    from collections.abc import Iterable

    from medkit_replay.config.kinds import Kind

FILE_PARAMETERS: dict[str, Kind] = {
    "correlation.config_file": "correlation",
    "entity_thresholds.config_file": "entity_thresholds",
    "snapshots.config_file": "snapshots",
}
"""fault_manager's parameters whose value is a file (resolved beside the file that sets them),
each with the kind of file it names."""


def config_files(configs: Iterable[str | Path], *, check: bool = True) -> list[Path]:
    """``configs`` and every file their fault_manager parameters name, in that order.

    With ``check``, the configs are also read as every replay will read them, so that a bad one
    stops a command before it starts (once, with its file and line).

    Raises:
        ConfigError: a config file is missing, unparsable, or (with ``check``) holds a value
            upstream refuses.
    """
    paths = [Path(c) for c in configs]
    params = load_parameters(paths)
    if check:
        release = release_of(params)
        fault_manager_config(params.node("fault_manager"), release)
        replay_options(params, release)
    named = params.node("fault_manager")
    found = list(paths)
    for name in FILE_PARAMETERS:
        param = named.get(name)
        if param is not None and isinstance(param.value, str) and param.value:
            found.append(param.path.parent / param.value)
    return found
