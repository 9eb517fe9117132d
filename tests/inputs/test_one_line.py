"""An exception as one line of text: the one helper (text.one_line) every reader words its
failures with, and the messages it keeps unchanged where a reader cuts or names the type."""

from __future__ import annotations

import pytest

from medkit_replay.inputs import decompress
from medkit_replay.inputs.decompress import ChunkDamageError, decompress_chunk
from medkit_replay.text import one_line


def test_one_line_joins_whitespace_and_keeps_an_empty_text() -> None:
    assert one_line(ValueError("bad\n  header\tbytes ")) == "bad header bytes"
    assert one_line("a\r\nb") == "a b"
    assert one_line(OSError()) == ""


def test_one_line_cuts_and_names_the_type_when_asked() -> None:
    assert one_line(ValueError("x" * 300), 200) == "x" * 200
    assert one_line(TimeoutError(), or_name=True) == "TimeoutError"
    assert one_line(" \n ", or_name=True) == ""  # a text has no type worth naming


class _Failing:
    """A decompressor whose first call raises ``error``."""

    error: Exception = ValueError()
    eof = needs_input = False
    unused_data = b""

    def decompress(self, data: bytes, /, max_length: int = -1) -> bytes:
        raise self.error


@pytest.mark.parametrize(
    ("error", "reason"),
    [
        (ValueError("frame\nheader is\tbad"), "frame header is bad"),
        (OSError("y" * 500), "y" * 200),
        (EOFError(), "EOFError"),
    ],
)
def test_a_damaged_chunk_names_its_reason_on_one_cut_line(
    monkeypatch: pytest.MonkeyPatch, error: Exception, reason: str
) -> None:
    monkeypatch.setattr(_Failing, "error", error)
    monkeypatch.setitem(decompress._STREAMS, "bz2", _Failing)
    with pytest.raises(ChunkDamageError) as raised:
        decompress_chunk(b"BZh9 not really", "bz2", 10, 0)
    assert str(raised.value) == f"bz2 data is damaged ({reason})"
