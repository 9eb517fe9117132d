"""What every kind of input provides: the decoded Message, the Input protocol, how one is opened.

Declarations only; the rosbag2 inputs implement them, and a JSON-lines input may plug in too.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple, Protocol, TypeAlias

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator
    from pathlib import Path

    from medkit_replay.inputs.merge import Timed
    from medkit_replay.inputs.selection import Role, Selection
    from medkit_replay.model import InputSummary, Loss
    from medkit_replay.releases import Release


class Message(NamedTuple):
    """One decoded message of the merged stream.

    Attributes:
        t_ns: log (receive) time in bag time, nanoseconds.
        input_index: position of its input in the list given to ``open_recording``.
        topic: the recorded topic name.
        msgtype: its type, spelled ``pkg/msg/Name`` (old spellings normalised).
        role: why it was read (:data:`~medkit_replay.inputs.selection.Role`).
        msg: the message as decoded by rosbags (fields as in its definition).
    """

    t_ns: int
    input_index: int
    topic: str
    msgtype: str
    role: Role
    msg: object


class Warn(Protocol):
    """Told each loss or oddity in one line; damage comes with what it cost (:class:`Loss`),
    which the recording adds to the line and keeps for the result."""

    def __call__(self, text: str, loss: Loss | None = None, /) -> None: ...


class InputContext(NamedTuple):
    """What an input needs from the recording that opens it.

    Attributes:
        use_index: read uncompressed MCAP and ROS 1 bag chunks through their message indexes
            (False: every chunk is read whole, the route the index must agree with).
        release: the upstream release modelled (None: the newest): its ros2_medkit_msgs
            decode what a recording stores no definition for.
    """

    input_index: int
    selection: Selection
    warn: Warn
    use_index: bool = True
    release: Release | None = None


class Input(Protocol):
    """One opened input: a stream sorted by (log time, position), a summary, a close."""

    def messages(self) -> Iterator[Timed[Message]]:
        """Yield the selected messages once, sorted by ``(t_ns, position)``."""
        ...

    def summary(self) -> InputSummary:
        """What the input holds; complete once :meth:`messages` is exhausted."""
        ...

    def close(self) -> None:
        """Release files and temporary copies; safe to call twice."""
        ...


Opener: TypeAlias = "Callable[[Path, InputContext], Input]"
"""Opens one input path; raises InputError when nothing at all can be read from it."""
