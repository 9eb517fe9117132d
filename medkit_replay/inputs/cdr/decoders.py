"""Which decoder a recorded type gets: the hand-written DiagnosticArray decoder for the standard
layout, else one generated from the definition (``cdr.generator``), cached per typestore.

Types the generator does not cover get none: rosbags decodes those.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from medkit_replay.inputs.cdr.diagnostics import (
    DIAGNOSTIC_ARRAY,
    DiagnosticArrayView,
    diagnostic_array,
    layout,
)
from medkit_replay.inputs.cdr.generator import generate
from medkit_replay.inputs.cdr.refusals import (
    REFUSALS,
    RejectedError,
    UnsupportedError,
    sequence_refusal,
    string_refusal,
)
from medkit_replay.msgdefs import reference_types

if TYPE_CHECKING:
    from collections.abc import Callable

    from rosbags.typesys.store import Typestore

__all__ = [
    "DIAGNOSTIC_ARRAY",
    "REFUSALS",
    "DiagnosticArrayView",
    "RejectedError",
    "UnsupportedError",
    "generate",
    "generated_decoder",
    "sequence_refusal",
    "string_refusal",
]


_SPECIAL: dict[str, Callable[[Typestore], Callable[[bytes], object]]] = {
    DIAGNOSTIC_ARRAY: diagnostic_array,
}
"""Hand-written decoders, used when a recording's definition has the standard layout."""


def _standard(msgtype: str, store: Typestore) -> bool:
    try:
        return layout(store.fielddefs, msgtype) == layout(reference_types(), msgtype)
    except (KeyError, TypeError, ValueError):
        return False


_CACHE: dict[tuple[str, int], tuple[Typestore, Callable[[bytes], object] | None]] = {}
_CACHE_SIZE = 1024


def generated_decoder(msgtype: str, store: Typestore) -> Callable[[bytes], object] | None:
    """The decoder of ``msgtype`` in ``store`` (cached per store), or None if unsupported.

    It takes plain little-endian CDR (encapsulation header ``00 01``) and raises one of
    :data:`REFUSALS` on a payload that does not fit the definition.
    """
    key = (msgtype, id(store))
    cached = _CACHE.get(key)
    if cached is None:
        try:
            special = _SPECIAL.get(msgtype)
            if special is not None and _standard(msgtype, store):
                decode: Callable[[bytes], object] | None = special(store)
            else:
                decode = generate(msgtype, store)[0]
        except UnsupportedError:
            decode = None
        if len(_CACHE) >= _CACHE_SIZE:
            _CACHE.clear()
        cached = _CACHE[key] = (store, decode)  # holding the store keeps its id unique
    return cached[1]
