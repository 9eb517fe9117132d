"""Budget verdicts for GitHub Actions: workflow-command annotations and a step-summary page.

Every failed rule becomes ``::error file=BUDGET,line=N,title=...::message`` (the annotation sits
on the budget's rule; the title names the run), every replay warning ``::warning``. Recorded
text is made printable (no control characters: a line break in it is a space, ESC an escape),
then escaped as the Actions runner requires (``%``, CR, LF; in properties also ``:`` and ``,``),
so it can neither end a command nor start another, nor recolour the log. The Markdown summary
escapes Markdown and HTML in everything that comes from a recording, a config or a path.
"""

from __future__ import annotations

import html
import string
from typing import TYPE_CHECKING

from medkit_replay.model import read_in_part
from medkit_replay.text import WARNING_CAP, clip, printable

if TYPE_CHECKING:
    from collections.abc import Sequence

    from medkit_replay.checks.evaluate import CheckRun, Verdict

MAX_OFFENDERS = 20
"""Offending faults listed per rule in an annotation or a summary cell."""
_MARKDOWN_PUNCTUATION = frozenset(string.punctuation) - set("&<>\"'")


def escape_data(text: str) -> str:
    """A workflow command's message: ``%``, ``\\r`` and ``\\n`` percent-encoded."""
    return text.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")


def escape_property(text: str) -> str:
    """A workflow command's property value: as a message, and ``:`` and ``,`` encoded too."""
    return escape_data(text).replace(":", "%3A").replace(",", "%2C")


def markdown(text: str) -> str:
    """Literal text in Markdown: one line, HTML characters as entities, every other ASCII
    punctuation character backslash-escaped (no emphasis, links, tables, emoji, mentions)."""
    out: list[str] = []
    for char in printable(text):
        if char in "&<>\"'":
            out.append(html.escape(char, quote=True))
        elif char in _MARKDOWN_PUNCTUATION:
            out.append("\\" + char)
        else:
            out.append(char)
    return "".join(out)


def _offender_lines(verdict: Verdict) -> list[str]:
    lines = [o.text() for o in verdict.offenders[:MAX_OFFENDERS]]
    hidden = len(verdict.offenders) - MAX_OFFENDERS
    if hidden > 0:
        lines.append(f"... and {hidden} more")
    return lines


def workflow_commands(runs: Sequence[CheckRun]) -> list[str]:
    """The annotation lines, one command per line, in run and rule order."""
    commands: list[str] = []
    for run in runs:
        if run.error is not None:
            why = "nothing replayed" if run.empty else "recording cannot be read"
            title = escape_property(printable(f"{why} ({run.label})"))
            commands.append(f"::error title={title}::{escape_data(printable(run.error))}")
        for verdict in run.failures:
            rule = verdict.rule
            where = f"file={escape_property(run.budget.path)}"
            if rule.line is not None:
                where += f",line={rule.line}"
            title = escape_property(printable(f"fault budget exceeded: {rule.name} ({run.label})"))
            lines = [printable(line) for line in (verdict.message, *_offender_lines(verdict))]
            commands.append(f"::error {where},title={title}::{escape_data(chr(10).join(lines))}")
        title = escape_property(printable(f"recording read only in part ({run.label})"))
        for line in run.damage:
            commands.append(f"::error title={title}::{escape_data(printable(line))}")
        for loss in () if run.damage else run.losses:
            line = printable(read_in_part(loss))
            commands.append(f"::warning title={title}::{escape_data(line)}")
        for warning in run.warnings:
            title = escape_property(printable(f"medkit-replay warning ({run.label})"))
            shown = printable(clip(warning, WARNING_CAP))
            commands.append(f"::warning title={title}::{escape_data(shown)}")
    return commands


def _cell(verdict: Verdict) -> str:
    parts = [markdown(verdict.message)]
    parts += [f"• {markdown(line)}" for line in _offender_lines(verdict)]
    return "<br>".join(parts)


def step_summary(runs: Sequence[CheckRun]) -> str:
    """The Markdown page appended to ``$GITHUB_STEP_SUMMARY``: a verdict table per run."""
    held = all(run.passed for run in runs)
    unreadable = any(run.error is not None and not run.empty for run in runs)
    empty = any(run.empty for run in runs)
    budget = runs[0].budget if runs else None
    headline = "budget exceeded ❌"
    if unreadable or empty:
        headline = "a recording cannot be read ❌" if unreadable else "nothing replayed ❌"
    elif not any(run.failures for run in runs):
        headline = "a recording was read only in part (--strict) ❌"
    lines = ["## medkit-replay check: " + ("budget holds ✅" if held else headline), ""]
    if budget is not None:
        lines += [f"Budget: {markdown(budget.title)} ({markdown(budget.path)})", ""]
    for run in runs:
        if run.error is not None:
            lines += [
                f"### ❌ {markdown(run.label)}: "
                + ("nothing replayed" if run.empty else "cannot be read"),
                "",
                f"- {markdown(run.error)}",
                *(f"- ⚠️ {markdown(clip(w, WARNING_CAP))}" for w in run.warnings),
                "",
            ]
            continue
        failed = len(run.failures)
        state = f"{failed} of {len(run.verdicts)} rules failed" if failed else "all rules passed"
        lines += [
            f"### {'✅' if run.passed else '❌'} {markdown(run.label)}: {state}",
            "",
            "| | rule | verdict |",
            "| --- | --- | --- |",
        ]
        for verdict in run.verdicts:
            mark = "✅ pass" if verdict.passed else "❌ **fail**"
            lines.append(f"| {mark} | {markdown(verdict.rule.name)} | {_cell(verdict)} |")
        lines.append("")
        lost = [f"- ❌ {markdown(line)}" for line in run.damage] or [
            f"- ⚠️ {markdown(read_in_part(loss))}" for loss in run.losses
        ]
        lines += [*lost, ""] if lost else []
        if run.warnings:
            lines += [f"- ⚠️ {markdown(clip(w, WARNING_CAP))}" for w in run.warnings]
            lines.append("")
    return "\n".join(lines) + "\n"
