"""Every sample and fixture recording, replayed and compared with the plain oracle's conclusions.

Same engine sections of the report; same messages field by field as the oracle reads and
decodes them (rosbags, where it reads the recording), and the same messages and warnings whether
MCAP chunks are read through their message indexes or whole.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

from medkit_replay.errors import InputError
from medkit_replay.inputs import Message, Selection, open_recording
from medkit_replay.pipeline import replay
from tests.oracle.replay import oracle_messages
from tests.speed.support import FIXTURES, RULES, SAMPLES, plain, report_both_ways

if TYPE_CHECKING:
    from pathlib import Path

RECORDINGS = SAMPLES + FIXTURES
IDS = [p.name for p in RECORDINGS]


@pytest.fixture(scope="module")
def log_bridge_on(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("configs") / "log_bridge.yaml"
    path.write_text("medkit_replay:\n  ros__parameters:\n    enable_log_bridge: true\n")
    return path


@pytest.mark.parametrize("recording", RECORDINGS, ids=IDS)
@pytest.mark.parametrize("configs", ["defaults", "log_bridge", "nav2_rules"])
def test_the_replay_concludes_what_the_oracle_does(
    recording: Path, configs: str, log_bridge_on: Path
) -> None:
    chosen = {
        "defaults": [],
        "log_bridge": [log_bridge_on],
        "nav2_rules": [RULES / "fault_manager.yaml", RULES / "bridges.yaml"],
    }[configs]
    try:
        reference, fast = report_both_ways([recording], chosen)
    except InputError:
        with pytest.raises(InputError):
            replay([recording], chosen)
        return
    assert fast == reference


def test_several_inputs_merged_conclude_what_the_oracle_does(log_bridge_on: Path) -> None:
    inputs = [SAMPLES[0], *(p for p in FIXTURES if p.name.startswith(("talker", "service")))]
    reference, fast = report_both_ways(inputs, [log_bridge_on])
    assert fast == reference


def _messages(recording: Path, *, use_index: bool) -> tuple[list[tuple[object, ...]], list[str]]:
    with open_recording(
        [recording], rosout=True, use_index=use_index, extra_topics=["/chatter"]
    ) as opened:
        messages = [_fields(m) for m in opened.messages()]
        return messages, list(opened.warnings)


def _fields(m: Message) -> tuple[object, ...]:
    return (m.t_ns, m.input_index, m.topic, m.msgtype, m.role, plain(m.msg))


@pytest.mark.parametrize("recording", RECORDINGS, ids=IDS)
def test_messages_equal_the_oracles(recording: Path) -> None:
    try:
        messages, warnings = _messages(recording, use_index=True)
    except InputError:
        return
    assert _messages(recording, use_index=False) == (messages, warnings)
    selection = Selection(rosout=True, extra_topics=("/chatter",))
    assert [_fields(m) for m in oracle_messages([recording], selection)] == messages
