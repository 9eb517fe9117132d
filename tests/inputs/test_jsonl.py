"""JSON-lines scripts: every accepted form, and one clear error per malformed line."""

from __future__ import annotations

import io

import pytest

from medkit_replay.errors import InputError
from medkit_replay.inputs.jsonl import iter_script
from medkit_replay.model import ClearRequest, ReportRequest


def parse(text: str) -> list[ReportRequest | ClearRequest]:
    return [line.request for line in iter_script(io.BytesIO(text.encode()), "s.jsonl")]


def test_report_and_clear_lines_with_defaults() -> None:
    requests = parse(
        "# comment\n\n"
        '{"t_ns": 1, "op": "report", "fault_code": "A", "event_type": "FAILED", '
        '"source_id": "/n"}\n'
        '{"t_ns": 2, "op": "report", "fault_code": "A", "event_type": 1, "severity": 3, '
        '"description": "d", "source_id": "/n"}\n'
        '{"t_ns": 2, "op": "clear", "fault_code": "A"}\n'
    )
    assert requests == [
        ReportRequest(
            t_ns=1, fault_code="A", event_type=0, severity=0, description="", source_id="/n"
        ),
        ReportRequest(
            t_ns=2, fault_code="A", event_type=1, severity=3, description="d", source_id="/n"
        ),
        ClearRequest(t_ns=2, fault_code="A", skip_correlation_auto_clear=False),
    ]


def test_out_of_set_event_type_reaches_the_manager() -> None:
    # 7 is a valid uint8; the manager rejects it with upstream's reason, not the parser.
    (request,) = parse(
        '{"t_ns": 1, "op": "report", "fault_code": "A", "event_type": 7, "source_id": "/n"}\n'
    )
    assert isinstance(request, ReportRequest) and request.event_type == 7


@pytest.mark.parametrize(
    ("line", "problem"),
    [
        ("not json", "invalid JSON"),
        ("[1, 2]", "expected a JSON object"),
        ('{"t_ns": 1, "op": "explode", "fault_code": "A"}', "unknown op 'explode'"),
        ('{"op": "clear", "fault_code": "A"}', "missing 't_ns'"),
        ('{"t_ns": -1, "op": "clear", "fault_code": "A"}', "'t_ns' must be in >= 0"),
        ('{"t_ns": 1.5, "op": "clear", "fault_code": "A"}', "'t_ns' must be an integer"),
        ('{"t_ns": 1, "op": "clear"}', "missing 'fault_code'"),
        (
            '{"t_ns": 1, "op": "report", "fault_code": "A", "event_type": "BROKEN", '
            '"source_id": "/n"}',
            "'event_type' must be FAILED, PASSED",
        ),
        (
            '{"t_ns": 1, "op": "report", "fault_code": "A", "event_type": 0, "severity": 300, '
            '"source_id": "/n"}',
            "'severity' must be in 0..255",
        ),
        ('{"t_ns": 1, "op": "report", "fault_code": "A", "event_type": 0}', "missing 'source_id'"),
        (
            '{"t_ns": 1, "op": "report", "fault_code": "A", "event_type": 0, "source_id": "/n", '
            '"severty": 2}',
            "unknown key(s) ['severty']",
        ),
        (
            '{"t_ns": 1, "op": "clear", "fault_code": "A", "skip_correlation_auto_clear": 1}',
            "'skip_correlation_auto_clear' must be true or false",
        ),
    ],
)
def test_malformed_line_names_file_and_line(line: str, problem: str) -> None:
    with pytest.raises(InputError) as info:
        parse("# header\n" + line + "\n")
    assert info.value.path == "s.jsonl"
    assert info.value.line == 2
    assert problem in info.value.problem
    assert str(info.value).startswith("s.jsonl:2: ")


def test_decreasing_time_is_an_error_at_its_line() -> None:
    with pytest.raises(InputError, match=r"^s\.jsonl:3: t_ns 5 is earlier"):
        parse(
            '{"t_ns": 9, "op": "clear", "fault_code": "A"}\n'
            '{"t_ns": 9, "op": "clear", "fault_code": "A"}\n'
            '{"t_ns": 5, "op": "clear", "fault_code": "A"}\n'
        )


def test_overlong_line_is_refused_without_reading_it_whole() -> None:
    with pytest.raises(InputError, match="longer than"):
        parse('{"t_ns": 1, "op": "clear", "fault_code": "' + "A" * (1 << 21) + '"}\n')
