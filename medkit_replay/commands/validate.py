"""``medkit-replay validate FILE...``: check config files without a recording, as a replay would
read them, one line per finding.

Thin: the kind of each file is told by config.kinds, the findings come from the replay's own
readers (config.validation, checks.budget_file).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import click

from medkit_replay.commands.streams import standard_output

if TYPE_CHECKING:
    from medkit_replay.config.validation import Finding
    from medkit_replay.releases import Release


def _release(_ctx: click.Context, _param: click.Parameter, value: str | None) -> Release | None:
    from medkit_replay.releases import release_named  # noqa: PLC0415

    if value is None:
        return None
    try:
        return release_named(value)
    except KeyError as err:
        raise click.BadParameter(str(err.args[0])) from None


@click.command()
@click.argument(
    "files", nargs=-1, required=True, metavar="FILE...", type=click.Path(path_type=Path)
)
@click.option(
    "--release",
    "release",
    type=str,
    default=None,
    callback=_release,
    metavar="RELEASE",
    help="Check parameter files against this upstream release (default: each file's own "
    "medkit_replay.upstream_release, else the newest).",
)
@click.option(
    "--json",
    "as_json",
    is_flag=True,
    help="Write the findings as a JSON list of records (file, line, severity, kind, message, "
    "suggestion) instead of lines.",
)
@click.pass_context
def validate(
    ctx: click.Context, files: tuple[Path, ...], release: Release | None, as_json: bool
) -> None:
    """Check config files without a recording: parameter files (with the correlation,
    entity-threshold and snapshot files they name), correlation, entity-threshold and
    snapshot files, budgets and --graph files.

    Each FILE's kind is told from its content and said; each is read alone, by the readers
    a replay runs. One line per finding, FILE:LINE first. Exit status: 0 clean; 1 warnings
    only (unknown keys, values upstream replaces or clamps); 2 bad usage, or a file that
    cannot be read or used (refused, or ignored whole by upstream).

    \b
    Examples:
      medkit-replay validate rules/nav2/*.yaml rules/budgets/*.yaml
      medkit-replay validate robot_params.yaml --release 0.6.0 --json
    """
    from medkit_replay.config.validation import validate_files  # noqa: PLC0415

    findings = validate_files(files, release, _budget_findings)
    with standard_output("the findings"):
        if as_json:
            records = ",\n".join(
                "  " + json.dumps(f.to_json(), ensure_ascii=True) for f in findings
            )
            sys.stdout.write(f"[\n{records}\n]\n" if records else "[]\n")
        else:
            sys.stdout.write("".join(f.render() + "\n" for f in findings))
    severities = {f.severity for f in findings}
    if "error" in severities:
        ctx.exit(2)
    if "warning" in severities:
        ctx.exit(1)


def _budget_findings(path: Path) -> list[Finding]:
    """A budget read as check reads it (the checks layer, which config does not import)."""
    from medkit_replay.checks.budget_file import load_budget  # noqa: PLC0415
    from medkit_replay.config.validation import strict_findings  # noqa: PLC0415

    return strict_findings(path, "budget", load_budget)
