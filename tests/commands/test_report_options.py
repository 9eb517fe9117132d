"""analyze's and follow's file options are declared from outputs.OUTPUTS: each output's option
with its help, taking a file, or (an output that writes a folder's files) a folder or a file."""

from __future__ import annotations

import click
import pytest

from medkit_replay.cli import cli
from medkit_replay.outputs import OUTPUTS


@pytest.mark.parametrize("command", ["analyze", "follow"])
def test_file_options_come_from_outputs(command: str) -> None:
    params = {opt: p for p in cli.commands[command].params for opt in p.opts}
    for output in OUTPUTS:
        option = params[output.option]
        assert isinstance(option, click.Option)
        assert option.help == output.help
        assert option.type.dir_okay == (output.files is not None)  # type: ignore[attr-defined]
