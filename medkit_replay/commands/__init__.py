"""Subcommands of ``medkit-replay`` beyond ``analyze``: one module per command.

Each module defines one click command; ``medkit_replay.cli`` registers it on the group.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

if TYPE_CHECKING:
    from collections.abc import Callable

    from click.decorators import FC

CONFIG_HELP = "ROS 2 parameter file (repeatable; later files override earlier ones)."


def config_option(help_text: str = CONFIG_HELP) -> Callable[[FC], FC]:
    """The ``--config FILE`` option every command takes, collected as ``configs``."""
    return click.option(
        "--config", "configs", multiple=True, type=click.Path(path_type=Path), help=help_text
    )
