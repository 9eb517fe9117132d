"""The plugin's pytest hooks and its state per process: the sessions running, the modules kept.

``--update-golden`` and ``--allow-empty-replay`` are read from the innermost running session
(pytester nests sessions). The modules the replays, budgets and goldens import are kept here and
handed back to every later session, so that none is imported twice in one process (see the
package's docstring).
"""

from __future__ import annotations

import sys
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    from collections.abc import Iterator
    from types import ModuleType

_configs: list[pytest.Config] = []
"""Configs of the running pytest sessions, innermost last (pytester nests sessions)."""
_updated_key = pytest.StashKey[list[Path]]()
_KEPT: dict[str, ModuleType] = {}
"""Every module this plugin's replays, budgets and goldens brought into the process, by name:
put back into ``sys.modules`` when a session starts, so that none is ever imported twice."""


@contextmanager
def keeping_modules() -> Iterator[None]:
    """Remember the modules imported inside the block (the replay's, numpy, rosbags...), after
    putting back those an earlier block imported (a pytester session may have dropped them)."""
    _restore_modules()
    before = set(sys.modules)
    try:
        yield
    finally:
        for name in set(sys.modules) - before:
            module = sys.modules.get(name)
            if module is not None:
                _KEPT.setdefault(name, module)


def _restore_modules() -> None:
    """Give ``sys.modules`` back the modules an earlier session imported and pytester dropped."""
    for name, module in _KEPT.items():
        sys.modules.setdefault(name, module)


# --- hooks ---------------------------------------------------------------------------------------


def pytest_addoption(parser: pytest.Parser) -> None:
    """Add ``--update-golden``, ``--allow-empty-replay``, ``--strict-replay`` and
    ``--golden-max-report-mb``."""
    group = parser.getgroup("medkit-replay", "medkit-replay regression tests")
    group.addoption(
        "--update-golden",
        action="store_true",
        default=False,
        dest="medkit_replay_update_golden",
        help="medkit-replay: write golden reports that differ or are missing instead of failing.",
    )
    group.addoption(
        "--allow-empty-replay",
        action="store_true",
        default=False,
        dest="medkit_replay_allow_empty",
        help="medkit-replay: let assert_within_budget pass a replay in which nothing reached "
        "the fault manager (it fails by default).",
    )
    group.addoption(
        "--strict-replay",
        action="store_true",
        default=False,
        dest="medkit_replay_strict",
        help="medkit-replay: assert_within_budget fails a recording read only in part (damage).",
    )
    group.addoption(
        "--golden-max-report-mb",
        type=int,
        default=None,
        dest="medkit_replay_max_report_mb",
        metavar="MB",
        help="medkit-replay: largest golden report read, plain or decompressed, in MiB "
        "(default 1024, or MEDKIT_REPLAY_MAX_REPORT_MB).",
    )


def pytest_configure(config: pytest.Config) -> None:
    """Remember the session's config (for the update flag of the module-level helpers), and
    hand it the replay's modules if an earlier session in this process imported them."""
    _restore_modules()
    mb = config.getoption("medkit_replay_max_report_mb", None)
    if mb is not None and mb < 1:
        raise pytest.UsageError("--golden-max-report-mb must be 1 or more")
    config.stash[_updated_key] = []
    _configs.append(config)


def pytest_unconfigure(config: pytest.Config) -> None:
    """Forget the session's config."""
    if config in _configs:
        _configs.remove(config)


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    """List the golden reports this session wrote (only when it wrote any)."""
    updated = terminalreporter.config.stash.get(_updated_key, [])
    if not updated:
        return
    terminalreporter.section("medkit-replay golden reports written")
    for path in updated:
        terminalreporter.write_line(str(path))


def update_requested() -> bool:
    if not _configs:
        return False
    return bool(_configs[-1].getoption("medkit_replay_update_golden"))


def empty_allowed() -> bool:
    """``--allow-empty-replay`` was given to the innermost running session."""
    if not _configs:
        return False
    return bool(_configs[-1].getoption("medkit_replay_allow_empty"))


def strict_requested() -> bool:
    """Whether ``--strict-replay`` was given (False outside a pytest session)."""
    if not _configs:
        return False
    return bool(_configs[-1].getoption("medkit_replay_strict"))


def golden_size_limit() -> int | None:
    """``--golden-max-report-mb`` in bytes, or None when not given (the default limit)."""
    if not _configs:
        return None
    mb = _configs[-1].getoption("medkit_replay_max_report_mb")
    return None if mb is None else int(mb) * 1024 * 1024


def note_updated(path: Path) -> None:
    if _configs:
        _configs[-1].stash.setdefault(_updated_key, []).append(path)
