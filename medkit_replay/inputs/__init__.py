"""Inputs: recording files turned into one time-ordered stream of decoded, typed messages.

rosbag2 directories (metadata.yaml; sqlite3 or MCAP storage; split files; zstd file or message
compression), bare ``.mcap`` / ``.db3`` files and ROS 1 ``.bag`` files (their messages mapped to
the ROS 2 types the bridges read) are read streaming and read-only; several inputs
merge in (log time, input index, position) order. Only the topics the replay needs are decoded
(:class:`Selection`), by decoders generated from the recording's own definitions or bundled
ones (rosbags decodes the types they do not cover and big-endian payloads). Uncompressed MCAP
chunks are read through their message indexes. Any of these may be named by an ``s3://``,
``gs://`` or ``http(s)://`` URL instead (:mod:`medkit_replay.inputs.remote.bag`, the ``remote``
extra): an indexed MCAP is then fetched by ranges, other storage files through a temporary copy.
Damage costs what it destroyed and is said in ``Recording.warnings``, what it cost (messages,
bytes, bag time, where known) in ``Recording.losses``; an input of which nothing can be read
raises :class:`~medkit_replay.errors.InputError`. A recording still being written is followed
with ``open_recording(..., follow=Follow())``: its files are read as they grow and appear
(``tail.py``), never locked or changed, until it is finished or the :class:`Follow` stops.

    with open_recording(["run_bag/"], rosout=True) as recording:
        for message in recording.messages():
            ...
        summaries = recording.inputs
"""

from medkit_replay.files import is_remote
from medkit_replay.inputs.follow import Follow
from medkit_replay.inputs.recording import READERS, Recording, input_kind, open_recording
from medkit_replay.inputs.selection import Role, Selection
from medkit_replay.inputs.source import Input, InputContext, Message, Opener
from medkit_replay.msgdefs import normalize_typename

__all__ = [
    "READERS",
    "Follow",
    "Input",
    "InputContext",
    "Message",
    "Opener",
    "Recording",
    "Role",
    "Selection",
    "input_kind",
    "is_remote",
    "normalize_typename",
    "open_recording",
]
