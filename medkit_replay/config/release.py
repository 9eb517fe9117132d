"""Which upstream release a replay models: ``medkit_replay.upstream_release`` in any config.

Read once, before the nodes' configs, since their defaults and checks follow the release.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.config.nodes import located, values
from medkit_replay.config.reader import ParameterReader
from medkit_replay.errors import ConfigError
from medkit_replay.releases import DEFAULT_RELEASE, Release, release_named

if TYPE_CHECKING:
    from medkit_replay.config.params import ParameterSet

PARAMETER = "upstream_release"
"""The parameter of node ``medkit_replay`` that names the release."""


def release_of(params: ParameterSet) -> Release:
    """The release the merged parameter files name (the newest when none does).

    Raises:
        ConfigError: not a string, or a release the replay does not model, with file and line.
    """
    own = params.node("medkit_replay")

    def read() -> Release:
        name = ParameterReader("medkit_replay", values(own)).string(PARAMETER, DEFAULT_RELEASE)
        try:
            return release_named(name)
        except KeyError as err:
            raise ConfigError(str(err.args[0]), parameter=PARAMETER) from None

    return located(own, read)
