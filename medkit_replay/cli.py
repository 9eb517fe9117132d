"""The ``medkit-replay`` command line: parses options, calls the pipeline, writes outputs.

Thin: the only place errors become one line of text and an exit status.
"""

from __future__ import annotations

import importlib
import signal
import sys
from contextlib import nullcontext
from pathlib import Path
from typing import TYPE_CHECKING

import click

from medkit_replay.commands import config_option
from medkit_replay.commands.check import check
from medkit_replay.commands.diff import diff
from medkit_replay.commands.fleet import fleet
from medkit_replay.errors import MedkitReplayError, Terminated
from medkit_replay.outputs.json_report import write_json
from medkit_replay.outputs.progress import progress_bar
from medkit_replay.outputs.terminal import echo, print_summary
from medkit_replay.pipeline import replay
from medkit_replay.version import __version__

if TYPE_CHECKING:
    from medkit_replay.result import Result


@click.group()
@click.version_option(__version__, prog_name="medkit-replay")
def cli() -> None:
    """Replay recorded ROS 2 traffic through ros2_medkit's fault manager logic."""


@cli.command()
@click.argument("inputs", nargs=-1, required=True, type=click.Path(path_type=Path))
@config_option()
@click.option(
    "--json",
    "json_out",
    type=str,
    default=None,
    help="Write the JSON report here ('-' for standard output).",
)
@click.option(
    "--csv",
    "csv_dir",
    type=click.Path(path_type=Path),
    default=None,
    help="Write every report table as CSV into this directory.",
)
@click.option(
    "--parquet",
    "parquet_dir",
    type=click.Path(path_type=Path),
    default=None,
    help="Write every report table as Parquet into this directory (needs the 'parquet' extra).",
)
@click.option(
    "--mcap",
    "mcap_out",
    type=click.Path(path_type=Path, dir_okay=False),
    default=None,
    help="Write the replayed FaultEvents and status changes as an MCAP recording.",
)
@click.option(
    "--html",
    "html_out",
    type=click.Path(path_type=Path, dir_okay=False),
    default=None,
    help="Write a self-contained HTML report (fault timeline, counter traces, correlation).",
)
@click.option("--quiet", is_flag=True, help="No human summary, no progress bar.")
def analyze(
    inputs: tuple[Path, ...],
    configs: tuple[Path, ...],
    json_out: str | None,
    csv_dir: Path | None,
    parquet_dir: Path | None,
    mcap_out: Path | None,
    html_out: Path | None,
    quiet: bool,
) -> None:
    """Replay INPUT... (merged as one recording) and report what the fault manager concluded.

    \b
    Examples:
      medkit-replay analyze mission/ --config robot_params.yaml --json report.json
      medkit-replay analyze run.jsonl --json - --quiet
      medkit-replay analyze bag/ --html report.html
      medkit-replay analyze mission/ --mcap replayed.mcap --parquet tables/
    """
    if parquet_dir is not None:
        from medkit_replay.outputs.parquet import require_pyarrow  # noqa: PLC0415  # pandas

        require_pyarrow()  # say so before a long replay, not after it
    bar = progress_bar(sys.stderr, quiet=quiet)
    with bar if bar is not None else nullcontext():
        result = replay(list(inputs), list(configs), progress=bar)
    if json_out == "-":
        write_json(result, sys.stdout)
    elif json_out is not None:
        try:
            with Path(json_out).open("w", encoding="utf-8") as stream:
                write_json(result, stream)
        except OSError as err:
            raise MedkitReplayError(f"cannot write report: {err.strerror}", path=json_out) from None
    for target, label, module, function in (
        (csv_dir, "CSV", "medkit_replay.outputs.tables", "write_csv"),
        (parquet_dir, "Parquet", "medkit_replay.outputs.parquet", "write_parquet"),
        (mcap_out, "MCAP", "medkit_replay.outputs.mcap_events", "write_mcap"),
        (html_out, "HTML", "medkit_replay.outputs.html", "write_html"),
    ):
        if target is not None:
            _write_output(result, target, label, module, function)
    if not quiet:
        print_summary(result, sys.stderr if json_out == "-" else sys.stdout)


def _write_output(result: Result, target: Path, label: str, module: str, function: str) -> None:
    """Run one file output; its module is imported only now (pandas, pyarrow, mcap are heavy)."""
    writer = getattr(importlib.import_module(module), function)
    try:
        writer(result, target)
    except OSError as err:
        raise MedkitReplayError(f"cannot write {label}: {err.strerror}", path=str(target)) from None


def _terminate(signum: int, _frame: object) -> None:
    raise Terminated(signum)


def _install_signal_handlers() -> None:
    """SIGTERM and SIGHUP unwind like Ctrl-C, so every ``finally`` removes its temporary files."""
    for name in ("SIGTERM", "SIGHUP"):
        signum = getattr(signal, name, None)
        if signum is not None and signal.getsignal(signum) is signal.SIG_DFL:
            signal.signal(signum, _terminate)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the console script; returns the exit status."""
    _install_signal_handlers()
    try:
        status = cli.main(args=argv, prog_name="medkit-replay", standalone_mode=False)
    except Terminated as err:
        echo(f"medkit-replay: {err}; nothing partial was left behind\n", sys.stderr)
        return 2
    except MedkitReplayError as err:
        echo(f"medkit-replay: error: {err.render()}\n", sys.stderr)
        return err.exit_code
    except click.exceptions.Abort:
        echo("medkit-replay: aborted\n", sys.stderr)
        return 2
    except click.ClickException as err:
        echo(f"medkit-replay: error: {err.format_message()}\n", sys.stderr)
        return 2
    except Exception as err:  # a bug must still end in one line, no traceback
        echo(
            f"medkit-replay: internal error: {type(err).__name__}: {err} (please report this)\n",
            sys.stderr,
        )
        return 2
    # A command that ends with ctx.exit(n) (a failed check: 1) hands its status back here.
    return status if isinstance(status, int) else 0


# Subcommands beyond analyze live in medkit_replay/commands/, one module each; register here.
cli.add_command(check)
cli.add_command(diff)
cli.add_command(fleet)


if __name__ == "__main__":
    sys.exit(main())
