"""``medkit-replay serve`` as people run it: the real server over a real socket, Ctrl-C, the
address it takes; bulk data equal to analyze's clips; CORS only for the origins given."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
from typing import TYPE_CHECKING

import httpx
import pytest
from rosbags.rosbag2 import StoragePlugin

from medkit_replay.cli import main
from medkit_replay.gateway.app import build_app
from tests.evidence.robot import write_config, write_robot
from tests.gateway.schemas import validate
from tests.gateway.support import MISSION, NAV2, running, seconds, serve_replay

if TYPE_CHECKING:
    from pathlib import Path

    from medkit_replay.gateway.recording import ServedRecording


def start(args: list[str], env: dict[str, str]) -> tuple[subprocess.Popen[str], str]:
    """The command in a child process, and the base URL it printed once listening."""
    server = subprocess.Popen(
        [sys.executable, "-m", "medkit_replay.cli", "serve", *args],
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    assert server.stderr is not None
    line = server.stderr.readline()
    while line and "Serving" not in line:
        line = server.stderr.readline()
    if "Serving" not in line:
        server.kill()
        pytest.fail(f"serve did not start: {line!r}")
    return server, line.split(" at ", 1)[1].split("/api/v1", 1)[0]


def test_the_real_server_answers_httpx_and_stops_cleanly_on_ctrl_c(tmp_path: Path) -> None:
    env = {**os.environ, "TMPDIR": str(tmp_path)}
    server, base = start([str(MISSION), "--config", str(NAV2), "--port", "0", "--quiet",
                          "--speed", "0"], env)  # fmt: skip
    try:
        assert base.startswith("http://127.0.0.1:")  # loopback unless --host says otherwise
        staging = list(tmp_path.iterdir())
        assert [p.name.startswith("medkit-replay-serve-") for p in staging] == [True]
        with httpx.Client(base_url=base, timeout=30) as client:
            faults = client.get("/api/v1/faults", params={"status": "all"})
            assert faults.status_code == 200
            validate(faults.json(), "FaultList")
            assert faults.json()["items"]
            events = client.get("/api/v1/x-medkit/recording").json()["events"]
            last = str(events - 9)
            stream = client.get("/api/v1/faults/stream", headers={"Last-Event-ID": last})
            ids = [line for line in stream.text.splitlines() if line.startswith("id: ")]
            assert ids == [f"id: {n}" for n in range(events - 8, events + 1)]
    finally:
        server.send_signal(signal.SIGINT)
        _, rest = server.communicate(timeout=30)
    assert server.returncode == 0
    assert rest == "Stopped.\n"  # no traceback, no "aborted"
    assert list(tmp_path.iterdir()) == []  # the temporary clip folder went with it


def test_sigterm_stops_the_server_as_ctrl_c_does(tmp_path: Path) -> None:
    # docker stop and systemd stop a service with SIGTERM: a normal stop, not a failure.
    env = {**os.environ, "TMPDIR": str(tmp_path)}
    server, base = start([str(MISSION), "--config", str(NAV2), "--port", "0", "--quiet"], env)
    try:
        with httpx.Client(base_url=base, timeout=30) as client:
            assert client.get("/api/v1/health").status_code == 200
    finally:
        server.send_signal(signal.SIGTERM)
        _, rest = server.communicate(timeout=30)
    assert server.returncode == 0
    assert rest == "Stopped.\n"
    assert list(tmp_path.iterdir()) == []


def test_an_address_already_taken_is_one_line_and_status_2(
    capsys: pytest.CaptureFixture[str],
) -> None:
    taken = socket.socket()
    taken.bind(("127.0.0.1", 0))
    taken.listen(1)
    try:
        port = taken.getsockname()[1]
        status = main(["serve", str(MISSION), "--port", str(port), "--quiet"])
    finally:
        taken.close()
    assert status == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"cannot listen on 127.0.0.1:{port}" in err


def test_cors_only_for_the_origins_given() -> None:
    served = serve_replay([MISSION], [NAV2])
    app = build_app(served, speed=0, cors=["http://localhost:5173"])
    with running(app) as client:
        asked = {"Access-Control-Request-Method": "GET"}
        good = client.options(
            "/api/v1/faults", headers={"Origin": "http://localhost:5173", **asked}
        )
        assert good.headers["access-control-allow-origin"] == "http://localhost:5173"
        other = client.get("/api/v1/faults", headers={"Origin": "http://evil.example"})
        assert "access-control-allow-origin" not in other.headers
    with running(build_app(served, speed=0)) as client:
        plain = client.get("/api/v1/faults", headers={"Origin": "http://localhost:5173"})
        assert "access-control-allow-origin" not in plain.headers


@pytest.fixture(scope="module")
def robot_served(tmp_path_factory: pytest.TempPathFactory) -> tuple[ServedRecording, Path]:
    root = tmp_path_factory.mktemp("robot")
    robot = write_robot(root, StoragePlugin.MCAP)
    config = write_config(root, "mcap")
    analyzed = root / "analyze_clips"
    argv = ["analyze", str(robot.bag), str(robot.script), "--config", str(config),
            "--graph", str(robot.graph), "--evidence", str(analyzed), "--quiet"]  # fmt: skip
    assert main(argv) == 0
    served = serve_replay(
        [robot.bag, robot.script], [config], graph=robot.graph, clips=root / "served_clips"
    )
    return served, analyzed


def test_a_clip_downloads_byte_for_byte_as_analyze_writes_it(
    robot_served: tuple[ServedRecording, Path],
) -> None:
    served, analyzed = robot_served
    held = [r for r in served.result.recordings if r.deleted_ns is None]
    assert held
    with running(build_app(served, speed=0)) as client:
        apps = [a["id"] for a in client.get("/api/v1/apps").json()["items"]]
        downloaded = 0
        for recording in held:
            code = recording.fault_codes[0]
            for app in apps:
                listing = client.get(f"/api/v1/apps/{app}/bulk-data/rosbags").json()
                validate(listing, "BulkDataDescriptorList")
                if recording.recording_id not in [d["id"] for d in listing["items"]]:
                    continue
                answer = client.get(
                    f"/api/v1/apps/{app}/bulk-data/rosbags/{recording.recording_id}"
                )
                assert answer.status_code == 200
                assert answer.headers["content-type"] == "application/x-mcap"
                written = next((analyzed / recording.recording_id).glob("*.mcap"))
                assert answer.content == written.read_bytes()
                detail = client.get(f"/api/v1/apps/{app}/faults/{code}").json()
                uris = [s.get("bulk_data_uri") for s in detail["environment_data"]["snapshots"]]
                # As the gateway writes it: below the API base the client already holds.
                assert f"/apps/{app}/bulk-data/rosbags/{recording.recording_id}" in uris
                # Before its post-roll ended the manager had not written it yet.
                early = seconds(served, recording.end_ns - 1)
                listed = client.get(f"/api/v1/apps/{app}/bulk-data/rosbags?at={early}").json()
                assert recording.recording_id not in [d["id"] for d in listed["items"]]
                gone = client.get(
                    f"/api/v1/apps/{app}/bulk-data/rosbags/{recording.recording_id}?at={early}"
                )
                assert gone.status_code == 404
                downloaded += 1
        assert downloaded >= len(held)


def test_without_the_serve_extra_it_says_what_to_install() -> None:
    # The web stack hidden, as on a machine with only `pip install medkit-replay`.
    code = (
        "import sys\n"
        "sys.modules['uvicorn'] = None\n"
        "from medkit_replay.cli import main\n"
        f"sys.exit(main(['serve', {str(MISSION)!r}, '--quiet']))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], check=False, capture_output=True, text=True)
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1
    assert "pip install 'medkit-replay[serve]'" in done.stderr


def test_a_clip_downloads_in_ranges(robot_served: tuple[ServedRecording, Path]) -> None:
    served, _ = robot_served
    recording = next(r for r in served.result.recordings if r.recording_id in served.clips)
    whole = served.clips[recording.recording_id].read_bytes()
    with running(build_app(served, speed=0)) as client:
        apps = [a["id"] for a in client.get("/api/v1/apps").json()["items"]]
        for app in apps:
            path = f"/api/v1/apps/{app}/bulk-data/rosbags/{recording.recording_id}"
            part = client.get(path, headers={"Range": "bytes=8-99"})
            if part.status_code == 404:
                continue
            assert part.status_code == 206
            assert part.content == whole[8:100]
            assert part.headers["content-disposition"].endswith(
                f'filename="{recording.recording_id}.mcap"'
            )
            break
        else:
            pytest.fail("no app lists the recording")


def test_clips_are_never_written_over_the_recording(capsys: pytest.CaptureFixture[str]) -> None:
    inside = MISSION / "clips"
    status = main(["serve", str(MISSION), "--evidence", str(inside), "--port", "0", "--quiet"])
    assert status == 2
    assert not inside.exists()
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "clips" in err
