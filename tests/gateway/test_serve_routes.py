"""The served nav2 mission through the gateway's routes: shapes, moments, errors, the stream."""

from __future__ import annotations

import dataclasses
import http.client
import json
import time
from typing import TYPE_CHECKING

import pytest

from medkit_replay.captures import SnapshotCapture, SnapshotTopic
from medkit_replay.gateway.app import build_app
from medkit_replay.gateway.stream import EventStream
from medkit_replay.model import EVENT_ROWS, FaultEvent
from medkit_replay.spool import Spool
from tests.gateway.schemas import response_schema, validate
from tests.gateway.support import MISSION, NAV2, running, seconds, serve_replay

if TYPE_CHECKING:
    from collections.abc import Iterator
    from pathlib import Path

    import httpx

    from medkit_replay.gateway.recording import ServedRecording

KINDS = ("areas", "components", "apps", "functions")


@pytest.fixture(scope="module")
def served() -> ServedRecording:
    return serve_replay([MISSION], [NAV2])


@pytest.fixture(scope="module")
def client(served: ServedRecording) -> Iterator[httpx.Client]:
    with running(build_app(served, speed=0)) as client:
        yield client


def checked(client: httpx.Client, path: str, template: str | None = None) -> object:
    """GET ``path``: 200, JSON, and valid against the published schema of its route."""
    answer = client.get(path)
    assert answer.status_code == 200, (path, answer.text)
    assert answer.headers["content-type"].startswith("application/json")
    body = answer.json()
    schema = response_schema(template or path.split("?", maxsplit=1)[0], "get", "200")
    assert schema is not None, f"no published schema for {template or path}"
    validate(body, schema)
    return body


def test_root_version_health_and_the_recording(
    client: httpx.Client, served: ServedRecording
) -> None:
    checked(client, "/api/v1/", "/")
    checked(client, "/api/v1/version-info", "/version-info")
    checked(client, "/api/v1/health", "/health")
    facts = client.get("/api/v1/x-medkit/recording").json()
    assert facts["upstream_release"] == served.result.upstream_release
    assert facts["start_ns"] == served.origin_ns and facts["end_ns"] == served.end_ns
    assert [i["path"] for i in facts["inputs"]] == [str(MISSION)]


def test_every_entity_and_its_faults_have_the_published_shapes(client: httpx.Client) -> None:
    seen = 0
    for kind in KINDS:
        listing = checked(client, f"/api/v1/{kind}", f"/{kind}")
        assert isinstance(listing, dict)
        for item in listing["items"]:
            entity = f"/api/v1/{kind}/{item['id']}"
            singular = kind[:-1]
            checked(client, entity, f"/{kind}/{{{singular}_id}}")
            faults = checked(
                client, f"{entity}/faults?status=all", f"/{kind}/{{{singular}_id}}/faults"
            )
            assert isinstance(faults, dict)
            for fault in faults["items"]:
                checked(
                    client,
                    f"{entity}/faults/{fault['fault_code']}",
                    f"/{kind}/{{{singular}_id}}/faults/{{fault_code}}",
                )
                seen += 1
    assert seen  # the mission's reporting sources are entities whose faults are listed


def test_the_global_list_at_the_end_is_the_report(
    client: httpx.Client, served: ServedRecording
) -> None:
    body = checked(client, "/api/v1/faults?status=all", "/faults")
    assert isinstance(body, dict)
    muted = {m.fault_code for m in served.result.muted_faults}
    expected = [f.fault_code for f in served.result.faults if f.fault_code not in muted]
    assert [item["fault_code"] for item in body["items"]] == expected
    with_muted = client.get("/api/v1/faults?status=all&include_muted=true").json()
    assert [i["fault_code"] for i in with_muted["items"]] == [
        f.fault_code for f in served.result.faults
    ]


def test_any_moment_answers_the_state_the_transitions_left(
    client: httpx.Client, served: ServedRecording
) -> None:
    last: dict[tuple[str, int], str] = {}
    for transition in served.result.transitions:
        last[transition.fault_code, transition.t_ns] = transition.to_status
    muted_ever = {m.fault_code for m in served.result.muted_faults}
    checked_moments = 0
    for (code, t_ns), status in list(last.items())[::3]:
        at = seconds(served, t_ns)
        body = client.get(f"/api/v1/faults?status=all&include_muted=true&at={at}").json()
        found = {item["fault_code"]: item for item in body["items"]}
        assert found[code]["status"] == status, (code, at)
        prefixed = client.get(f"/at/{at}/api/v1/faults?status=all&include_muted=true").json()
        assert prefixed == body
        checked_moments += 1
        if code in muted_ever:
            continue
    assert checked_moments > 5
    # Before the first report nothing is known; a moment past the end is the end.
    assert client.get("/api/v1/faults?status=all&at=0").json()["items"] == []
    end = client.get("/api/v1/faults?status=all&at=1e9").json()
    assert end == client.get("/api/v1/faults?status=all").json()


def test_the_detail_at_a_moment_is_that_moment_s_fault(
    client: httpx.Client, served: ServedRecording
) -> None:
    transition = next(t for t in served.result.transitions if t.from_status is not None)
    history = served.history
    app = next(
        a["id"]
        for a in client.get("/api/v1/apps").json()["items"]
        if any(
            f["fault_code"] == transition.fault_code
            for f in client.get(f"/api/v1/apps/{a['id']}/faults?status=all").json()["items"]
        )
    )
    before = seconds(served, transition.t_ns - 1)
    body = client.get(f"/api/v1/apps/{app}/faults/{transition.fault_code}?at={before}").json()
    fault = history.fault_at(transition.fault_code, transition.t_ns - 1)
    assert fault is not None
    assert body["x-medkit"]["status_raw"] == fault.status == transition.from_status
    assert body["x-medkit"]["occurrence_count"] == fault.occurrence_count


def test_unknown_things_answer_404_with_a_generic_error(client: httpx.Client) -> None:
    app = client.get("/api/v1/apps").json()["items"][0]["id"]
    for path in (
        "/api/v1/apps/no_such_app",
        "/api/v1/apps/no_such_app/faults",
        f"/api/v1/apps/{app}/faults/NO_SUCH_CODE",
        f"/api/v1/apps/{app}/bulk-data/rosbags/no_such_recording",
        f"/api/v1/apps/{app}/bulk-data/no_such_category",
        "/api/v1/gadgets",
        "/api/v1/apps/x/y/z/w/v",
        "/nowhere",
    ):
        answer = client.get(path)
        assert answer.status_code == 404, path
        validate(answer.json(), "GenericError")


def test_writes_answer_405_with_a_generic_error(client: httpx.Client) -> None:
    app = client.get("/api/v1/apps").json()["items"][0]["id"]
    for method, path in (
        ("DELETE", "/api/v1/faults"),
        ("DELETE", f"/api/v1/apps/{app}/faults"),
        ("DELETE", f"/api/v1/apps/{app}/faults/ANY_CODE"),
        ("POST", f"/api/v1/apps/{app}/bulk-data/rosbags"),
        ("DELETE", f"/api/v1/apps/{app}/bulk-data/rosbags/any"),
        ("PUT", "/api/v1/apps"),
    ):
        answer = client.request(method, path)
        assert answer.status_code == 405, (method, path)
        validate(answer.json(), "GenericError")
        assert answer.headers["allow"] == "GET, HEAD"


def test_bad_parameters_answer_400(client: httpx.Client) -> None:
    for path in (
        "/api/v1/faults?status=bogus",
        "/api/v1/faults?at=soon",
        "/api/v1/faults?at=nan",
        "/at/inf/api/v1/faults",
    ):
        answer = client.get(path)
        assert answer.status_code == 400, path
        validate(answer.json(), "GenericError")


def raw_get(client: httpx.Client, path: str) -> tuple[int, bytes]:
    """GET ``path`` exactly as written (httpx would fold ``..`` segments before sending)."""
    connection = http.client.HTTPConnection(client.base_url.host, client.base_url.port)
    try:
        connection.request("GET", path)
        answer = connection.getresponse()
        return answer.status, answer.read()
    finally:
        connection.close()


def test_no_route_reaches_the_file_system(client: httpx.Client) -> None:
    app = client.get("/api/v1/apps").json()["items"][0]["id"]
    base = f"/api/v1/apps/{app}/bulk-data/rosbags/"
    for file_id in (
        "..%2F..%2F..%2F..%2Fetc%2Fpasswd",
        "%2Fetc%2Fpasswd",
        "..%5C..%5Cwindows",
        "%2e%2e",
        "metadata.yaml",
        "fault_X_1%00.mcap",
    ):
        status, body = raw_get(client, base + file_id)
        assert status == 404, file_id
        validate(json.loads(body), "GenericError")
        assert b"root:" not in body
    # Dot segments written out reach no file either: the route they leave is another route.
    for path in (base + "../../../../../../etc/passwd", base + "..", "/api/v1/../../etc/passwd"):
        status, body = raw_get(client, path)
        assert b"root:" not in body and status in (200, 404), path


def sse_frames(text: str) -> list[dict[str, str]]:
    frames = []
    for block in text.split("\n\n"):
        fields: dict[str, str] = {}
        for line in block.splitlines():
            if line.startswith(":"):
                continue
            name, _, value = line.partition(":")
            fields[name] = value.removeprefix(" ")
        if fields:
            frames.append(fields)
    return frames


def test_the_stream_is_the_report_s_events_in_order(
    client: httpx.Client, served: ServedRecording
) -> None:
    answer = client.get("/api/v1/faults/stream")
    assert answer.status_code == 200
    assert answer.headers["content-type"].startswith("text/event-stream")
    frames = sse_frames(answer.text)
    events = list(served.result.events)
    assert [int(f["id"]) for f in frames] == list(range(1, len(events) + 1))
    for frame, event in zip(frames, events, strict=True):
        data = json.loads(frame["data"])
        assert data["event_type"] == event.event_type
        assert data["fault"]["fault_code"] == event.fault.fault_code


def test_the_stream_resumes_after_last_event_id(
    client: httpx.Client, served: ServedRecording
) -> None:
    total = len(served.result.events)
    resumed = sse_frames(client.get("/api/v1/faults/stream", headers={"Last-Event-ID": "5"}).text)
    assert [int(f["id"]) for f in resumed] == list(range(6, total + 1))
    for junk in ("-1", "abc", "5x", ""):
        frames = sse_frames(
            client.get("/api/v1/faults/stream", headers={"Last-Event-ID": junk}).text
        )
        assert int(frames[0]["id"]) == 1, junk
    beyond = client.get("/api/v1/faults/stream", headers={"Last-Event-ID": "99999"})
    assert sse_frames(beyond.text) == []  # above the newest id: clamped to it, nothing owed
    # Out of uint64's range the gateway's parse gives 0: everything again.
    huge = client.get("/api/v1/faults/stream", headers={"Last-Event-ID": str(10**30)})
    assert int(sse_frames(huge.text)[0]["id"]) == 1


def test_relationship_collections_have_the_published_shapes(client: httpx.Client) -> None:
    from medkit_replay.gateway.discovery_json import RELATIONS  # noqa: PLC0415

    seen = 0
    for kind, relations in RELATIONS.items():
        for item in client.get(f"/api/v1/{kind}").json()["items"]:
            for relation in relations:
                path = f"/api/v1/{kind}/{item['id']}/{relation}"
                answer = client.get(path)
                assert answer.status_code == 200, path
                # belongs-to is the handler's, not in the document; is-located-on answers a
                # collection (the handler) where the document says one entity.
                validate(answer.json(), "EntityList")
                seen += 1
    assert seen


def test_an_oversized_request_head_answers_431(client: httpx.Client) -> None:
    answer = client.get("/api/v1/faults", headers={"X-Padding": "a" * 20_000})
    assert answer.status_code == 431
    validate(answer.json(), "GenericError")
    long_query = client.get("/api/v1/faults?status=all&x=" + "b" * 20_000)
    assert long_query.status_code == 431


def test_the_recording_route_says_what_is_served(served: ServedRecording) -> None:
    from tests.gateway.support import serve_replay  # noqa: PLC0415

    at_ten = serve_replay([MISSION], [NAV2], at_sec=10.0)
    with running(build_app(at_ten, speed=0)) as client:
        facts = client.get("/api/v1/x-medkit/recording").json()
        assert facts["default_at_sec"] == 10.0
        assert facts["duration_sec"] == (served.end_ns - served.origin_ns) / 1e9
        # Without a moment the answer is --at's, not the end's.
        assert (
            client.get("/api/v1/faults?status=all").json()
            == client.get("/api/v1/faults?status=all&at=10").json()
        )


def test_streams_beyond_the_gateway_s_two_clients_answer_503(served: ServedRecording) -> None:
    slow = build_app(served, speed=1e-6)  # the second event would come days later
    with running(slow) as client, client.stream("GET", "/api/v1/faults/stream") as first:
        assert first.status_code == 200
        first_lines = first.iter_lines()
        assert next(first_lines).startswith("id: 1")
        with client.stream("GET", "/api/v1/faults/stream") as second:
            assert second.status_code == 200
            second_lines = second.iter_lines()  # kept: a dropped iterator closes the stream
            assert next(second_lines).startswith("id: 1")
            third = client.get("/api/v1/faults/stream", timeout=10)
            assert third.status_code == 503
            validate(third.json(), "GenericError")


def test_a_moment_in_the_base_url_starts_the_stream_there(
    client: httpx.Client, served: ServedRecording
) -> None:
    events = list(served.result.events)
    middle = events[len(events) // 2]
    first_id = next(i for i, e in enumerate(events, 1) if e.t_ns >= middle.t_ns)
    for path in (
        f"/at/{seconds(served, middle.t_ns)}/api/v1/faults/stream",
        f"/api/v1/faults/stream?at={seconds(served, middle.t_ns)}",
    ):
        frames = sse_frames(client.get(path).text)
        assert [int(f["id"]) for f in frames] == list(range(first_id, len(events) + 1)), path


def test_head_answers_like_get_without_a_body(client: httpx.Client) -> None:
    got, head = client.get("/api/v1/faults"), client.head("/api/v1/faults")
    assert head.status_code == 200 and head.content == b""
    assert head.headers["content-length"] == got.headers["content-length"]


def test_the_release_modelled_is_served(tmp_path: Path) -> None:
    release = tmp_path / "release.yaml"
    release.write_text('medkit_replay:\n  ros__parameters:\n    upstream_release: "0.6.0"\n')
    old = serve_replay([MISSION], [NAV2, release])
    assert old.max_code_length == 128  # the 0.6.0 manager's bound on a fault code
    with running(build_app(old, speed=0)) as client:
        assert client.get("/api/v1/x-medkit/recording").json()["upstream_release"] == "0.6.0"
        app = client.get("/api/v1/apps").json()["items"][0]["id"]
        # A code the 0.6.0 manager refuses: the gateway passes the manager's failure on (503).
        answer = client.get(f"/api/v1/apps/{app}/faults/{'C' * 200}")
        assert answer.status_code == 503
        validate(answer.json(), "GenericError")


def test_a_stream_a_client_closes_frees_its_slot(served: ServedRecording) -> None:
    slow = build_app(served, speed=1e-6)
    with running(slow) as client, client.stream("GET", "/api/v1/faults/stream") as first:
        lines = first.iter_lines()
        assert next(lines).startswith("id: 1")
        with client.stream("GET", "/api/v1/faults/stream") as second:
            second_lines = second.iter_lines()
            assert next(second_lines).startswith("id: 1")
        # The second client went away: its slot is free again (the server notices the
        # closed connection when it next writes or polls it).
        deadline = time.monotonic() + 10
        while True:
            with client.stream("GET", "/api/v1/faults/stream") as third:
                if third.status_code == 200:
                    break
            assert time.monotonic() < deadline, "the closed stream's slot was never freed"
            time.sleep(0.1)


def with_capture(served: ServedRecording, *, retained: bool) -> ServedRecording:
    """``served`` with one freeze-frame capture of its first fault, taken at the start."""
    topic = SnapshotTopic(
        topic="/battery", message_type="std_msgs/msg/Float64", message_t_ns=served.origin_ns,
        data={"data": 12.5},
    )  # fmt: skip
    capture = SnapshotCapture(
        fault_code=served.history.faults_at(served.end_ns)[0].fault_code, capture_id=1,
        t_ns=served.origin_ns, retained=retained, freeze_frame=True, topics=(topic,),
    )  # fmt: skip
    return dataclasses.replace(
        served, result=dataclasses.replace(served.result, snapshots=(capture,))
    )


def served_snapshots(served: ServedRecording) -> list[dict[str, object]]:
    """The detail route's snapshots of the first fault, from the app that reports it."""
    code = served.history.faults_at(served.end_ns)[0].fault_code
    with running(build_app(served, speed=0)) as client:
        app = next(
            a["id"]
            for a in client.get("/api/v1/apps").json()["items"]
            if any(
                f["fault_code"] == code
                for f in client.get(f"/api/v1/apps/{a['id']}/faults?status=all").json()["items"]
            )
        )
        detail = client.get(f"/api/v1/apps/{app}/faults/{code}").json()
    snapshots: list[dict[str, object]] = detail["environment_data"]["snapshots"]
    return snapshots


def test_a_cleared_capture_is_still_served_as_the_compact_freeze_frame(
    served: ServedRecording,
) -> None:
    # After a clear (retain_on_clear false) the manager drops the capture's rows but keeps
    # its compact freeze frame: retained=False, freeze_frame=True.
    frames = [s for s in served_snapshots(with_capture(served, retained=False))
              if s["type"] == "freeze_frame"]  # fmt: skip
    assert [(f["name"], f["data"]) for f in frames] == [
        ("freeze_frame", {"/battery": {"data": 12.5}})
    ]


def test_a_spilled_stream_resumes_from_any_event(served: ServedRecording) -> None:
    events: Spool[FaultEvent] = Spool(3, codec=EVENT_ROWS)
    for event in served.result.events:
        events.append(event)
    spilled = dataclasses.replace(served, result=dataclasses.replace(served.result, events=events))
    assert EventStream(spilled, speed=0, max_clients=2).times == [e.t_ns for e in events]
    total = len(events)
    with running(build_app(spilled, speed=0)) as client:
        for after in (0, 4, 5, total - 1, total):
            answer = client.get("/api/v1/faults/stream", headers={"Last-Event-ID": str(after)})
            frames = sse_frames(answer.text)
            assert [int(f["id"]) for f in frames] == list(range(after + 1, total + 1))
            codes = [json.loads(f["data"])["fault"]["fault_code"] for f in frames]
            assert codes == [e.fault.fault_code for e in served.result.events][after:]


def test_retain_on_clear_serves_the_compact_frame_beside_the_rows(
    served: ServedRecording, tmp_path: Path
) -> None:
    retain = tmp_path / "retain.yaml"
    retain.write_text(
        "fault_manager:\n  ros__parameters:\n    snapshots:\n      retain_on_clear: true\n"
    )
    assert serve_replay([MISSION], [NAV2, retain]).retain_on_clear
    assert not served.retain_on_clear
    held = with_capture(served, retained=True)
    names = {
        retained: [
            s["name"] for s in served_snapshots(dataclasses.replace(held, retain_on_clear=retained))
        ]
        for retained in (False, True)
    }
    assert names == {False: ["battery"], True: ["battery", "freeze_frame"]}
