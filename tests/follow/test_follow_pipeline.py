"""The one pipeline in follow mode, in process: same result as a replay of the finished recording.

Recordings here are finished before they are followed (no waiting); the CLI tests write live.
"""

from __future__ import annotations

import io
import time
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from medkit_replay.inputs.follow import Follow
from medkit_replay.model import POLL_MAX_S, POLL_MIN_S, FaultEvent, Transition
from medkit_replay.outputs.json_report import write_json
from medkit_replay.pipeline import replay
from tests.follow.live_writer import records, write_live
from tests.pipeline_support import MS, SEC, WARN, bag, diagnostics, report_call, status

if TYPE_CHECKING:
    from medkit_replay.result import Result
    from tests.inputs.builders import Storage

SAMPLES = Path(__file__).resolve().parents[2] / "sample_bags"


def json_bytes(result: Result) -> bytes:
    stream = io.StringIO()
    write_json(result, stream)
    return stream.getvalue().encode()


@pytest.mark.parametrize(
    "sample", ["nav2_mission_mcap", "nav2_mission_sqlite3", "service_calls.mcap"]
)
def test_following_a_finished_sample_is_analyzing_it(sample: str) -> None:
    follow = Follow(poll_s=POLL_MIN_S)
    seen: list[Transition | FaultEvent] = []
    followed = replay([SAMPLES / sample], follow=follow, live=seen.append)
    assert follow.finished and follow.stopped is None and follow.notes == []
    plain = replay([SAMPLES / sample])
    assert json_bytes(followed) == json_bytes(plain)
    assert [r for r in seen if isinstance(r, Transition)] == list(plain.transitions)
    assert [r for r in seen if isinstance(r, FaultEvent)] == list(plain.events)


def test_a_bare_db3_without_wal_is_finished(tmp_path: Path) -> None:
    source = SAMPLES / "nav2_mission_sqlite3" / "nav2_mission_sqlite3.db3"
    bare = tmp_path / "download.db3"
    bare.write_bytes(source.read_bytes())
    follow = Follow(poll_s=POLL_MIN_S)
    followed = replay([bare], follow=follow)
    assert follow.finished
    assert json_bytes(followed) == json_bytes(replay([bare]))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["download.db3"]


def test_a_recorded_call_after_the_bridge_replays_the_finished_recording(
    tmp_path: Path, storage: Storage
) -> None:
    # The bridge reports MOTOR from 1 s; the recorded ReportFault call for it only comes at 5 s.
    # analyze withholds the bridge's reports (known from its pre-pass); following cannot look
    # ahead, so once finished the recording is replayed as it stands, and the user is told.
    recs = [diagnostics(t * SEC, status("motor", WARN, "warm")) for t in (1, 2, 3, 4)]
    recs += report_call(
        [5 * SEC + i * MS for i in range(1, 5)],
        "MOTOR",
        sequence=1,
        severity=1,
        description="hot",
        source_id="/diagnostic_bridge",
    )
    path = bag(tmp_path, "bag", recs, storage)
    follow = Follow(poll_s=POLL_MIN_S)
    seen: list[Transition | FaultEvent] = []
    followed = replay([path], follow=follow, live=seen.append)
    assert json_bytes(followed) == json_bytes(replay([path]))
    assert len(follow.notes) == 1 and "MOTOR" in follow.notes[0]
    assert seen[0].t_ns < 5 * SEC  # what was printed live applied the bridge's reports


def test_a_stop_before_the_end_keeps_what_was_read(tmp_path: Path) -> None:
    recs = [diagnostics(t * SEC, status("motor", WARN, "warm")) for t in range(1, 40)]
    path = bag(tmp_path, "bag", recs, "mcap")
    follow = Follow(poll_s=POLL_MIN_S)
    follow.request_stop("interrupted by SIGINT")
    result = replay([path], follow=follow)
    assert not follow.finished and follow.stopped == "interrupted by SIGINT"
    assert result.summary.messages_read < len(recs)
    assert any("following stopped (interrupted by SIGINT)" in w for w in result.warnings)


def test_a_costly_step_takes_a_bounded_share_of_the_time() -> None:
    follow = Follow()
    assert follow.may_spend("copy")
    with follow.spending("copy"):
        time.sleep(0.05)
    assert not follow.may_spend("copy")  # not before 10x its cost has passed since it began
    time.sleep(0.5)
    assert follow.may_spend("copy")


def test_the_poll_interval_is_clamped() -> None:
    assert Follow(poll_s=0).poll_s == POLL_MIN_S
    assert Follow(poll_s=3600).poll_s == POLL_MAX_S


@pytest.fixture(params=["mcap", "sqlite3"])
def storage(request: pytest.FixtureRequest) -> Storage:
    value: Storage = request.param
    return value


class Appending(Follow):
    """A Follow whose every wait is a writer appending the next ``step`` bytes of a recording
    (and metadata.yaml at the end): torn records at every offset, deterministically."""

    def __init__(self, source: Path, target: Path, step: int) -> None:
        super().__init__(poll_s=POLL_MIN_S)
        self.source, self.target, self.step = source, target, step
        self.files = sorted(p for p in source.iterdir() if p.suffix == ".mcap")
        self.at = (0, 0)  # file, bytes written
        target.mkdir()

    def wait(self) -> None:
        number, done = self.at
        if number == len(self.files):
            if not (self.target / "metadata.yaml").exists():
                (self.target / "metadata.yaml").write_bytes(
                    (self.source / "metadata.yaml").read_bytes()
                )
            super().wait()
            return
        data = self.files[number].read_bytes()
        with (self.target / self.files[number].name).open("ab") as sink:
            sink.write(data[done : done + self.step])
        done += self.step
        self.at = (number + 1, 0) if done >= len(data) else (number, done)


@pytest.mark.parametrize("step", [1021, 4099, 65537])
def test_an_mcap_appended_a_few_bytes_per_poll(tmp_path: Path, step: int) -> None:
    source = tmp_path / "source"
    write_live(source, "mcap", records("nav2"), 20, 0)  # the mission in 20 chunks
    follow = Appending(source, tmp_path / "bag", step)
    followed = replay([tmp_path / "bag"], follow=follow)
    assert follow.finished
    assert json_bytes(followed) == json_bytes(replay([tmp_path / "bag"]))
