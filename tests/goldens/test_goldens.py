"""Every golden case's JSON report is byte-identical to the one recorded before a refactoring."""

from __future__ import annotations

import json

import pytest

from tests.goldens.cases import GOLDENS, cases
from tests.goldens.record import report_digest

RECORDED: dict[str, str] = json.loads(GOLDENS.read_text(encoding="utf-8"))


def test_every_case_has_a_golden() -> None:
    assert sorted(RECORDED) == sorted(case for case, _, _ in cases())


@pytest.mark.parametrize(("case", "inputs", "configs"), cases(), ids=str)
def test_report_is_unchanged(case: str, inputs: list[str], configs: list[str]) -> None:
    assert report_digest(inputs, configs) == RECORDED[case]
