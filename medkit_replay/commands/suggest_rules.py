"""``medkit-replay suggest-rules INPUT...``: correlation rules learned from a fleet of recordings.

Thin: replays the inputs (:mod:`medkit_replay.tuning.observe`, in worker processes as a fleet
does), mines them (:mod:`medkit_replay.tuning.suggest`), writes the correlation file
(:mod:`medkit_replay.tuning.rules_file`) and, with ``--validate``, replays them with it.
"""

from __future__ import annotations

import sys
import tempfile
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, TextIO

import click

from medkit_replay.commands import (
    JOBS_OPTION,
    config_option,
    count_option,
    input_argument,
    local_paths,
    path_option,
    say_written,
    writing,
)
from medkit_replay.commands.streams import standard_output
from medkit_replay.errors import MedkitReplayError
from medkit_replay.outputs.console import echo, warn
from medkit_replay.text import printable
from medkit_replay.tuning.suggest import (
    DEFAULT_MAX_PAIRS,
    DEFAULT_MIN_CONFIDENCE,
    DEFAULT_MIN_SUPPORT,
    DEFAULT_WINDOW_MS,
    Suggestion,
    pairs_of,
    suggest,
)

if TYPE_CHECKING:
    from medkit_replay.tuning.observe import Checked, Observed

MAX_LISTED = 20
"""Runs listed per finding in the validation report."""


@click.command("suggest-rules")
@input_argument("inputs")
@config_option("ROS 2 parameter file every input is replayed with (repeatable).")
@count_option(
    "--window-ms",
    default=DEFAULT_WINDOW_MS,
    most=60000,
    show_default=True,
    help="A symptom confirms at most this long after its root; a burst's codes this close.",
)
@count_option(
    "--min-support",
    default=DEFAULT_MIN_SUPPORT,
    show_default=True,
    help="Runs a pattern must be seen in to be proposed.",
)
@click.option(
    "--min-confidence",
    type=click.FloatRange(min=0.0, max=1.0),
    default=DEFAULT_MIN_CONFIDENCE,
    show_default=True,
    help="Share of the runs with the later code that the pattern must explain.",
)
@count_option(
    "--max-pairs",
    default=DEFAULT_MAX_PAIRS,
    show_default=True,
    help="Pairs of codes weighed at most; past it, only the codes confirmed in the most runs are "
    "paired (said in a warning).",
)
@path_option(
    "--out", "out_path", help="Write the correlation file here (default: standard output)."
)
@click.option(
    "--validate",
    is_flag=True,
    help="Replay the inputs with the proposed rules: events muted, and mutes without a root.",
)
@JOBS_OPTION
def suggest_rules(
    inputs: tuple[Path | str, ...],
    configs: tuple[Path, ...],
    window_ms: int,
    min_support: int,
    min_confidence: float,
    max_pairs: int,
    out_path: Path | None,
    validate: bool,
    jobs: int | None,
) -> None:
    """Propose correlation rules from how faults confirm across INPUT... (a fleet).

    A hierarchical rule when a code confirms within --window-ms after another in at least
    --min-support runs and --min-confidence of the runs it confirmed in; an auto-cluster rule
    for codes that confirm together as often. The file is in upstream's correlation schema,
    each rule with its support and confidence as comments: point
    fault_manager.correlation.config_file at it (try it with ``sweep`` first). Exit status: 0
    done, also when a recording cannot be read; 2 bad usage, no recording found, an invalid
    config.

    \b
    Examples:
      medkit-replay suggest-rules missions/ --config robot.yaml --out correlation.yaml
      medkit-replay suggest-rules missions/ --window-ms 1000 --min-support 5 --validate
    """
    from medkit_replay.config.referenced import config_files  # noqa: PLC0415
    from medkit_replay.fleet.discover import discover_some  # noqa: PLC0415
    from medkit_replay.fleet.workers import run_jobs  # noqa: PLC0415
    from medkit_replay.outputs.atomic import refuse_overlap, write_text_atomic  # noqa: PLC0415
    from medkit_replay.tuning.observe import failed_observation, observe  # noqa: PLC0415
    from medkit_replay.tuning.rules_file import rules_yaml  # noqa: PLC0415

    config_paths = config_files(configs)
    refuse_overlap([*local_paths(inputs), *config_paths], [("--out", out_path)] if out_path else [])
    recordings = discover_some(inputs)
    jobs_list = [(p if isinstance(p, str) else str(p.absolute()), str(p)) for p in recordings]
    base = tuple(str(Path(c).absolute()) for c in configs)
    observed: list[Observed | None] = [None] * len(recordings)

    def keep(index: int, run: Observed) -> None:
        observed[index] = run

    run_jobs(jobs_list, partial(observe, configs=base), failed_observation, jobs=jobs, on_done=keep)
    runs = [run for run in observed if run is not None]
    good = [run.confirmations for run in runs if run.ok]
    suggestion = suggest(good, window_ms, min_support, min_confidence, max_pairs)
    paired = suggestion.paired
    if paired.dropped:
        warn(
            f"{paired.candidates:,} codes confirmed in at least {min_support} runs make "
            f"{pairs_of(paired.candidates):,} pairs, more than --max-pairs {max_pairs:,}: only "
            f"the {paired.kept:,} confirmed in the most runs were paired ({paired.dropped:,} "
            "pairs dropped; raise --max-pairs to weigh them)"
        )
    text = rules_yaml(suggestion)
    report = sys.stdout if out_path is not None else sys.stderr
    if out_path is not None:
        with writing("the rules", out_path):
            write_text_atomic(out_path, text)
        say_written([out_path])
    else:
        with standard_output("the rules"):
            echo(text, sys.stdout)
    with standard_output("the findings"):
        _found(suggestion, runs, report)
    if validate:
        checked = _validate(text, jobs_list, base, jobs)
        with standard_output("the validation"):
            _validation(checked, report)


def _found(suggestion: Suggestion, runs: list[Observed], stream: TextIO) -> None:
    failed = [run for run in runs if not run.ok]
    echo(
        f"suggest-rules: {len(runs) - len(failed):,} run(s) replayed"
        + (f", {len(failed):,} failed" if failed else "")
        + f"; {len(suggestion.cascades):,} hierarchical and {len(suggestion.bursts):,} "
        f"auto-cluster rule(s) proposed (window {suggestion.window_ms} ms, min support "
        f"{suggestion.min_support}, min confidence {suggestion.min_confidence:g})\n",
        stream,
    )
    for cascade in suggestion.cascades:
        symptoms = ", ".join(s.code for s in cascade.symptoms)
        echo(printable(f"  cascade: {cascade.root} -> {symptoms}") + "\n", stream)
    for burst in suggestion.bursts:
        echo(printable(f"  burst: {', '.join(burst.codes)}") + "\n", stream)
    for run in failed[:MAX_LISTED]:
        echo(printable(f"  not replayed: {run.error}") + "\n", stream)


def _validate(
    text: str, jobs_list: list[tuple[str, str]], base: tuple[str, ...], jobs: int | None
) -> list[Checked]:
    """Replay every input with the rules switched on (a temporary correlation file and a
    parameter file naming it, layered last)."""
    from medkit_replay.config.correlation_file import load_correlation  # noqa: PLC0415
    from medkit_replay.fleet.workers import run_jobs  # noqa: PLC0415
    from medkit_replay.tuning.observe import check, failed_check  # noqa: PLC0415

    with tempfile.TemporaryDirectory(prefix="medkit-replay-rules-") as scratch:
        rules = Path(scratch) / "correlation.yaml"
        rules.write_text(text, encoding="utf-8")
        loaded = load_correlation(rules)
        if loaded.config is None:  # cannot happen: the tests load every file we write
            raise MedkitReplayError("the proposed rules do not load: " + "; ".join(loaded.warnings))
        params = Path(scratch) / "params.yaml"
        params.write_text(
            "fault_manager:\n  ros__parameters:\n    correlation:\n"
            f"      config_file: {rules.name}\n",
            encoding="utf-8",
        )
        checked: list[Checked | None] = [None] * len(jobs_list)

        def keep(index: int, run: Checked) -> None:
            checked[index] = run

        task = partial(check, configs=(*base, str(params)))
        run_jobs(jobs_list, task, failed_check, jobs=jobs, on_done=keep)
    return [run for run in checked if run is not None]


def _validation(checked: list[Checked], stream: TextIO) -> None:
    ok = [run for run in checked if run.ok]
    muted = sum(run.muted_events for run in ok)
    rootless = [run for run in ok if run.rootless]
    echo(
        f"validation: {muted:,} event(s) muted over {len(ok):,} run(s); "
        f"{sum(len(r.rootless) for r in rootless):,} fault(s) muted although their root never "
        f"confirmed, in {len(rootless):,} run(s)\n",
        stream,
    )
    for run in ok[:MAX_LISTED]:
        faults = len(run.muted)
        echo(
            printable(
                f"  {run.label}: {run.muted_events:,} event(s) muted, {faults:,} fault(s) muted"
            )
            + "\n",
            stream,
        )
    for run in rootless[:MAX_LISTED]:
        for code, root, rule in run.rootless:
            echo(
                printable(
                    f"  root never confirmed: {run.label}: {code} muted by {rule} "
                    f"(root {root} reported, never CONFIRMED)"
                )
                + "\n",
                stream,
            )
    for run in checked:
        if not run.ok:
            echo(printable(f"  not replayed: {run.error}") + "\n", stream)
