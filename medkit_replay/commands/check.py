"""``medkit-replay check``: replay recordings and hold them to a fault budget (exit 1 if exceeded
or if a recording cannot be read).

Thin: the budget, the verdicts and their outputs live in medkit_replay.checks.
"""

from __future__ import annotations

import os
import stat
import sys
from contextlib import nullcontext
from pathlib import Path
from typing import TYPE_CHECKING

import click

from medkit_replay.commands import (
    allow_empty_option,
    config_option,
    input_argument,
    local_paths,
    path_option,
    say_written,
    strict_option,
    writing,
)
from medkit_replay.commands.streams import standard_output
from medkit_replay.errors import ConfigError, InputError, MedkitReplayError
from medkit_replay.files import FileRefusedError, check_regular
from medkit_replay.text import one_line

if TYPE_CHECKING:
    from medkit_replay.checks.budget import Budget
    from medkit_replay.checks.evaluate import CheckRun

SUMMARY_ENV = "GITHUB_STEP_SUMMARY"


@click.command()
@input_argument("inputs")
@click.option(
    "--budget",
    "budget_path",
    required=True,
    type=click.Path(path_type=Path),
    help="Fault budget YAML (version 1; see docs/budgets.md).",
)
@config_option()
@click.option(
    "--merge",
    is_flag=True,
    help="Check the inputs as one recording (as analyze does), not each as its own run.",
)
@path_option(
    "--junit", "junit_out", help="Write JUnit XML: one testsuite per run, one testcase per rule."
)
@click.option(
    "--github",
    is_flag=True,
    help="Print GitHub Actions annotations; append a summary to $GITHUB_STEP_SUMMARY if set.",
)
@allow_empty_option()
@strict_option()
@click.pass_context
def check(
    ctx: click.Context,
    inputs: tuple[Path | str, ...],
    budget_path: Path,
    configs: tuple[Path, ...],
    merge: bool,
    junit_out: Path | None,
    github: bool,
    allow_empty: bool,
    strict: bool,
) -> None:
    """Replay each INPUT and check it against a fault budget.

    Each INPUT is its own run (one mission per recording) unless --merge is given. A run in
    which nothing reached the fault manager fails, whatever the rules (--allow-empty passes
    it). Exit status: 0 every rule holds on every run; 1 the budget is exceeded or a recording
    cannot be read or replayed nothing (with --strict, also when one is read only in part); 2
    bad usage, budget or config, or an INPUT that does not exist.

    \b
    Examples:
      medkit-replay check mission/ --budget budget.yaml --config robot_params.yaml
      medkit-replay check runs/*.mcap --budget budget.yaml --junit budget.xml --github
    """
    # Imported here, so that --help and the other commands start without them.
    from medkit_replay.checks.budget_file import load_budget  # noqa: PLC0415
    from medkit_replay.checks.junit import write_junit  # noqa: PLC0415
    from medkit_replay.checks.terminal import (  # noqa: PLC0415
        print_conclusion,
        print_release,
        print_run,
    )
    from medkit_replay.config.params import load_parameters  # noqa: PLC0415
    from medkit_replay.config.referenced import config_files  # noqa: PLC0415
    from medkit_replay.config.release import release_of  # noqa: PLC0415
    from medkit_replay.outputs.atomic import refuse_overlap  # noqa: PLC0415

    budget = load_budget(budget_path, allow_empty=allow_empty)  # fails before any replay
    protected = config_files(configs)  # so does a bad config
    release = release_of(load_parameters(configs)).name
    for path in local_paths(inputs):
        if not os.path.lexists(path):
            raise InputError("input not found", path=str(path))
    summary_path = os.environ.get(SUMMARY_ENV) if github else None
    outputs = [("--junit", junit_out)] if junit_out is not None else []
    if summary_path:
        outputs.append((f"${SUMMARY_ENV}", Path(summary_path)))
    refuse_overlap([*local_paths(inputs), *protected, budget_path], outputs)
    groups = [list(inputs)] if merge else [[path] for path in inputs]
    runs: list[CheckRun] = []
    with standard_output("the check's results"):
        print_release(release, sys.stdout)
    for group in groups:
        run = _check_group(budget, group, configs, release, strict=strict)
        runs.append(run)
        with standard_output("the check's results"):
            print_run(run, sys.stdout)
    with standard_output("the check's results"):
        print_conclusion(runs, sys.stdout)
    if junit_out is not None:
        with writing("JUnit XML", junit_out):
            write_junit(runs, junit_out)
    if github:
        _github(runs)
    if junit_out is not None:
        say_written([junit_out])
    if not all(run.passed for run in runs):
        ctx.exit(1)


def _check_group(
    budget: Budget,
    group: list[Path | str],
    configs: tuple[Path, ...],
    release: str,
    *,
    strict: bool = False,
) -> CheckRun:
    """Replay one run and check it; a recording that cannot be read is a failed run saying why
    (a config problem is still the whole command's, exit 2)."""
    from medkit_replay.checks.evaluate import check_run, unreadable_run  # noqa: PLC0415
    from medkit_replay.outputs.console import progress_bar  # noqa: PLC0415
    from medkit_replay.pipeline import replay  # noqa: PLC0415

    labels = [str(path) for path in group]
    try:
        for path in local_paths(group):
            if not path.is_dir():
                check_regular(path)  # a FIFO would block its reader
        bar = progress_bar(sys.stderr)
        with bar if bar is not None else nullcontext():
            result = replay(group, configs, progress=bar)
        return check_run(budget, result, labels, strict=strict)
    except ConfigError:
        raise
    except MedkitReplayError as err:
        error = err.render()
    except FileRefusedError as err:
        error = f"{path}: {err}"
    except Exception as err:  # whatever the recording makes the replay raise: it failed
        text = one_line(err)
        error = f"{' + '.join(labels)}: {type(err).__name__}" + (f": {text}" if text else "")
    return unreadable_run(budget, labels, one_line(error), release)


def _github(runs: list[CheckRun]) -> None:
    from medkit_replay.checks.github import step_summary, workflow_commands  # noqa: PLC0415

    with standard_output("the GitHub annotations"):
        for command in workflow_commands(runs):
            sys.stdout.write(command + "\n")
    summary_path = os.environ.get(SUMMARY_ENV)
    if not summary_path:
        return
    try:
        append_whole(Path(summary_path), step_summary(runs).encode("utf-8", "backslashreplace"))
    except OSError as err:
        raise MedkitReplayError(
            f"cannot append the step summary: {err.strerror}", path=summary_path
        ) from None


def append_whole(path: Path, data: bytes) -> None:
    """Append ``data`` to a file in one write; if it cannot all be written (a full disk, a size
    limit, a signal), the file is cut back to its old length, so a failed append leaves nothing
    behind."""
    fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_CLOEXEC, 0o666)
    try:
        info = os.fstat(fd)
        regular = stat.S_ISREG(info.st_mode)
        try:
            rest = memoryview(data)
            while rest:  # one write, unless the system takes only part of it
                rest = rest[os.write(fd, rest) :]
        except BaseException:
            if regular:
                os.ftruncate(fd, info.st_size)
            raise
    finally:
        os.close(fd)
