"""Remote inputs against real servers on 127.0.0.1: moto's S3 server and an HTTP server with
Range support, over real sockets (nothing in the client is patched).

The same recording gives the same report remote and local (its name aside); an indexed MCAP
is fetched by ranges, a .db3 through a temporary copy that is removed; 403, 404, a missing
extra, a cut object and a dropped connection behave as the docs say; no secret is ever shown.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import replace
from typing import TYPE_CHECKING

import pytest

from medkit_replay import replay
from medkit_replay.errors import InputError
from medkit_replay.inputs import open_recording
from medkit_replay.inputs.remote.store import open_store, parse_location
from medkit_replay.outputs.json_report import dumps
from tests.inputs.builders import diag, flipped, string_msg, truncated, write_bag
from tests.remote_support import (
    KEY_ID,
    NAV2,
    ROOT,
    SAMPLES,
    SECRET,
    aws_environment,
    cli,
    config_args,
    one_line_error,
    range_server,
    report_text,
    s3_server,
    same_as_local,
    upload,
)
from tests.speed.support import plain
from tests.speed.test_index_reading import mixed_bag

if TYPE_CHECKING:
    from collections.abc import Iterator
    from pathlib import Path

pytest.importorskip("obstore")
pytest.importorskip("boto3")
pytest.importorskip("moto.server")


@pytest.fixture(scope="module")
def s3_endpoint() -> Iterator[str]:
    with s3_server() as endpoint:
        yield endpoint


@pytest.fixture
def s3_env(s3_endpoint: str, monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> str:
    """The AWS environment a user would set for MinIO; returns a fresh bucket's name."""
    return aws_environment(monkeypatch, s3_endpoint, tmp_path)


# -- the same report, remote and local ----------------------------------------------------------


def test_bare_mcap_over_s3_reports_like_the_local_file(s3_env: str) -> None:
    local = SAMPLES / "service_calls.mcap"
    upload(s3_env, local, "runs/service_calls.mcap")
    remote = same_as_local(f"s3://{s3_env}/runs/service_calls.mcap", local, [])
    fetched, size = remote.fetched[f"s3://{s3_env}/runs/service_calls.mcap"]
    assert size == local.stat().st_size
    assert fetched > 0


def test_rosbag2_folder_over_s3_reports_like_the_local_folder(s3_env: str) -> None:
    local = SAMPLES / "nav2_mission_mcap"
    upload(s3_env, local, "robot7/nav2_mission_mcap")
    same_as_local(f"s3://{s3_env}/robot7/nav2_mission_mcap/", local)
    same_as_local(f"s3://{s3_env}/robot7/nav2_mission_mcap", local)  # with or without "/"


def test_bare_mcap_and_folder_over_http_report_like_local() -> None:
    with range_server(SAMPLES) as (base, served):
        same_as_local(f"{base}/nav2_mission_mcap/nav2_mission_mcap.mcap", _bare_copy())
        same_as_local(f"{base}/nav2_mission_mcap/", SAMPLES / "nav2_mission_mcap")
    gets = [headers for method, headers in served.seen if method == "GET"]
    assert gets and all("range" in map(str.lower, headers) for headers in gets)  # never whole


def _bare_copy() -> Path:
    return SAMPLES / "nav2_mission_mcap" / "nav2_mission_mcap.mcap"


def test_sqlite3_bag_is_downloaded_to_a_temporary_copy_that_is_removed(
    s3_env: str, tmp_path: Path
) -> None:
    local = SAMPLES / "nav2_mission_sqlite3"
    upload(s3_env, local, "nav2_mission_sqlite3")
    url = f"s3://{s3_env}/nav2_mission_sqlite3"
    temp = tmp_path / "tmpdir"
    temp.mkdir()
    report = tmp_path / "report.json"
    done = cli("analyze", url, *config_args(), "--json", str(report), env={"TMPDIR": str(temp)})
    assert done.returncode == 0, done.stderr
    assert list(temp.iterdir()) == []
    expected = dumps(replay([local], NAV2))
    assert report.read_text().replace(url, str(local)) == expected


# -- reading by ranges -------------------------------------------------------------------------


def camera_heavy_bag(root: Path) -> Path:
    """10 s of 15 Hz 60 kB frames on an unread topic beside 5 Hz diagnostics (98 % frames).

    Chunks of three messages: the first chunk, which also holds the schema and channel
    records, is read whole, the others by their message indexes.
    """
    frame = "x" * 60_000
    records = []
    for k in range(150):
        t_ns = 10**18 + k * 66_666_666
        records.append(string_msg(t_ns, "/camera/image", frame))
        if k % 3 == 0:
            records.append(diag(t_ns + 1, level=2 if k % 30 < 12 else 0))
    return write_bag(root / "camera_bag", records, chunk_every=3)


def test_an_indexed_mcap_is_fetched_by_ranges_only_where_the_replay_reads(tmp_path: Path) -> None:
    bag = camera_heavy_bag(tmp_path)
    mcap = next(bag.glob("*.mcap"))
    with range_server(tmp_path) as (base, served):
        url = f"{base}/camera_bag/"
        result = same_as_local(url, bag, [])
    fetched, size = result.fetched[url.rstrip("/")]
    assert size == mcap.stat().st_size + (bag / "metadata.yaml").stat().st_size
    assert fetched == served.body_bytes  # what the server sent is what is counted
    assert fetched < 0.02 * size, f"{fetched} of {size} bytes fetched"
    assert result.summary.messages_read == 50


def test_the_terminal_summary_says_how_much_was_fetched(tmp_path: Path) -> None:
    bag = camera_heavy_bag(tmp_path)
    with range_server(tmp_path) as (base, _served):
        done = cli("analyze", f"{base}/camera_bag")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    at = lines.index(f"  {base}/camera_bag (mcap)")  # below the header and the release line
    fetched = lines[at + 1]
    assert fetched.startswith("  fetched ") and " of 9." in fetched and "%)" in fetched
    local = cli("analyze", str(bag))
    assert "fetched" not in local.stdout


# -- failures ---------------------------------------------------------------------------------


def test_a_missing_object_is_one_line_naming_the_url(s3_env: str) -> None:
    url = f"s3://{s3_env}/nothing/here.mcap"
    line = one_line_error(cli("analyze", url))
    assert url in line and "not found" in line
    line = one_line_error(cli("analyze", f"s3://{s3_env}/no/such/prefix/"))
    assert f"s3://{s3_env}/no/such/prefix/" in line
    with range_server(SAMPLES) as (base, _served):
        line = one_line_error(cli("analyze", f"{base}/missing.mcap"))
    assert f"{base}/missing.mcap: not found (HTTP 404)" in line


def test_access_denied_is_one_line_naming_the_url() -> None:
    with range_server(SAMPLES) as (base, served):
        served.forbidden.add("service_calls.mcap")
        line = one_line_error(cli("analyze", f"{base}/service_calls.mcap"))
    assert line.endswith(f"{base}/service_calls.mcap: access denied (HTTP 403)")


def test_without_the_remote_extra_one_line_says_how_to_install_it() -> None:
    code = (
        "import sys; sys.modules['obstore'] = None; from medkit_replay.cli import main; "
        "sys.exit(main(['analyze', 's3://bucket/run.mcap']))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        timeout=60,
        check=False,
    )
    line = one_line_error(done)
    assert "pip install 'medkit-replay[remote]'" in line


def test_a_cut_object_is_read_as_far_as_a_cut_local_file(tmp_path: Path, s3_env: str) -> None:
    whole = _bare_copy()
    cut = truncated(whole, tmp_path / "cut.mcap", whole.stat().st_size * 2 // 3)
    upload(s3_env, cut, "cut.mcap")
    remote = same_as_local(f"s3://{s3_env}/cut.mcap", cut)
    assert remote.warnings and all(str(tmp_path) not in w for w in remote.warnings)
    assert any(w.startswith(f"s3://{s3_env}/cut.mcap: ") for w in remote.warnings)


def test_a_dropped_connection_is_retried() -> None:
    with range_server(SAMPLES) as (base, served):
        served.drop_next = 3
        same_as_local(f"{base}/nav2_mission_mcap/", SAMPLES / "nav2_mission_mcap")
        assert served.drop_next == 0


def test_a_connection_that_keeps_dropping_ends_in_one_line() -> None:
    with range_server(SAMPLES) as (base, served):
        served.drop_next = 10**6
        done = cli("analyze", f"{base}/service_calls.mcap")
    line = one_line_error(done)
    assert line.endswith(f"{base}/service_calls.mcap: connection failed; gave up after 5 tries")


def test_credentials_and_queries_never_appear(tmp_path: Path, s3_env: str) -> None:
    local = SAMPLES / "nav2_mission_mcap"
    upload(s3_env, local, "bag")
    outputs = []
    report, html = tmp_path / "report.json", tmp_path / "report.html"
    url = f"s3://{s3_env}/bag"
    ok = cli("analyze", url, *config_args(), "--json", str(report), "--html", str(html))
    assert ok.returncode == 0, ok.stderr
    outputs += [ok.stdout, ok.stderr, report.read_text(), html.read_text()]
    for args in (
        ["analyze", f"s3://{s3_env}/missing.mcap"],
        ["analyze", f"https://user:{SECRET}@127.0.0.1:9/bag.mcap"],
        ["analyze", f"https://127.0.0.1:9/bag.mcap?X-Amz-Signature={SECRET}"],
        ["check", f"s3://{s3_env}/missing/", "--budget", str(tmp_path / "none.yaml")],
    ):
        done = cli(*args)
        assert done.returncode == 2, done.stderr
        outputs += [done.stdout, done.stderr]
    for text in outputs:
        assert SECRET not in text
        assert KEY_ID not in text


def test_sigterm_during_a_download_leaves_the_temporary_folder_empty(tmp_path: Path) -> None:
    temp = tmp_path / "tmpdir"
    temp.mkdir()
    shutil.copytree(SAMPLES / "nav2_mission_sqlite3", tmp_path / "served" / "bag")
    with range_server(tmp_path / "served") as (base, served):
        served.delay_s = 0.5
        command = [sys.executable, "-m", "medkit_replay.cli", "analyze", f"{base}/bag/"]
        env = {**os.environ, "PYTHONPATH": str(ROOT), "TMPDIR": str(temp)}
        with subprocess.Popen(command, env=env, stderr=subprocess.PIPE, text=True) as process:
            deadline = time.monotonic() + 30
            while not list(temp.glob("medkit-replay-remote-*/bag/*.db3")):
                assert time.monotonic() < deadline and process.poll() is None
                time.sleep(0.02)
            process.send_signal(signal.SIGTERM)
            _, stderr = process.communicate(timeout=30)
    assert process.returncode != 0
    assert "Traceback" not in stderr
    assert list(temp.iterdir()) == []


def test_check_and_diff_take_urls(tmp_path: Path) -> None:
    baseline = tmp_path / "baseline.json"
    budget = ROOT / "rules/budgets/nav2_mission_pass.yaml"
    local = SAMPLES / "nav2_mission_mcap"
    assert cli("analyze", str(local), *config_args(), "--json", str(baseline)).returncode == 0
    with range_server(SAMPLES) as (base, _served):
        url = f"{base}/nav2_mission_mcap/"
        diff = cli("diff", str(baseline), url, *config_args())
        check = cli("check", url, *config_args(), "--budget", str(budget))
    assert diff.returncode == 0, diff.stderr
    assert "reports are equal" in diff.stdout
    assert f"{url} (replayed now)" in diff.stdout
    assert check.returncode == 0, check.stderr
    assert "budget holds" in check.stdout


def _read(source: Path | str, local: Path) -> object:
    """What the inputs layer makes of a recording: messages, warnings, summaries (or the error),
    a remote one's name put back to the local file's."""
    name = str(source).rstrip("/")
    try:
        with open_recording([source], rosout=True) as recording:
            messages = [(m.t_ns, m.topic, plain(m.msg)) for m in recording.messages()]
            warnings = [w.replace(name, str(local)) for w in recording.warnings]
            inputs = [replace(s, path=s.path.replace(name, str(local))) for s in recording.inputs]
            return messages, warnings, inputs
    except InputError as exc:
        return str(exc).replace(name, str(local))


def test_damaged_files_read_the_same_remote_as_local(tmp_path: Path) -> None:
    source = mixed_bag(tmp_path, frames=8)
    data = source.read_bytes()
    structure = [i for i in range(len(data)) if data[i] != 7]  # outside the frames' filler
    served = tmp_path / "served"
    served.mkdir()
    with range_server(served) as (base, _served):
        for offset in [*structure[:: max(1, len(structure) // 40)], len(data) - 20]:
            path = flipped(source, served / "flip.mcap", offset)
            assert _read(f"{base}/flip.mcap", path) == _read(path, path), offset
        for size in (len(data) // 3, len(data) - 30, len(data) - 1):
            path = truncated(source, served / "cut.mcap", size)
            assert _read(f"{base}/cut.mcap", path) == _read(path, path), size


def test_an_mcap_without_its_summary_is_streamed_in_blocks(tmp_path: Path) -> None:
    bag = camera_heavy_bag(tmp_path)
    mcap = next(bag.glob("*.mcap"))
    size = mcap.stat().st_size
    assert size > 8 * 1024 * 1024  # more than one block of the stream
    served = tmp_path / "served"
    served.mkdir()
    cut = truncated(mcap, served / "cut.mcap", size - 1000)  # no footer, no summary
    with range_server(served) as (base, _served):
        url = f"{base}/cut.mcap"
        remote = replay([url], [])
    text = report_text(remote, url, cut)
    assert text == dumps(replay([cut], []))
    assert "scanning the file from the start" in text
    assert remote.fetched[url][0] >= size - 1000  # every byte, read once per pass


def test_s3_credentials_come_from_an_aws_profile(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """No keys in the environment: the profile's keys sign the requests (seen by the server)."""
    for name in list(os.environ):
        if name.startswith("AWS_"):
            monkeypatch.delenv(name)
    credentials = tmp_path / "credentials"
    credentials.write_text(
        "[robots]\naws_access_key_id = PROFILEKEYID123\naws_secret_access_key = " + SECRET + "\n"
    )
    config = tmp_path / "config"
    config.write_text("[profile robots]\nregion = eu-west-1\n")
    served_root = tmp_path / "served"
    (served_root / "fleet-bags").mkdir(parents=True)
    shutil.copy(SAMPLES / "service_calls.mcap", served_root / "fleet-bags" / "run.mcap")
    with range_server(served_root) as (base, served):
        monkeypatch.setenv("AWS_ENDPOINT_URL", base)  # path-style requests: /bucket/key
        monkeypatch.setenv("AWS_PROFILE", "robots")
        monkeypatch.setenv("AWS_SHARED_CREDENTIALS_FILE", str(credentials))
        monkeypatch.setenv("AWS_CONFIG_FILE", str(config))
        same_as_local("s3://fleet-bags/run.mcap", SAMPLES / "service_calls.mcap", [])
    signatures = [h.get("authorization", "") for _, h in served.seen]
    assert signatures and all("Credential=PROFILEKEYID123/" in s for s in signatures)
    assert all("/eu-west-1/s3/" in s for s in signatures)  # the profile's region


@pytest.mark.parametrize(
    ("url", "display"),
    [
        ("s3://bags/robot7/run.mcap", "s3://bags/robot7/run.mcap"),
        ("gs://bags/robot7/", "gs://bags/robot7/"),
        ("HTTPS://Files.Example:8443/m/run.db3", "https://files.example:8443/m/run.db3"),
    ],
)
def test_urls_are_named_as_given_and_each_scheme_has_its_store(url: str, display: str) -> None:
    location = parse_location(url)
    assert location.display == display
    kinds = {"s3": "S3Store", "gs": "GCSStore", "https": "HTTPStore"}
    assert type(open_store(location)).__name__ == kinds[location.scheme]  # no request is made


@pytest.mark.parametrize(
    "url",
    [
        f"https://robot:{SECRET}@files.example/run.mcap",
        f"https://files.example/run.mcap?token={SECRET}",
        f"s3://bags/run.mcap#{SECRET}",
        "s3:///run.mcap",
        "ftp://files.example/run.mcap",
    ],
)
def test_urls_with_secrets_or_without_a_bucket_are_refused_without_showing_them(url: str) -> None:
    with pytest.raises(InputError) as caught:
        parse_location(url)
    assert SECRET not in str(caught.value)


def test_sweep_suggest_rules_and_explain_take_urls(tmp_path: Path) -> None:
    """The tuning commands and explain read a URL as analyze does: same rows, same story."""
    local = _bare_copy()  # an HTTP server cannot be listed: a file's own URL
    vary = ["--vary", "fault_manager.confirmation_threshold=-1,-2", "--jobs", "1", "--quiet"]
    explain = ["MOTOR_LEFT_OVERHEAT", *config_args(), "--json", "--quiet"]
    here, there = tmp_path / "local", tmp_path / "remote"
    assert cli("sweep", str(local), *config_args(), *vary, "--out", str(here)).returncode == 0
    local_story = cli("explain", str(local), *explain)
    with range_server(SAMPLES) as (base, _served):
        url = f"{base}/nav2_mission_mcap/nav2_mission_mcap.mcap"
        sweep = cli("sweep", url, *config_args(), *vary, "--out", str(there))
        story = cli("explain", url, *explain)
        suggest = cli("suggest-rules", url, *config_args(), "--min-support", "1")
    assert sweep.returncode == 0, sweep.stderr
    for table in ("variants.csv", "codes.csv"):
        assert (there / table).read_text() == (here / table).read_text()
    runs = (there / "runs.csv").read_text()
    assert url in runs
    assert runs.replace(url, str(local)) == (here / "runs.csv").read_text()
    assert story.returncode == 0, story.stderr
    remote_entries = json.loads(story.stdout)["entries"]
    assert remote_entries == json.loads(local_story.stdout)["entries"]
    assert suggest.returncode == 0, suggest.stderr
    assert "Learned from 1 run(s)" in suggest.stdout
