"""``fleet s3://bucket/prefix/``: recordings discovered under a prefix of moto's S3 server on
127.0.0.1 by the local rules, replayed as their local copies are, also by Dask workers that
read them straight from the store."""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

from medkit_replay.cli import main
from medkit_replay.fleet.discover import discover
from tests.fleet.fleet_support import SAMPLES, fleet_rows, fleet_tree
from tests.remote_support import aws_environment, s3_server, tree_objects, upload

if TYPE_CHECKING:
    from collections.abc import Iterator
    from pathlib import Path

pytest.importorskip("obstore")
pytest.importorskip("boto3")
pytest.importorskip("moto.server")
distributed = pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def s3_endpoint() -> Iterator[str]:
    with s3_server() as endpoint:
        yield endpoint


def test_fleet_over_a_prefix_finds_and_replays_what_a_local_folder_would(
    s3_endpoint: str, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    bucket = aws_environment(monkeypatch, s3_endpoint, tmp_path)
    local = fleet_tree(tmp_path / "fleet")
    for path, key in tree_objects(local, "2026-03/fleet"):
        upload(bucket, path, key)
    url = f"s3://{bucket}/2026-03/fleet/"
    found = discover([url])
    assert found == [
        f"{url}robot7/nav2_mission_mcap/",
        f"{url}robot7/sqlite_run/",
        f"{url}robot9/service_calls.mcap",
    ]
    assert [str(p) for p in discover([local])] == [
        str(local / "robot7/nav2_mission_mcap"),
        str(local / "robot7/sqlite_run"),
        str(local / "robot9/service_calls.mcap"),
    ]
    assert discover([f"s3://{bucket}/2026-03/fleet/robot7/nav2_mission_mcap"]) == [found[0]]

    args = ["--config", str(SAMPLES.parent / "rules/nav2/fault_manager.yaml"), "--quiet"]
    assert main(["fleet", str(local), *args, "--jobs", "1", "--out", str(tmp_path / "l")]) == 0
    assert main(["fleet", url, *args, "--jobs", "1", "--out", str(tmp_path / "r")]) == 0
    with distributed.LocalCluster(
        n_workers=1,
        processes=True,
        threads_per_worker=1,
        dashboard_address=None,
        worker_dashboard_address=None,
    ) as cluster:
        address = cluster.scheduler_address
        assert main(["fleet", url, *args, "--dask", address, "--out", str(tmp_path / "d")]) == 0

    expected = fleet_rows(tmp_path / "l", f"{local}/")
    assert [run["path"] for run in expected] == [
        "robot7/nav2_mission_mcap",
        "robot7/sqlite_run",
        "robot9/service_calls.mcap",
    ]
    assert all(not run.get("error") for run in expected)
    assert fleet_rows(tmp_path / "r", url) == expected
    assert fleet_rows(tmp_path / "d", url) == expected


def test_an_http_prefix_cannot_be_listed(tmp_path: Path) -> None:
    from medkit_replay.errors import InputError  # noqa: PLC0415

    with pytest.raises(InputError, match="cannot be listed"):
        discover(["https://127.0.0.1:9/fleet/"])
