"""Budget verdicts as JUnit XML: one testsuite per run, one testcase per rule.

A failed rule is a ``<failure>`` whose ``message`` names the offending faults on one line and
whose text lists them one per line. A run whose recording cannot be read, or in which nothing
was replayed, has one testcase with an ``<error>`` saying why. Written with xml.etree; text XML
cannot hold is escaped; the file is written through a temporary file renamed into place.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import TYPE_CHECKING

from medkit_replay.model import total_loss
from medkit_replay.outputs.atomic import write_bytes_atomic
from medkit_replay.result import RELEASE_PARAMETER
from medkit_replay.text import xml_text
from medkit_replay.version import __version__

if TYPE_CHECKING:
    from collections.abc import Sequence
    from pathlib import Path

    from medkit_replay.checks.evaluate import CheckRun, Verdict

MAX_IN_MESSAGE = 20
"""Offending faults named in a failure's one-line message; its text lists every one."""
UNREADABLE_CASE = "the recording can be read"
"""The testcase of a run whose recording could not be replayed."""
EMPTY_CASE = "something was replayed"
"""The testcase of a run in which nothing reached the fault manager (``--allow-empty``: none)."""
WHOLE_CASE = "the recording is read whole"
"""The testcase ``--strict`` adds to each run: it fails when damage cost anything."""


def failure_message(verdict: Verdict) -> str:
    """The verdict's line and the offending faults, on one line."""
    offenders = [o.text() for o in verdict.offenders[:MAX_IN_MESSAGE]]
    hidden = len(verdict.offenders) - MAX_IN_MESSAGE
    if hidden > 0:
        offenders.append(f"and {hidden} more")
    return verdict.message + (": " + "; ".join(offenders) if offenders else "")


def _testcase(suite: ET.Element, run: CheckRun, verdict: Verdict) -> None:
    rule = verdict.rule
    case = ET.SubElement(
        suite,
        "testcase",
        {
            "name": xml_text(rule.name),
            "classname": xml_text(run.label),
            "file": xml_text(run.budget.path),
        },
    )
    if rule.line is not None:
        case.set("line", str(rule.line))
    if verdict.passed:
        ET.SubElement(case, "system-out").text = xml_text(verdict.message)
        return
    failure = ET.SubElement(
        case, "failure", {"message": xml_text(failure_message(verdict)), "type": rule.kind}
    )
    lines = [verdict.message, *(f"- {o.text()}" for o in verdict.offenders)]
    failure.text = xml_text("\n".join(lines))


def _unreadable_case(suite: ET.Element, run: CheckRun, error: str) -> None:
    case = ET.SubElement(
        suite,
        "testcase",
        {
            "name": EMPTY_CASE if run.empty else UNREADABLE_CASE,
            "classname": xml_text(run.label),
            "file": xml_text(run.inputs[0]),
        },
    )
    kind = "empty" if run.empty else "unreadable"
    ET.SubElement(case, "error", {"message": xml_text(error), "type": kind}).text = xml_text(error)


def _whole_case(suite: ET.Element, run: CheckRun) -> None:
    case = ET.SubElement(
        suite,
        "testcase",
        {"name": WHOLE_CASE, "classname": xml_text(run.label), "file": xml_text(run.inputs[0])},
    )
    if not run.damage:
        ET.SubElement(case, "system-out").text = "nothing was lost to damage"
        return
    message = "; ".join(run.damage)
    ET.SubElement(
        case, "failure", {"message": xml_text(message), "type": "damage"}
    ).text = xml_text("\n".join(run.damage))


def _loss_properties(run: CheckRun) -> list[tuple[str, str]]:
    """What damage cost the run, in total: messages, bytes, bag time span (ns), or unknown."""
    if not run.losses:
        return []
    lost = total_loss(run.losses)

    def amount(value: int | None, more: bool) -> str:
        return "unknown" if value is None else ("at least " if more else "") + str(value)

    span = "unknown"
    if lost.start_ns is not None and lost.end_ns is not None:
        span = f"{lost.start_ns}..{lost.end_ns}"
    return [
        ("medkit_replay.lost_messages", amount(lost.messages, lost.more_messages)),
        ("medkit_replay.lost_bytes", amount(lost.bytes, lost.more_bytes)),
        ("medkit_replay.lost_span_ns", span),
    ]


def _strict_case(run: CheckRun) -> int:
    """1 when ``--strict`` adds its testcase to a replayed run, else 0."""
    return int(run.strict and run.error is None)


def junit_element(runs: Sequence[CheckRun]) -> ET.Element:
    """The JUnit document of a check: its ``testsuites`` root element, indented."""
    tests = sum(len(r.verdicts) + _strict_case(r) if r.error is None else 1 for r in runs)
    failures = sum(len(r.failures) + bool(r.damage) for r in runs)
    errors = sum(1 for r in runs if r.error is not None)
    root = ET.Element(
        "testsuites",
        {
            "name": "medkit-replay check",
            "tests": str(tests),
            "failures": str(failures),
            "errors": str(errors),
        },
    )
    for run in runs:
        suite = ET.SubElement(
            root,
            "testsuite",
            {
                "name": xml_text(run.label),
                "tests": str(len(run.verdicts) + _strict_case(run) if run.error is None else 1),
                "failures": str(len(run.failures) + bool(run.damage)),
                "errors": "0" if run.error is None else "1",
                "skipped": "0",
            },
        )
        properties = ET.SubElement(suite, "properties")
        entries = [
            ("budget", run.budget.path),
            ("medkit_replay_version", __version__),
            (RELEASE_PARAMETER, run.upstream_release),
        ]
        entries += [("input", path) for path in run.inputs]
        entries += _loss_properties(run)
        for name, value in entries:
            ET.SubElement(properties, "property", {"name": name, "value": xml_text(value)})
        if run.error is not None:
            _unreadable_case(suite, run, run.error)
        for verdict in run.verdicts:
            _testcase(suite, run, verdict)
        if _strict_case(run):
            _whole_case(suite, run)
        if run.warnings:
            ET.SubElement(suite, "system-err").text = xml_text("\n".join(run.warnings))
    ET.indent(root)
    return root


def write_junit(runs: Sequence[CheckRun], path: Path) -> None:
    """Write the JUnit XML file (UTF-8, with an XML declaration), whole or not at all."""
    text = ET.tostring(junit_element(runs), encoding="utf-8", xml_declaration=True)
    write_bytes_atomic(path, text)
