"""Red team: a server that trickles, against the low-speed deadline of remote reads.

A server sending one byte a second held ``analyze`` for minutes before "gave up after 5 tries";
now each try under the speed limit for its time is ended (its connection closed) and two such
tries end the read in one line naming the stall and the URL. Small deadlines, set through the
environment variables, keep each case to seconds.
"""

from __future__ import annotations

import re
import time
from contextlib import contextmanager
from typing import TYPE_CHECKING

import pytest

from medkit_replay.errors import InputError
from medkit_replay.inputs.remote.fetch import SPEED_LIMIT_ENV, SPEED_TIME_ENV
from medkit_replay.inputs.remote.store import RemoteObject, Tally, open_store, parse_location
from tests.inputs.builders import diag, write_bare
from tests.redteam.support import assert_one_line_error, run_limited
from tests.remote_support import range_server

if TYPE_CHECKING:
    from collections.abc import Iterator
    from pathlib import Path

pytest.importorskip("obstore")

SECOND = 1_000_000_000
DATA = bytes(range(256)) * 8


@contextmanager
def trickling(root: Path, per_byte_s: float) -> Iterator[str]:
    """The Range server, its GETs sending a byte every ``per_byte_s``, serving DATA as run.mcap;
    yields its base URL."""
    (root / "run.mcap").write_bytes(DATA)
    with range_server(root) as (base, served):
        served.trickle_s = per_byte_s
        yield base


def remote_object(base: str, name: str) -> RemoteObject:
    location = parse_location(f"{base}/{name}")
    return RemoteObject(open_store(location), location, Tally(location.display))


def test_analyze_against_a_server_sending_a_byte_a_second_ends_in_one_line(
    tmp_path: Path,
) -> None:
    write_bare(tmp_path / "run.mcap", [diag(k * SECOND) for k in (1, 2, 3)])
    with range_server(tmp_path) as (base, served):
        served.trickle_s = 1.0
        started = time.monotonic()
        outcome = run_limited(
            ["analyze", f"{base}/run.mcap", "--quiet"], env={SPEED_TIME_ENV: "2"}, timeout=60
        )
        elapsed = time.monotonic() - started
        waited = time.monotonic() + 10  # the server sees a hang-up at its next byte
        while served.hung_up < 2 and time.monotonic() < waited:
            time.sleep(0.1)
        hung_up = served.hung_up
    line = assert_one_line_error(
        outcome, f"{base}/run.mcap: stalled: under 1 KB/s for 2 s; gave up after "
    )
    assert re.search(
        rf"gave up after [45] s under that speed \(raise the limits with {SPEED_TIME_ENV} or "
        rf"{SPEED_LIMIT_ENV}\)$",
        line,
    ), line
    assert hung_up >= 2  # each stalled try closed its connection: the server stopped sending
    print(f"\nstalled read given up after {elapsed:.1f} s (2 tries of 2 s)")


def test_a_read_above_the_speed_limit_is_never_stalled(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # About 200 bytes a second for 2 s: over a limit of 50 B/s it is read whole, over one of
    # 1 KB/s it stalls. The same server, the same bytes: only the deadline differs.
    monkeypatch.setenv(SPEED_TIME_ENV, "1")
    with trickling(tmp_path, 0.005) as base:
        monkeypatch.setenv(SPEED_LIMIT_ENV, "50")
        assert remote_object(base, "run.mcap").fetch(100, 500) == DATA[100:500]
        monkeypatch.setenv(SPEED_LIMIT_ENV, "1024")
        with pytest.raises(InputError, match=r"stalled: under 1 KB/s for 1 s; gave up after"):
            remote_object(base, "run.mcap").fetch(100, 500)
        monkeypatch.setenv(SPEED_LIMIT_ENV, "0")  # no deadline
        assert remote_object(base, "run.mcap").fetch(0, 300) == DATA[:300]


def test_small_reads_each_slow_but_short_are_given_up_in_all(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # 30 bytes at about 20 a second: each read ends before the 3 s of the deadline, yet the
    # object is given up once its reads spent 2 x 3 s under the limit (not read after read).
    monkeypatch.setenv(SPEED_TIME_ENV, "3")
    with trickling(tmp_path, 0.05) as base:
        obj = remote_object(base, "run.mcap")
        started = time.monotonic()
        read = 0
        with pytest.raises(InputError, match=r"too slow: reads under 1 KB/s; gave up after") as err:
            for start in range(0, 2000, 100):
                assert obj.fetch(start, start + 30) == DATA[start : start + 30]
                read += 1
        elapsed = time.monotonic() - started
    assert str(err.value).startswith(f"{base}/run.mcap: too slow: reads under 1 KB/s; gave up")
    assert 2 <= read <= 5  # 6 s of reads of 1.5 s or more, not twenty reads
    print(f"\nslow reads given up after {read} reads, {elapsed:.1f} s")


@pytest.mark.parametrize(
    ("name", "value"),
    [
        (SPEED_TIME_ENV, "abc"),
        (SPEED_TIME_ENV, "0"),
        (SPEED_LIMIT_ENV, "-1"),
        (SPEED_LIMIT_ENV, "nan"),
    ],
)
def test_a_deadline_that_is_not_a_number_in_range_is_one_line(
    tmp_path: Path, name: str, value: str
) -> None:
    write_bare(tmp_path / "run.mcap", [diag(SECOND)])
    with range_server(tmp_path) as (base, _served):
        outcome = run_limited(["analyze", f"{base}/run.mcap", "--quiet"], env={name: value})
    assert_one_line_error(outcome, f"{name}={value!r}: must be")
