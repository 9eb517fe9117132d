"""Everything taken from rosbags beyond its public API, behind one module (rosbags >= 0.11.6).

Each name is pinned by tests/inputs/test_rosbags_internals.py; a rosbags release that moves
one breaks that test, not a decoder somewhere.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from rosbags.serde import primitives
from rosbags.serde.utils import SIZEMAP as _SIZEMAP, align as _align, align_after as _align_after

if TYPE_CHECKING:
    from collections.abc import Callable

    from rosbags.interfaces.typing import FieldDesc
    from rosbags.typesys.store import Typestore

SIZEMAP: dict[str, int] = {str(name): size for name, size in _SIZEMAP.items()}
"""Bytes of each primitive type in CDR (``rosbags.serde.utils.SIZEMAP``)."""


def unpack_le(typ: str) -> Callable[[bytes, int], tuple[Any, ...]]:
    """rosbags' little-endian reader of one primitive: ``struct.Struct(...).unpack_from``.

    Raises:
        AttributeError: rosbags has no reader for ``typ``.
    """
    unpack: Callable[[bytes, int], tuple[Any, ...]] = getattr(primitives, f"unpack_{typ}_le")
    return unpack


def align(desc: FieldDesc, store: Typestore) -> int:
    """The alignment a field starts at in CDR, as rosbags computes it."""
    return _align(desc, store)


def align_after(desc: FieldDesc, store: Typestore) -> int:
    """The alignment known to hold right after a field in CDR, as rosbags computes it."""
    return _align_after(desc, store)


def max_sequence_length(store: Typestore) -> int:
    """The longest sequence ``store``'s decoders accept (rosbags refuses longer counts)."""
    return store.max_sequence_length
