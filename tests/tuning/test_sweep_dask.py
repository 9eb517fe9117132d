"""``sweep --dask``: the same jobs on a Dask cluster give the same tables; ``--timeout`` fails
only the job that runs out of time."""

from __future__ import annotations

from typing import TYPE_CHECKING

from distributed import LocalCluster

from medkit_replay.cli import main
from tests.fleet.fleet_support import episode, write_script
from tests.tuning.test_sweep_cli import BRINGUP, flapping

if TYPE_CHECKING:
    from pathlib import Path

    import pytest

CLUSTER = {"n_workers": 1, "dashboard_address": None, "worker_dashboard_address": None}
TABLES = [
    f"{t}.{s}" for t in ("runs", "run_codes", "variants", "codes") for s in ("csv", "parquet")
]


def test_dask_gives_the_local_tables(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scripts = [str(flapping(tmp_path / f"in/run_{i}.jsonl")) for i in range(2)]
    args = ["sweep", *scripts, "--config", str(BRINGUP), "--quiet"]
    args += ["--vary", "fault_manager.healing_threshold=1,2,4"]
    assert main([*args, "--jobs", "1", "--out", str(tmp_path / "local")]) == 0
    threads = LocalCluster(processes=False, threads_per_worker=2, **CLUSTER)  # type: ignore[no-untyped-call]
    with threads as cluster:
        address = cluster.scheduler_address
        assert main([*args, "--dask", address, "--out", str(tmp_path / "dask")]) == 0
        timed = [*args, "--dask", address, "--timeout", "60", "--out", str(tmp_path / "timed")]
        assert main(timed) == 0
    assert capsys.readouterr().err == ""
    for name in TABLES:
        local = (tmp_path / "local" / name).read_bytes()
        assert (tmp_path / "dask" / name).read_bytes() == local, name
        assert (tmp_path / "timed" / name).read_bytes() == local, name


def test_a_job_past_its_timeout_fails_its_rows(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    slow = write_script(
        tmp_path / "slow.jsonl",
        [line for n in range(40_000) for _, line in episode(f"C{n % 997}", 1.0 + n / 1000, None)],
    )
    args = ["sweep", str(slow), "--vary", "fault_manager.healing_threshold=1,2"]
    status = main([*args, "--jobs", "1", "--timeout", "0.2", "--out", str(tmp_path / "out")])
    out = capsys.readouterr().out
    assert status == 0
    assert "timedoutafter0.2s" in "".join(out.split())  # wrapped at 80 columns
    rows = (tmp_path / "out" / "runs.csv").read_text().splitlines()[1:]
    assert len(rows) == 2 and all("timed out after 0.2 s" in r for r in rows)
