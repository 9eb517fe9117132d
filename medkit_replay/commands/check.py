"""``medkit-replay check``: replay recordings and hold them to a fault budget (exit 1 if exceeded).

Thin: the budget, the verdicts and their outputs live in medkit_replay.checks.
"""

from __future__ import annotations

import os
import sys
from contextlib import nullcontext
from pathlib import Path

import click

from medkit_replay.checks.budget import load_budget
from medkit_replay.checks.evaluate import CheckRun, check_run
from medkit_replay.checks.github import step_summary, workflow_commands
from medkit_replay.checks.junit import write_junit
from medkit_replay.checks.terminal import print_conclusion, print_run
from medkit_replay.commands import config_option
from medkit_replay.errors import MedkitReplayError
from medkit_replay.outputs.progress import progress_bar
from medkit_replay.pipeline import replay


@click.command()
@click.argument("inputs", nargs=-1, required=True, type=click.Path(path_type=Path))
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
@click.option(
    "--junit",
    "junit_out",
    type=click.Path(path_type=Path, dir_okay=False),
    default=None,
    help="Write JUnit XML: one testsuite per run, one testcase per rule.",
)
@click.option(
    "--github",
    is_flag=True,
    help="Print GitHub Actions annotations; append a summary to $GITHUB_STEP_SUMMARY if set.",
)
@click.pass_context
def check(
    ctx: click.Context,
    inputs: tuple[Path, ...],
    budget_path: Path,
    configs: tuple[Path, ...],
    merge: bool,
    junit_out: Path | None,
    github: bool,
) -> None:
    """Replay each INPUT and check it against a fault budget.

    Each INPUT is its own run (one mission per recording) unless --merge is given. Exit
    status: 0 every rule holds on every run, 1 the budget is exceeded, 2 bad input or config.

    \b
    Examples:
      medkit-replay check mission/ --budget budget.yaml --config robot_params.yaml
      medkit-replay check runs/*.mcap --budget budget.yaml --junit budget.xml --github
    """
    budget = load_budget(budget_path)  # a bad budget fails before any replay
    groups = [list(inputs)] if merge else [[path] for path in inputs]
    runs: list[CheckRun] = []
    for group in groups:
        bar = progress_bar(sys.stderr)
        with bar if bar is not None else nullcontext():
            result = replay(group, configs, progress=bar)
        run = check_run(budget, result, [str(path) for path in group])
        runs.append(run)
        print_run(run, sys.stdout)
    print_conclusion(runs, sys.stdout)
    if junit_out is not None:
        try:
            write_junit(runs, junit_out)
        except OSError as err:
            raise MedkitReplayError(
                f"cannot write JUnit XML: {err.strerror}", path=str(junit_out)
            ) from None
    if github:
        _github(runs)
    if not all(run.passed for run in runs):
        ctx.exit(1)


def _github(runs: list[CheckRun]) -> None:
    for command in workflow_commands(runs):
        sys.stdout.write(command + "\n")
    summary_path = os.environ.get("GITHUB_STEP_SUMMARY")
    if not summary_path:
        return
    try:
        with Path(summary_path).open("a", encoding="utf-8") as stream:
            stream.write(step_summary(runs))
    except OSError as err:
        raise MedkitReplayError(
            f"cannot append the step summary: {err.strerror}", path=summary_path
        ) from None
