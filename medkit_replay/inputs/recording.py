"""A recording: several inputs opened together and merged into one time-ordered message stream.

Chooses a reader per input through READERS (a URL: inputs.remote.bag); the only place inputs are
opened and closed.
"""

from __future__ import annotations

from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING

from medkit_replay.closing import Closing
from medkit_replay.errors import InputError
from medkit_replay.files import is_remote
from medkit_replay.inputs.merge import merge
from medkit_replay.inputs.rosbag2 import open_directory, open_file
from medkit_replay.inputs.script import open_script_input
from medkit_replay.inputs.selection import Selection
from medkit_replay.inputs.source import InputContext, Warn
from medkit_replay.inputs.tail import open_tail

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Iterator

    from medkit_replay.inputs.follow import Follow
    from medkit_replay.inputs.remote.store import Tally
    from medkit_replay.inputs.selection import Role
    from medkit_replay.inputs.source import Input, Message, Opener
    from medkit_replay.model import InputSummary, Loss
    from medkit_replay.releases import Release


def open_bag1(path: Path, ctx: InputContext) -> Input:
    """Open a ROS 1 bag; its reader (and the ROS 1 type store) loads with the first one."""
    from medkit_replay.inputs.ros1.bag import open_bag1 as open_ros1  # noqa: PLC0415

    return open_ros1(path, ctx)


READERS: dict[str, Opener] = {
    "dir": open_directory,
    ".mcap": open_file,
    ".db3": open_file,
    ".bag": open_bag1,
    ".jsonl": open_script_input,
}
"""Input openers by kind: ``dir`` for a directory, else the file's lower-cased suffix."""


def input_kind(path: Path) -> str:
    """The READERS key for a path: ``dir`` or its lower-cased suffix (``.bag`` for a ROS 1 bag
    ``rosbag record`` left as ``NAME.bag.active``: still recording, or stopped unindexed)."""
    if path.is_dir():
        return "dir"
    if path.name.lower().endswith(".bag.active"):
        return ".bag"
    return path.suffix.lower()


class Recording(Closing):
    """Opened inputs read as one recording; use as a context manager.

    Attributes:
        warnings: what the user should know, in the order found (losses, skipped topics...).
        losses: what damage cost, one entry per damage warning, in the same order.
    """

    def __init__(self, inputs: list[Input], warnings: list[str], losses: list[Loss]) -> None:
        self._inputs = inputs
        self.warnings = warnings
        self.losses = losses
        self._used = False

    def messages(self) -> Iterator[Message]:
        """Yield every selected message of every input once, ordered by (log time, input, position).

        Raises:
            RuntimeError: called a second time.
        """
        if self._used:
            raise RuntimeError("Recording.messages() can be read only once")
        self._used = True
        if len(self._inputs) == 1:
            plain: Callable[[], Iterator[Message]] | None = getattr(
                self._inputs[0], "plain_messages", None
            )
            if plain is not None:
                return plain()
            return (timed.item for timed in self._inputs[0].messages())
        return (merged.item for merged in merge([i.messages() for i in self._inputs]))

    def message_tuples(self) -> Iterator[tuple[int, int, str, str, Role, object]]:
        """:meth:`messages` as plain tuples laid out as Message: the replay's fast path.

        Raises:
            RuntimeError: the messages were already read.
        """
        if len(self._inputs) == 1:
            tuples: Callable[[], Iterator[tuple[int, int, str, str, Role, object]]] | None = (
                getattr(self._inputs[0], "message_tuples", None)
            )
            if tuples is not None:
                if self._used:
                    raise RuntimeError("Recording.messages() can be read only once")
                self._used = True
                return tuples()
        return iter(self.messages())

    @property
    def span(self) -> tuple[int, int] | None:
        """First and last log time (ns) of the whole recording, as known before reading.

        Taken from what the inputs declare when opened (an MCAP summary, a ``.db3``'s index),
        so it costs nothing and covers every topic, read or not. None when any input does not
        declare its span up front (a script, an MCAP file without a summary): a partial span
        would be wrong about the recording's end. Informational only (progress, ETA).
        """
        starts: list[int] = []
        ends: list[int] = []
        for opened in self._inputs:
            summary = opened.summary()
            if summary.start_ns is None or summary.end_ns is None:
                return None
            starts.append(summary.start_ns)
            ends.append(summary.end_ns)
        if not starts:
            return None
        return min(starts), max(ends)

    @property
    def inputs(self) -> tuple[InputSummary, ...]:
        """One summary per input, in input order; final once :meth:`messages` is exhausted."""
        return tuple(i.summary() for i in self._inputs)

    def close(self) -> None:
        """Close every input (temporary copies are deleted); safe to call twice."""
        for opened in self._inputs:
            opened.close()


def open_recording(
    paths: Iterable[str | Path],
    *,
    rosout: bool = False,
    rosout_topic: str = "/rosout",
    diagnostics_topics: Iterable[str] = ("/diagnostics",),
    extra_topics: Iterable[str] = (),
    only_roles: Iterable[Role] | None = None,
    use_index: bool = True,
    follow: Follow | None = None,
    tallies: dict[str, Tally] | None = None,
    release: Release | None = None,
) -> Recording:
    """Open inputs to be read as one recording.

    Args:
        paths: rosbag2 directories, ``.mcap`` or ``.db3`` files, ROS 1 ``.bag`` files (any kind
            READERS knows), or ``s3://``, ``gs://``, ``http(s)://`` URLs of a bag folder or
            storage file.
        rosout: also read ``/rosout`` (for the log bridge).
        diagnostics_topics: topics of type DiagnosticArray to read.
        extra_topics: further topics to read whatever their type (role ``extra``).
        only_roles: read only topics of these roles (None: every role).
        use_index: read uncompressed MCAP chunks through their message indexes (False:
            every chunk is read whole; the messages are the same).
        follow: read the inputs while they are written, waiting for more as it says
            (:mod:`medkit_replay.inputs.tail`); None: read them as they stand.
        tallies: bytes fetched for remote inputs are counted here, by URL (give the same
            dict to several passes over the same inputs to count them all).
        release: the upstream release modelled (None: the newest): its ros2_medkit_msgs
            decode what a recording stores no definition for, and a recorded FaultEvent
            definition of another release is pointed out.

    Returns:
        The opened recording; close it (``with``) to release files and temporary copies.

    Raises:
        InputError: no input given, an input is missing or of an unknown kind, or nothing at
            all can be read from one; the inputs opened before it are closed again.
    """
    selection = Selection(
        rosout=rosout,
        rosout_topic=rosout_topic,
        diagnostics_topics=tuple(diagnostics_topics),
        extra_topics=tuple(extra_topics),
        only_roles=frozenset(only_roles) if only_roles is not None else None,
    )
    warnings: list[str] = []
    losses: list[Loss] = []

    def sink(name: str) -> Warn:
        def warn(text: str, loss: Loss | None = None, /) -> None:
            if loss is not None:
                losses.append(replace(loss, input=name))
                text = f"{text}; {loss.text()}"
            warnings.append(" ".join(text.splitlines()))  # one line each, whatever a file held

        return warn

    inputs: list[Input] = []
    try:
        for index, raw_path in enumerate(paths):
            if is_remote(raw_path):
                context = InputContext(
                    index, selection, sink(str(raw_path)), use_index=use_index, release=release
                )
                # The remote reader (threads, the optional store client) loads with a URL only.
                from medkit_replay.inputs.remote.bag import open_remote  # noqa: PLC0415

                inputs.append(open_remote(str(raw_path), context, tallies))
                continue
            path = Path(raw_path)
            if not path.exists():
                raise InputError("input not found", path=str(path))
            opener = (
                READERS.get(input_kind(path))
                if follow is None
                else partial(open_tail, follow=follow)
            )
            if opener is None:
                kinds = ", ".join(sorted(k for k in READERS if k != "dir"))
                raise InputError(
                    f"unsupported input (expected a rosbag2 directory or a {kinds} file)",
                    path=str(path),
                )
            context = InputContext(
                index, selection, sink(str(path)), use_index=use_index, release=release
            )
            try:
                inputs.append(opener(path, context))
            except OSError as exc:
                raise InputError(
                    f"cannot be read ({exc.strerror or exc})", path=str(path)
                ) from None
        if not inputs:
            raise InputError("no input given")
    except BaseException:
        for opened in inputs:
            opened.close()
        raise
    return Recording(inputs, warnings, losses)
