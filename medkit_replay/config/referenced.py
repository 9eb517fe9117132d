"""The files a set of parameter files makes the replay read: themselves and the files they name.

Commands protect all of them from being overwritten by an output.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.config.params import load_parameters

if TYPE_CHECKING:
    from collections.abc import Iterable

# fault_manager parameters whose value is a file, resolved beside the file that sets them.
FILE_PARAMETERS = ("correlation.config_file", "entity_thresholds.config_file")


def config_files(configs: Iterable[Path]) -> list[Path]:
    """``configs`` and every file their fault_manager parameters name, in that order.

    Raises:
        ConfigError: a config file is missing or unparsable.
    """
    paths = [Path(c) for c in configs]
    named = load_parameters(paths).node("fault_manager")
    found = list(paths)
    for name in FILE_PARAMETERS:
        param = named.get(name)
        if param is not None and isinstance(param.value, str) and param.value:
            found.append(param.path.parent / param.value)
    return found
