"""``fleet --dask``: the same runs on a local Dask distributed cluster, and its failures."""

from __future__ import annotations

import shutil
import socket
import sys
from typing import TYPE_CHECKING

from distributed import LocalCluster

from medkit_replay.cli import main
from medkit_replay.fleet import cluster as fleet_cluster
from medkit_replay.fleet.cluster import run_on_dask
from medkit_replay.fleet.report import FILES
from medkit_replay.fleet.workers import run_all
from tests.fleet.fleet_support import BRINGUP, SAMPLES, build_fleet, episode, write_script

if TYPE_CHECKING:
    from pathlib import Path

    import pytest

CLUSTER = {"n_workers": 1, "dashboard_address": ":0", "worker_dashboard_address": None}


def small_fleet(root: Path) -> Path:
    """Six scripts, a bag folder, and a broken file."""
    fleet = build_fleet(root, scripts=6)
    for folder in ("bags", "broken"):
        shutil.rmtree(fleet.root / folder)
    shutil.copytree(SAMPLES / "nav2_mission_sqlite3", fleet.root / "bag")
    (fleet.root / "broken.mcap").write_bytes(b"broken")
    return fleet.root


def test_dask_threads_cluster_gives_the_local_report(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fleet = small_fleet(tmp_path / "fleet")
    args = ["fleet", str(fleet), "--config", str(BRINGUP)]
    assert main([*args, "--jobs", "1", "--quiet", "--out", str(tmp_path / "local")]) == 0
    threads = LocalCluster(processes=False, threads_per_worker=2, **CLUSTER)  # type: ignore[no-untyped-call]
    with threads as cluster:
        address = cluster.scheduler_address
        assert main([*args, "--dask", address, "--out", str(tmp_path / "dask")]) == 0
    out, err = capsys.readouterr()
    assert "fleet: 8 recordings, 7 replayed, 1 failed" in out
    assert "broken.mcap:notanMCAPfile" in "".join(out.split())  # wrapped at 80 columns
    assert err == ""
    for name in FILES:
        local = (tmp_path / "local" / name).read_bytes()
        assert (tmp_path / "dask" / name).read_bytes() == local, name


def test_dask_worker_processes_and_budget(tmp_path: Path) -> None:
    """Real worker processes: the summaries and the budget travel pickled."""
    from medkit_replay.checks import parse_budget  # noqa: PLC0415

    scripts = [
        write_script(tmp_path / "a.jsonl", [line for _, line in episode("MOTOR_HOT", 1.0, None)]),
        write_script(tmp_path / "b.jsonl", [line for _, line in episode("WIFI", 1.0, 2.0)]),
    ]
    budget = parse_budget("version: 1\nrules:\n  - never_confirm: ['MOTOR_*']\n", "b.yaml")
    paths = [*scripts, tmp_path / "missing.jsonl"]
    seen: list[int] = []
    processes = LocalCluster(processes=True, threads_per_worker=1, **CLUSTER)  # type: ignore[no-untyped-call]
    with processes as cluster:
        runs = run_on_dask(
            cluster.scheduler_address,
            paths,
            [BRINGUP],
            budget=budget,
            on_done=lambda index, _: seen.append(index),
        )
    assert runs == run_all(paths, [BRINGUP], budget=budget, jobs=1)
    assert [r.budget for r in runs] == ["fail", "pass", None]
    assert runs[2].error == f"{tmp_path / 'missing.jsonl'}: input not found"
    assert sorted(seen) == [0, 1, 2]


def test_dask_timeout_kills_the_slow_run_only(tmp_path: Path) -> None:
    """With a timeout each task replays in a child process of its own, killed when time is up."""
    quick = write_script(tmp_path / "a.jsonl", [line for _, line in episode("WIFI", 1.0, 2.0)])
    slow = write_script(
        tmp_path / "slow.jsonl",
        [line for n in range(40_000) for _, line in episode(f"C{n % 997}", 1.0 + n / 1000, None)],
    )
    threads = LocalCluster(processes=False, threads_per_worker=2, **CLUSTER)  # type: ignore[no-untyped-call]
    with threads as cluster:
        runs = run_on_dask(cluster.scheduler_address, [quick, slow], [BRINGUP], timeout=0.5)
    assert runs[0] == run_all([quick], [BRINGUP], jobs=1)[0]
    assert runs[1].error == f"{slow}: timed out after 0.5 s"
    assert runs[1].path == str(slow) and runs[1].kind == "script"


def test_missing_extra_is_one_line_naming_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    write_script(tmp_path / "a.jsonl", [line for _, line in episode("A", 1.0, None)])
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed: ImportError
    status = main(["fleet", str(tmp_path), "--dask", "tcp://127.0.0.1:8786"])
    out, err = capsys.readouterr()
    assert status == 2 and out == ""
    assert err == (
        "medkit-replay: error: --dask needs the Dask distributed package: "
        "pip install 'medkit-replay[dask]'\n"
    )
    assert not (tmp_path / "fleet-report").exists()


def test_unreachable_scheduler_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    write_script(tmp_path / "in" / "a.jsonl", [line for _, line in episode("A", 1.0, None)])
    with socket.socket() as probe:  # a port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    monkeypatch.setattr(fleet_cluster, "DASK_CONNECT_TIMEOUT", "1s")
    address = f"tcp://127.0.0.1:{port}"
    status = main(["fleet", str(tmp_path / "in"), "--dask", address, "--out", str(tmp_path / "o")])
    out, err = capsys.readouterr()
    assert status == 2 and out == ""
    assert err.startswith(f"medkit-replay: error: {address}: cannot reach the Dask scheduler")
    assert err.count("\n") == 1
