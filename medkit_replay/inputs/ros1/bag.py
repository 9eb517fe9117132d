"""ROS 1 bag inputs (``.bag``): topics selected, decoded into the ROS 2 shapes the bridges read.

Reading the file is ros1.file's; this layer chooses and decodes, never touching the file.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

from medkit_replay.errors import InputError
from medkit_replay.inputs.merge import Timed, reorder_batches
from medkit_replay.inputs.ros1.decoders import DECODERS
from medkit_replay.inputs.ros1.file import Bag1File
from medkit_replay.inputs.ros1.messages import TRANSLATIONS, ros1_typestore, standard_md5
from medkit_replay.inputs.skipped import report_skipped
from medkit_replay.inputs.source import Message
from medkit_replay.inputs.storage import NotABagError
from medkit_replay.model import InputSummary, Loss, TopicSummary
from medkit_replay.msgdefs import normalize_typename
from medkit_replay.text import one_line

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator
    from pathlib import Path

    from medkit_replay.inputs.merge import Bound
    from medkit_replay.inputs.ros1.file import Raw1
    from medkit_replay.inputs.ros1.records import Ros1Connection
    from medkit_replay.inputs.selection import Role
    from medkit_replay.inputs.source import InputContext

STORAGE = "rosbag1"
MAX_HELD = 100_000
"""Most messages held to restore time order; beyond it the oldest leaves, later ones may be late."""
ROS1_ROLES: frozenset[Role] = frozenset({"diagnostics", "action_status", "rosout", "extra"})
"""The roles a ROS 1 bag's topics can have (ROS 1 has no ros2_medkit service events)."""


class _Reader(NamedTuple):
    """How one connection's messages are replayed."""

    role: Role
    topic: str
    msgtype: str
    decode: Callable[[bytes], object]


def open_bag1(path: Path, ctx: InputContext) -> Rosbag1Input:
    """Open a ROS 1 bag.

    Raises:
        InputError: the file is not a ROS 1 bag (format 2.0) or its bag header is unreadable.
        OSError: the file cannot be opened.
    """
    return Rosbag1Input(path, ctx)


class Rosbag1Input:
    """One ROS 1 bag read as a stream sorted by (log time, position); see ``Input``."""

    def __init__(self, path: Path, ctx: InputContext) -> None:
        self.path = path
        self.ctx = ctx
        self._readers: dict[int, _Reader | None] = {}
        self._warned: set[str] = set()
        self._failures: dict[str, tuple[int, int, int, str]] = {}
        self._late: tuple[int, int] = (0, 0)
        self._used = False
        try:
            self._bag = Bag1File(
                path,
                self._warn,
                lambda cid: self._reader(cid) is not None,
                indexed=ctx.use_index,
            )
        except NotABagError as exc:
            raise InputError(str(exc), path=str(path)) from None

    def _warn(self, text: str, loss: Loss | None = None, /) -> None:
        text = f"{self.path}: {text}"
        if text not in self._warned:
            self._warned.add(text)
            self.ctx.warn(text, loss)

    def _reader(self, cid: int) -> _Reader | None:
        """How a connection is replayed, decided when its first message is met (None: not read)."""
        if cid in self._readers:
            return self._readers[cid]
        connection = self._bag.connections[cid]
        reader = self._readers[cid] = self._make_reader(connection)
        return reader

    def _make_reader(self, connection: Ros1Connection) -> _Reader | None:
        ros1_type = normalize_typename(connection.msgtype)
        translation = TRANSLATIONS.get(ros1_type)
        topic, msgtype = connection.topic, ros1_type
        if translation is not None:
            topic, msgtype = translation.topic(connection.topic), translation.ros2_type
        selection = self.ctx.selection
        role, reason = selection.classify(topic, msgtype)
        if role is None and connection.topic in selection.extra_topics:
            role, reason, topic = "extra", None, connection.topic
        if role is None:
            if reason:
                self._warn(reason)
            return None
        store = ros1_typestore()
        if ros1_type not in store.fielddefs:
            self._warn(f"topic {connection.topic} has type {ros1_type}, unknown to ROS 1 Noetic")
            return None
        if translation is not None and connection.md5sum not in ("*", standard_md5(ros1_type)):
            self._warn(
                f"topic {connection.topic}: type {connection.msgtype} recorded with md5sum "
                f"{connection.md5sum!r}, not the standard one; decoded with the standard definition"
            )
        fast = DECODERS.get(ros1_type)
        if fast is not None:
            return _Reader(role, topic, msgtype, fast)
        deserialize = store.deserialize_ros1
        if translation is None:
            return _Reader(role, topic, msgtype, lambda raw: deserialize(raw, ros1_type))
        convert = translation.convert
        return _Reader(role, topic, msgtype, lambda raw: convert(deserialize(raw, ros1_type)))

    # -- reading -------------------------------------------------------------------------------

    def messages(self) -> Iterator[Timed[Message]]:
        """Yield the selected, decoded messages once, sorted by (log time, position).

        Raises:
            RuntimeError: called a second time.
        """
        self._claim()
        return self._stream(timed=True)  # type: ignore[return-value]  # Timed items

    def message_tuples(self) -> Iterator[tuple[int, int, str, str, Role, object]]:
        """:meth:`messages` as plain tuples laid out as Message, without their positions (a
        recording of one input needs none; cheaper to build)."""
        self._claim()
        return self._stream(timed=False)  # type: ignore[return-value]  # tuples

    def _claim(self) -> None:
        if self._used:
            raise RuntimeError(f"{self.path}: messages() can be read only once")
        self._used = True

    def _stream(
        self, *, timed: bool
    ) -> Iterator[Timed[Message] | tuple[int, int, str, str, Role, object]]:
        input_index, readers = self.ctx.input_index, self._readers
        try:
            for batch in reorder_batches(self._guarded_scan(), self._on_late, MAX_HELD):
                for t_ns, position, raw in batch:
                    reader = readers[raw.connection]
                    assert reader is not None
                    try:
                        msg = reader.decode(raw.data)
                    except ImportError:
                        raise  # the environment, not the bag
                    except Exception as exc:  # rosbags raises struct.error, IndexError, ...
                        self._failed(reader.topic, t_ns, exc)
                        continue
                    topic, msgtype, role = reader.topic, reader.msgtype, reader.role
                    if timed:
                        message = Message(t_ns, input_index, topic, msgtype, role, msg)
                        yield Timed(t_ns, position, message)
                    else:
                        yield (t_ns, input_index, topic, msgtype, role, msg)
        finally:
            self._report_losses()

    def _guarded_scan(self) -> Iterator[Bound | list[Timed[Raw1]]]:
        only = self.ctx.selection.only_roles
        if only is not None and not only & ROS1_ROLES:
            return  # e.g. the pre-pass over recorded service calls, which ROS 1 has none of
        try:
            yield from self._bag.scan()
        except Exception as exc:  # last resort: no reader failure may end the replay
            self._warn(f"reading stopped ({type(exc).__name__}: {exc})", Loss())

    def _on_late(self, item: Timed[Raw1]) -> None:
        count, first = self._late
        self._late = (count + 1, first if count else item.t_ns)

    def _failed(self, topic: str, t_ns: int, exc: Exception) -> None:
        reason = one_line(exc, or_name=True)
        count, first, _, why = self._failures.get(topic, (0, t_ns, t_ns, reason))
        self._failures[topic] = (count + 1, first, t_ns, why)

    def _report_losses(self) -> None:
        orphans = self._bag.orphans
        report_skipped(self._warn, self._failures, (0, 0))  # the order of old: orphans between
        if orphans:
            self._warn(
                f"{orphans} messages belong to connections whose records are lost "
                "(kept only in the missing index?); they cannot be decoded",
                Loss(messages=orphans),
            )
        report_skipped(self._warn, {}, self._late)

    # -- summary -------------------------------------------------------------------------------

    def summary(self) -> InputSummary:
        """Topics (as recorded, with the role of those read), counts and time span."""
        counts: dict[tuple[str, str], int] = {}
        roles: dict[tuple[str, str], Role] = {}
        bag = self._bag
        for cid, connection in bag.connections.items():
            key = (connection.topic, normalize_typename(connection.msgtype))
            counts[key] = counts.get(key, 0) + bag.counts.get(cid, 0)
            reader = self._readers.get(cid)
            if reader is not None:
                roles[key] = reader.role
        return InputSummary(
            path=str(self.path),
            storage=STORAGE,
            start_ns=bag.start_ns,
            end_ns=bag.end_ns,
            message_count=sum(bag.counts.values()),
            topics=tuple(
                TopicSummary(topic=topic, type=msgtype, role=roles.get(key), messages=count)
                for key, count in sorted(counts.items())
                for topic, msgtype in (key,)
            ),
        )

    def close(self) -> None:
        """Close the file; safe to call twice."""
        self._bag.close()
