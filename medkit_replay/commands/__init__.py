"""Subcommands of ``medkit-replay`` beyond ``analyze``: one module per command.

Each module defines one click command; ``medkit_replay.cli`` registers it on the group.
"""

from __future__ import annotations

import contextlib
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Literal

import click

from medkit_replay.errors import MedkitReplayError
from medkit_replay.files import is_remote

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Iterator, Sequence

    from click.decorators import FC

    from medkit_replay.checks import Budget
    from medkit_replay.model import Loss

CONFIG_HELP = "ROS 2 parameter file (repeatable; later files override earlier ones)."


def as_input(value: str) -> Path | str:
    """A recording argument: a local path, or an ``s3://``, ``gs://``, ``http(s)://`` URL kept
    as written (a Path would fold its ``//``)."""
    return value if is_remote(value) else Path(value)


def _as_inputs(
    _ctx: click.Context, _param: click.Parameter, value: str | tuple[str, ...]
) -> Path | str | tuple[Path | str, ...]:
    return as_input(value) if isinstance(value, str) else tuple(map(as_input, value))


def input_argument(name: str, *, many: bool = True) -> Callable[[FC], FC]:
    """A recording argument (``many``: one or more) taking local paths and URLs alike."""
    return click.argument(
        name, nargs=-1 if many else 1, required=True, type=str, callback=_as_inputs
    )


def local_paths(inputs: Iterable[Path | str]) -> list[Path]:
    """The inputs that are local paths (a URL cannot be overwritten by an output)."""
    return [path for path in inputs if isinstance(path, Path)]


def config_option(help_text: str = CONFIG_HELP) -> Callable[[FC], FC]:
    """The ``--config FILE`` option every command takes, collected as ``configs``."""
    return click.option(
        "--config", "configs", multiple=True, type=click.Path(path_type=Path), help=help_text
    )


PathKind = Literal["file", "folder", "any"]

_PATH_TYPES: dict[PathKind, click.Path] = {
    "file": click.Path(path_type=Path, dir_okay=False),
    "folder": click.Path(path_type=Path, file_okay=False),
    "any": click.Path(path_type=Path),
}


def path_option(
    *names: str,
    help: str,
    kind: PathKind = "file",
    default: Path | None = None,
    show_default: bool | None = None,
) -> Callable[[FC], FC]:
    """An option naming one file, one folder or any path (``kind``) to read or write, given as
    a Path."""
    return click.option(
        *names, type=_PATH_TYPES[kind], default=default, show_default=show_default, help=help
    )


def count_option(
    *names: str,
    help: str,
    default: int | None = None,
    most: int | None = None,
    show_default: bool | None = None,
    metavar: str | None = None,
) -> Callable[[FC], FC]:
    """An option taking a whole number from 1 (to ``most``): a count, a bound, a size."""
    return click.option(
        *names,
        type=click.IntRange(min=1, max=most),
        default=default,
        show_default=show_default,
        metavar=metavar,
        help=help,
    )


JOBS_OPTION = count_option(
    "--jobs", help="Worker processes (default: one per CPU; 1 runs in this process)."
)
"""``--jobs``: how many worker processes run the replays (one per CPU by default)."""


def allow_empty_option() -> Callable[[FC], FC]:
    """``--allow-empty``: a run in which nothing reached the fault manager may hold the budget
    (``check``, ``fleet --budget``, ``sweep --budget``)."""
    return click.option(
        "--allow-empty",
        is_flag=True,
        help="Let a run pass the budget though nothing in it reached the fault manager (no "
        "bridge topic, no recorded ReportFault/ClearFault call, nothing readable); without it "
        "such a run fails.",
    )


MAX_TIMEOUT = 10**9
"""Seconds: a longer --timeout is refused (some 30 years)."""


def _timeout_seconds(
    _ctx: click.Context, _param: click.Parameter, value: float | None
) -> float | None:
    if value is not None and not (math.isfinite(value) and 0 < value <= MAX_TIMEOUT):
        raise click.BadParameter(f"must be a number of seconds above 0, at most {MAX_TIMEOUT}")
    return value


def stacked(*options: Callable[[FC], FC]) -> Callable[[FC], FC]:
    """Several options as one decorator, listed in ``--help`` in the order given."""

    def decorate(command: FC) -> FC:
        for option in reversed(options):
            command = option(command)
        return command

    return decorate


def executor_options(timeout_help: str) -> Callable[[FC], FC]:
    """``--jobs``, ``--dask`` and ``--timeout``: where a command running many replays runs them
    (``fleet``, ``sweep``); ``timeout_help`` says what one timed-out unit of work is."""
    options = (
        JOBS_OPTION,
        click.option(
            "--dask",
            "dask_address",
            type=str,
            default=None,
            metavar="ADDRESS",
            help="Run on this Dask distributed scheduler (needs the 'dask' extra).",
        ),
        click.option(
            "--timeout",
            type=float,
            default=None,
            callback=_timeout_seconds,
            metavar="SECONDS",
            help=timeout_help,
        ),
    )
    return stacked(*options)


def check_executor(
    dask_address: str | None, jobs: int | None, *, strict: bool, budget: object, units: str
) -> None:
    """Refuse what ``executor_options`` and ``--strict`` cannot do together, before anything
    runs: ``--jobs`` with ``--dask``, ``--strict`` without ``--budget`` (``units``: what the
    command checks, runs or inputs); and say a missing ``dask`` extra at once."""
    if dask_address is not None and jobs is not None:
        raise click.UsageError("--jobs and --dask cannot be used together")
    if strict and budget is None:
        raise click.UsageError(f"--strict fails {units} of a budget check: give --budget too")
    if dask_address is not None:
        from medkit_replay.fleet.cluster import dask_client_type  # noqa: PLC0415

        dask_client_type()


def make_folder(path: Path, what: str) -> None:
    """Create an output folder (and its parents), or say in one line why it cannot be."""
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise MedkitReplayError(f"cannot create {what}: {err.strerror}", path=str(path)) from None


def foreign_clips(refused: Sequence[str], *, outputs: bool) -> MedkitReplayError:
    """The error for clip folders the evidence folder holds but this tool did not write
    (``Result.evidence_refused``); ``outputs``: the command's other outputs were written."""
    from medkit_replay.evidence.folder import MARKER  # noqa: PLC0415

    first, *others = refused
    more = f" ({len(others):,} more folders alike)" if others else ""
    written = "no recording was written" + (", the other outputs were" if outputs else "")
    return MedkitReplayError(
        f"has a clip's name but is not a clip this tool wrote (no {MARKER} in it){more}; "
        f"{written}: write the clips to another folder",
        path=first,
    )


STRICT_HELP = (
    "Fail (exit 1) a recording read only in part: any message, byte or file lost to damage, "
    "named in one line with what it cost (without it, damage is a warning)."
)


def strict_option() -> Callable[[FC], FC]:
    """``--strict``: damage fails the check (``check``; ``fleet``, ``sweep`` with a budget)."""
    return click.option("--strict", is_flag=True, help=STRICT_HELP)


@contextlib.contextmanager
def writing(what: str, path: Path | str | None) -> Iterator[None]:
    """Writing ``what`` (an output a command writes) to ``path``: an OSError becomes the one
    line that names the file (exit status 2), never a traceback."""
    try:
        yield
    except OSError as err:
        raise MedkitReplayError(
            f"cannot write {what}: {err.strerror or err}", path=str(path)
        ) from None


def say_written(paths: Iterable[Path | str], *, quiet: bool = False) -> None:
    """One line per file or folder an option wrote (``wrote report.html``), on standard error
    so that standard output stays the report or the summary; nothing when ``quiet``."""
    if quiet:
        return
    from medkit_replay.text import printable  # noqa: PLC0415  # not for --help

    # The summary before these lines, where both streams meet (nobody reading it: no order).
    with contextlib.suppress(BrokenPipeError, ValueError):
        sys.stdout.flush()
    for path in paths:
        click.echo(f"wrote {printable(str(path))}", err=True)


def optional_budget(path: Path | None, *, allow_empty: bool) -> Budget | None:
    """The ``--budget`` file read (before any replay), or None without one."""
    if path is None:
        return None
    from medkit_replay.checks import load_budget  # noqa: PLC0415  # only with a budget

    return load_budget(path, allow_empty=allow_empty)


def exit_on_failure(
    failed: bool, *, budget: Budget | None, strict: bool, losses: Iterable[Loss]
) -> None:
    """Exit 1 when a budget was given and some run failed, or (with ``--strict``, each said in
    a line on standard error) a recording was read only in part; else return."""
    if strict:
        from medkit_replay.model import strict_failure  # noqa: PLC0415  # not for --help

        lines = [strict_failure(loss) for loss in losses]
        for line in lines:
            click.echo(line, err=True)
        failed = failed or bool(lines)
    if budget is not None and failed:
        click.get_current_context().exit(1)
