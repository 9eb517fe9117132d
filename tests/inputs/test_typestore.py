"""Definitions from recordings and bundled ros2_medkit_msgs, turned into rosbags decoders.

Pure: definitions are strings here, payloads are serialised with the bundled store.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from medkit_replay.inputs.typestore import DecodeError, make_decoder
from medkit_replay.msgdefs import (
    Definition,
    DefinitionError,
    base_typestore,
    bundled_types,
    types_from_definition,
)
from tests.inputs.builders import INTERFACES, TS, diag, report_fault

RULE = "=" * 80


def test_bundled_medkit_types_include_service_parts() -> None:
    types = bundled_types()
    for srv in ("ReportFault", "ClearFault", "ListFaults", "GetFault"):
        for part in ("_Request", "_Response", "_Event"):
            assert f"ros2_medkit_msgs/srv/{srv}{part}" in types
    event_fields = [name for name, _ in types["ros2_medkit_msgs/srv/ReportFault_Event"][1]]
    assert event_fields == ["info", "request", "response"]
    request = dict(types["ros2_medkit_msgs/srv/ReportFault_Request"][1])
    assert set(request) == {"fault_code", "event_type", "severity", "description", "source_id"}
    # relative names inside a .srv point at the package's msg folder, as in ROS 2
    response = dict(types["ros2_medkit_msgs/srv/GetFault_Response"][1])
    assert response["fault"][1] == "ros2_medkit_msgs/msg/Fault"
    assert "ros2_medkit_msgs/msg/FaultEvent" in base_typestore().fielddefs


def test_srv_text_definition_yields_the_event_type() -> None:
    text = (INTERFACES / "ros2_medkit_msgs" / "srv" / "ReportFault.srv").read_text()
    types = types_from_definition(
        "ros2_medkit_msgs/srv/ReportFault_Event", Definition("ros2msg", text)
    )
    assert {"_Request", "_Response", "_Event"} == {
        k.removeprefix("ros2_medkit_msgs/srv/ReportFault") for k in types
    }


def test_ros2msg_with_dependency_sections_and_old_names() -> None:
    text = f"Inner a\nint32 b\n{RULE}\nMSG: pkg/Inner\nstring s\n"
    types = types_from_definition("pkg/msg/Outer", Definition("ros2msg", text))
    assert set(types) == {"pkg/msg/Outer", "pkg/msg/Inner"}


def test_bad_definitions_raise_definition_error() -> None:
    with pytest.raises(DefinitionError, match="not supported"):
        types_from_definition("a/msg/B", Definition("jsonschema", "{}"))
    with pytest.raises(DefinitionError, match="cannot be parsed"):
        types_from_definition("a/msg/B", Definition("ros2msg", "int32[ x"))


def test_recorded_definition_is_used_first() -> None:
    rec = diag(5)
    text = TS.generate_msgdef(rec.msgtype, ros_version=2)[0]
    decoder, problem = make_decoder(rec.msgtype, Definition("ros2msg", text), pytest.fail)
    assert problem is None
    msg = decoder.decode(TS.serialize_cdr(rec.msg, rec.msgtype))
    assert msg.status[0].name == "motor"  # type: ignore[attr-defined]


def test_definition_that_does_not_fit_falls_back_to_bundled_once() -> None:
    notes: list[str] = []
    rec = report_fault(7)
    decoder, problem = make_decoder(
        rec.msgtype, Definition("ros2msg", "string only\n---\nbool accepted\n"), notes.append
    )
    assert problem is None
    raw = TS.serialize_cdr(rec.msg, rec.msgtype)
    for _ in range(3):
        assert decoder.decode(raw).request[0].fault_code == "MOTOR_HOT"  # type: ignore[attr-defined]
    assert notes == ["recorded definition does not fit the data; used the bundled definition"]


def test_unparseable_definition_reports_problem_and_uses_bundled() -> None:
    rec = diag(1)
    decoder, problem = make_decoder(
        rec.msgtype, Definition("ros2msg", "Missing thing\n"), pytest.fail
    )
    assert problem is not None
    assert "does not define" in problem
    assert decoder.decode(TS.serialize_cdr(rec.msg, rec.msgtype)) is not None


def test_unknown_type_without_definition_raises() -> None:
    with pytest.raises(DefinitionError, match="no usable definition of x_msgs/msg/Y"):
        make_decoder("x_msgs/msg/Y", Definition("", ""), pytest.fail)


def test_corrupt_payload_raises_decode_error_without_huge_allocation() -> None:
    rec = diag(1)
    raw = bytearray(TS.serialize_cdr(rec.msg, rec.msgtype))
    # encapsulation 4, stamp 8, frame_id "" as length 4 + NUL + padding 3: then the status count
    assert raw[20:24] == b"\x01\x00\x00\x00"
    raw[20:24] = b"\xff\xff\xff\xff"
    decoder, _ = make_decoder(rec.msgtype, Definition("", ""), pytest.fail)
    with pytest.raises(DecodeError, match="sequence length"):
        decoder.decode(bytes(raw))
    with pytest.raises(DecodeError):
        decoder.decode(b"\x00\x01\x00\x00" + b"\xff" * 16)
    with pytest.raises(DecodeError):
        decoder.decode(b"")


def test_reference_types_match_the_store_they_stand_in_for() -> None:
    """The bundled DiagnosticArray family lays out as rosbags' Jazzy store does: checking a
    recording against it decides as checking against the store would."""
    from medkit_replay.inputs.cdr.diagnostics import DIAGNOSTIC_ARRAY, layout  # noqa: PLC0415
    from medkit_replay.msgdefs import reference_types  # noqa: PLC0415

    assert layout(reference_types(), DIAGNOSTIC_ARRAY) == layout(
        base_typestore().fielddefs, DIAGNOSTIC_ARRAY
    )


def test_a_recording_with_its_definitions_needs_no_rosbags_store(tmp_path: Path) -> None:
    """Building rosbags' Jazzy store costs a tenth of a second of every command: a recording
    that carries the definitions it uses (every sample bag does) is replayed without it."""
    sample = Path(__file__).resolve().parents[2] / "sample_bags" / "nav2_mission_mcap"
    script = (
        "import sys; from pathlib import Path; from medkit_replay.pipeline import replay; "
        f"r = replay([Path({str(sample)!r})], []); "
        "assert r.faults, 'no faults'; "
        "print(sorted(m for m in sys.modules if m.startswith('rosbags.typesys.stores.')))"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True, cwd=tmp_path
    )
    stores = done.stdout.strip()
    assert "ros2_jazzy" not in stores, stores


def test_bundled_definition_is_built_only_when_the_recorded_one_refuses() -> None:
    rec = diag(5)
    text = TS.generate_msgdef(rec.msgtype, ros_version=2)[0]
    decoder, problem = make_decoder(rec.msgtype, Definition("ros2msg", text), pytest.fail)
    assert problem is None
    for _ in range(3):
        decoder.decode(TS.serialize_cdr(rec.msg, rec.msgtype))
    # It fit: the bundled candidate was never built.
    assert [c[0] for c in decoder._candidates] == ["recorded definition"]
