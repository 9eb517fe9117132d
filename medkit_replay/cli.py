"""The ``medkit-replay`` command line: the group of commands and its entry point.

Thin: the only place errors become one line of text and an exit status.
"""

from __future__ import annotations

import atexit
import os
import signal
import sys
import threading
from typing import NoReturn

import click

from medkit_replay.commands.analyze import analyze
from medkit_replay.commands.check import check
from medkit_replay.commands.diff import diff
from medkit_replay.commands.explain import explain
from medkit_replay.commands.fleet import fleet
from medkit_replay.commands.follow import follow
from medkit_replay.commands.serve import serve
from medkit_replay.commands.streams import discard_stdout
from medkit_replay.commands.suggest_rules import suggest_rules
from medkit_replay.commands.sweep import sweep
from medkit_replay.commands.validate import validate
from medkit_replay.errors import MedkitReplayError, Terminated
from medkit_replay.outputs.console import echo
from medkit_replay.version import __version__


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="medkit-replay")
def cli() -> None:
    """Replay recorded ROS 2 traffic through ros2_medkit's fault manager logic.

    Exit status: 0 pass; 1 a check failed; 2 usage or input error -- except that in check,
    fleet --budget, sweep --budget and the pytest plugin a recording that cannot be read, or
    is empty, is a failed check (1).
    """


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
    except BrokenPipeError:
        # The reader of standard output stopped (``| head``): that ends the output, not a failure.
        discard_stdout()
        return 0
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


def run() -> NoReturn:
    """The console script: :func:`main`, then out at once.

    By then every output is written and closed; the exit functions still run (temporary
    folders go), but the interpreter does not free a long replay's objects one by one before
    the process ends, which costs a tenth of a second and changes nothing.
    """
    status = main()
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        discard_stdout()
    sys.stderr.flush()
    if any(t.is_alive() and not t.daemon for t in threading.enumerate() if t is not _MAIN):
        sys.exit(status)  # a thread still at work: leave the usual way, which waits for it
    atexit._run_exitfuncs()  # the exit functions os._exit would skip
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)


_MAIN = threading.main_thread()

# Subcommands live in medkit_replay/commands/, one module each; register here.
cli.add_command(analyze)
cli.add_command(check)
cli.add_command(diff)
cli.add_command(explain)
cli.add_command(fleet)
cli.add_command(follow)
cli.add_command(serve)
cli.add_command(sweep)
cli.add_command(suggest_rules)
cli.add_command(validate)


if __name__ == "__main__":
    run()
