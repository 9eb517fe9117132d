"""Red team: MCAP recordings built to exhaust memory or time in the reader and the decoders.

Chunks that decompress past (or short of) their declared size, zero-filled chunks, huge fixed
arrays in recorded definitions, and log times past int64: each run under rlimits.
"""

from __future__ import annotations

import json
import struct
import zlib
from typing import TYPE_CHECKING, Any

import lz4.frame  # type: ignore[import-untyped]
import pytest

from tests.inputs.builders import DIAGNOSTICS, TS, diag
from tests.redteam.support import MIB, run_limited

if TYPE_CHECKING:
    from collections.abc import Sequence
    from pathlib import Path

    from tests.redteam.support import Outcome

try:
    from compression import zstd  # type: ignore[import-not-found,unused-ignore]
except ImportError:
    from backports import zstd  # type: ignore[no-redef,unused-ignore]

MAGIC = b"\x89MCAP0\r\n"
SECOND = 1_000_000_000
MEMORY = 1536 * MIB
HELD_KIB = 700 * 1024
"""Peak RSS no bomb may reach: it counts the forked test process too; the bombs need GiBs."""


# -- a raw MCAP writer: every field under the test's control ------------------------------


def record(op: int, body: bytes) -> bytes:
    return bytes([op]) + struct.pack("<Q", len(body)) + body


def text(value: str | bytes) -> bytes:
    raw = value.encode() if isinstance(value, str) else value
    return struct.pack("<I", len(raw)) + raw


def schema(definition: str, name: str = DIAGNOSTICS, sid: int = 1) -> bytes:
    return record(0x03, struct.pack("<H", sid) + text(name) + text("ros2msg") + text(definition))


def channel(topic: str = "/diagnostics", cid: int = 1, sid: int = 1) -> bytes:
    return record(0x04, struct.pack("<HH", cid, sid) + text(topic) + text("cdr") + text(b""))


def message(t_ns: int, payload: bytes, cid: int = 1) -> bytes:
    return record(0x05, struct.pack("<HIQQ", cid, 0, t_ns, t_ns) + payload)


def diag_payload(t_ns: int, name: str) -> bytes:
    rec = diag(t_ns, name=name)
    return bytes(TS.serialize_cdr(rec.msg, DIAGNOSTICS))


def compress(records: bytes, compression: str) -> bytes:
    if compression == "zstd":
        return bytes(zstd.compress(records))
    if compression == "lz4":
        return bytes(lz4.frame.compress(records))
    return records


def chunk(
    records: bytes,
    *,
    compression: str = "",
    declared: int | None = None,
    data: bytes | None = None,
    times: tuple[int, int] = (0, 0),
    crc: bool = True,
) -> bytes:
    """A chunk record: ``declared`` and ``data`` override the honest size and bytes."""
    size = len(records) if declared is None else declared
    data = compress(records, compression) if data is None else data
    body = struct.pack("<QQQI", *times, size, zlib.crc32(records) if crc else 0)
    return record(0x06, body + text(compression) + struct.pack("<Q", len(data)) + data)


def chunk_summary(head: bytes, parts: Sequence[bytes], times: tuple[int, int]) -> bytes:
    """Schema, channel, one chunk index per chunk in ``parts``, statistics: the indexed route."""
    indexes = []
    offset = len(head)
    for part in parts:
        if part[0] == 0x06:
            start, end = struct.unpack_from("<QQ", part, 9)
            body = struct.pack("<QQQQ", start, end, offset, len(part))
            body += struct.pack("<IHQ", 10, 1, 0) + struct.pack("<Q", 0) + text("")
            indexes.append(record(0x08, body + struct.pack("<QQ", 0, 0)))
        offset += len(part)
    stats = struct.pack("<QHIIIIQQ", 0, 1, 1, 0, 0, len(indexes), *times)
    stats += struct.pack("<IHQ", 10, 1, 0)
    return schema(definition()) + channel() + b"".join(indexes) + record(0x0B, stats)


def mcap_file(
    path: Path, *parts: bytes, indexed: bool = False, times: tuple[int, int] = (0, 0)
) -> Path:
    """Header, the given data records, data end, a summary when ``indexed``, the footer."""
    head = MAGIC + record(0x01, text("ros2") + text("redteam"))
    data = head + b"".join(parts) + record(0x0F, struct.pack("<I", 0))
    summary = chunk_summary(head, parts, times) if indexed else b""
    summary_start = len(data) if summary else 0
    footer = record(0x02, struct.pack("<QQI", summary_start, 0, 0))
    path.write_bytes(data + summary + footer + MAGIC)
    return path


def zstd_zeros(total: int) -> bytes:
    """One zstd frame of ``total`` zero bytes (RLE blocks, 4 bytes per 128 KiB), no size stated."""
    block = 128 * 1024
    head = b"\x28\xb5\x2f\xfd\x00\x38"  # magic; no content size; window 128 KiB
    more = ((block << 3) | 2).to_bytes(3, "little") + b"\0"
    last = ((block << 3) | 3).to_bytes(3, "little") + b"\0"
    return head + more * (total // block - 1) + last


def lz4_zeros(total: int) -> bytes:
    """One LZ4 frame of ``total`` zero bytes (independent 4 MiB blocks), no size stated."""
    step = 4 * MIB
    frame = lz4.frame.compress(
        bytes(step),
        block_size=lz4.frame.BLOCKSIZE_MAX4MB,
        block_linked=False,
        content_checksum=False,
        store_size=False,
    )
    return bytes(frame[:7] + frame[7:-4] * (total // step) + frame[-4:])


def definition() -> str:
    return str(TS.generate_msgdef(DIAGNOSTICS, ros_version=2)[0])


def analyze(path: Path, *extra: str | Path, cpu_seconds: int = 60) -> Outcome:
    return run_limited(
        ["analyze", path, "--json", "-", "--quiet", *extra],
        memory=MEMORY,
        cpu_seconds=cpu_seconds,
        timeout=120,
    )


def report_of(outcome: Outcome) -> dict[str, Any]:
    assert outcome.status == 0, outcome.stderr[-3000:]
    assert "Traceback" not in outcome.stderr, outcome.stderr[-3000:]
    assert "internal error" not in outcome.stderr, outcome.stderr[-3000:]
    report: dict[str, Any] = json.loads(outcome.stdout)
    return report


def fault_codes(report: dict[str, Any]) -> list[str]:
    """The fault codes of the reports that reached the manager, in order."""
    return [str(r["fault_code"]) for r in report["reports"]]


def good(name: str, t_ns: int) -> bytes:
    return message(t_ns, diag_payload(t_ns, name))


def around(bad: bytes, compression: str = "zstd") -> list[bytes]:
    """A good chunk before and after ``bad`` (motor_a at 1 s, motor_c at 3 s), with the schema."""
    before = chunk(good("motor_a", SECOND), compression=compression, times=(SECOND, SECOND))
    after = chunk(good("motor_c", 3 * SECOND), compression=compression, times=(3 * SECOND,) * 2)
    return [schema(definition()) + channel(), before, bad, after]


def cost(outcome: Outcome, label: str) -> None:
    print(f"{label}: peak {outcome.peak_rss_kib} KiB")  # seen with pytest -s


# -- 1. chunks that expand past (or short of) what they declare -----------------------------

BOMBS = {"zstd": (zstd_zeros, 2 << 30), "lz4": (lz4_zeros, 1 << 30)}


@pytest.mark.parametrize("indexed", [False, True], ids=["scanned", "indexed"])
@pytest.mark.parametrize("compression", ["zstd", "lz4"])
def test_chunk_expanding_past_its_declared_size_is_cut_at_it(
    tmp_path: Path, compression: str, indexed: bool
) -> None:
    make, total = BOMBS[compression]
    data = make(total)
    bomb = chunk(b"", compression=compression, declared=1000, data=data, times=(2 * SECOND,) * 2)
    path = mcap_file(
        tmp_path / "bomb.mcap",
        *around(bomb, compression),
        indexed=indexed,
        times=(SECOND, 3 * SECOND),
    )
    outcome = analyze(path)
    cost(outcome, f"{compression} bomb, {indexed=}")
    report = report_of(outcome)
    assert fault_codes(report) == ["MOTOR_A", "MOTOR_C"]
    (warning,) = [w for w in report["warnings"] if "chunk at byte" in w]
    assert str(path) in warning
    assert "expands past its declared 1000 bytes; " in warning
    assert warning.endswith(" from bag time 2.000 s to 2.000 s skipped")
    assert outcome.peak_rss_kib < HELD_KIB  # the expansion was never held


def with_crc(record_bytes: bytes, crc: int) -> bytes:
    """A chunk record with its uncompressed_crc field replaced."""
    return record_bytes[:33] + struct.pack("<I", crc) + record_bytes[37:]


def test_each_damaged_chunk_costs_only_its_own_messages(tmp_path: Path) -> None:
    lost = good("motor_b", 2 * SECOND)
    span = (2 * SECOND, 2 * SECOND)
    damaged = {
        "expands to": chunk(lost, compression="zstd", declared=len(lost) + 100, times=span),
        "not the declared": chunk(lost, compression="lz4", declared=len(lost) - 1, times=span),
        "holds a frame of 1048576 bytes": chunk(
            lost, compression="zstd", data=zstd.compress(bytes(MIB)), times=span
        ),
        "lz4 bytes can give": chunk(lost, compression="lz4", declared=100 * MIB, times=span),
        "claims 1099511627776 bytes uncompressed": chunk(
            lost, compression="zstd", declared=1 << 40, times=span
        ),
        "fails its checksum": with_crc(chunk(lost, compression="zstd", times=span), 1),
        "unsupported compression 'brotli'": chunk(lost, compression="brotli", times=span),
        "zstd data is damaged": chunk(
            lost, compression="zstd", data=b"\x28\xb5\x2f\xfd" + b"\xff" * 40
        ),
    }
    parts = around(b"".join(damaged.values()))
    report = report_of(analyze(mcap_file(tmp_path / "damaged.mcap", *parts)))
    assert fault_codes(report) == ["MOTOR_A", "MOTOR_C"]
    warnings = [w for w in report["warnings"] if "chunk at byte" in w]
    assert len(warnings) == len(damaged), warnings
    for needle in damaged:
        assert sum(needle in w for w in warnings) == 1, (needle, warnings)


# -- 3. chunks of zero bytes: no records at all --------------------------------------------


@pytest.mark.parametrize(
    ("compression", "size", "indexed"),
    [("", 64 * MIB, False), ("zstd", 256 * MIB, True)],
    ids=["plain-scanned", "zstd-indexed"],
)
def test_zero_filled_chunk_is_given_up_at_its_first_byte(
    tmp_path: Path, compression: str, size: int, indexed: bool
) -> None:
    data = zstd_zeros(size) if compression else None
    zeros = chunk(
        bytes(size) if not compression else b"",
        compression=compression,
        declared=size,
        data=data,
        crc=False,
        times=(2 * SECOND, 2 * SECOND),
    )
    path = mcap_file(
        tmp_path / "zeros.mcap", *around(zeros), indexed=indexed, times=(SECOND, 3 * SECOND)
    )
    outcome = analyze(path, cpu_seconds=20)  # walked as 9-byte records, it took 40 s and more
    cost(outcome, f"zero chunk {compression or 'plain'}")
    report = report_of(outcome)
    assert fault_codes(report) == ["MOTOR_A", "MOTOR_C"]
    (warning,) = [w for w in report["warnings"] if "chunk at byte" in w]
    assert str(path) in warning
    assert f"invalid opcode 0x00 at byte 0 of its records ({size} bytes)" in warning


# -- 2. recorded definitions whose decoders would cost more than any payload ----------------

NOTHING = "=" * 80 + "\nMSG: custom_msgs/Nothing\n"
WIDE = "=" * 80 + "\nMSG: custom_msgs/Wide\ncustom_msgs/Nothing[100] n\n"
LOOP = "=" * 80 + "\nMSG: custom_msgs/Loop\ncustom_msgs/Loop[] more\n"


@pytest.mark.parametrize(
    ("field", "extra_types", "needle"),
    [
        ("string[100000] x", "", "fixed array std_msgs/msg/Header.x of 100000 elements"),
        ("custom_msgs/Wide[100] w", WIDE + NOTHING, "decoding steps per message"),
        ("custom_msgs/Nothing[] n", NOTHING, "sequence std_msgs/msg/Header.n of"),
        ("custom_msgs/Loop l", LOOP, "custom_msgs/msg/Loop contains itself"),
        ("uint8[2000000000] x", "", "needs at least 2000000013 bytes per message"),
    ],
    ids=["strings", "nested-empty", "sequence-of-empty", "self", "two-gigabytes"],
)
def test_definition_bomb_is_refused_and_the_topic_read_as_bundled(
    tmp_path: Path, field: str, extra_types: str, needle: str
) -> None:
    hostile = definition().replace("string frame_id\n", f"string frame_id\n{field}\n", 1)
    parts = around(b"")
    parts[0] = schema(hostile + "\n" + extra_types) + channel()
    outcome = analyze(mcap_file(tmp_path / "definition.mcap", *parts))
    cost(outcome, f"definition {field}")
    report = report_of(outcome)
    assert fault_codes(report) == ["MOTOR_A", "MOTOR_C"]
    (warning,) = [w for w in report["warnings"] if "recorded definition unusable" in w]
    assert "/diagnostics" in warning
    assert needle in warning


def test_fixed_array_of_a_billion_bytes_costs_nothing_before_its_data(tmp_path: Path) -> None:
    hostile = definition().replace("string frame_id\n", "string frame_id\nuint8[1000000000] x\n")
    parts = around(b"")
    parts[0] = schema(hostile) + channel()
    outcome = analyze(mcap_file(tmp_path / "definition.mcap", *parts))
    cost(outcome, "definition uint8[1000000000]")
    report = report_of(outcome)
    assert fault_codes(report) == ["MOTOR_A", "MOTOR_C"]  # the bundled definition fits them
    assert outcome.peak_rss_kib < HELD_KIB


def test_sequence_length_past_the_payload_allocates_nothing(tmp_path: Path) -> None:
    payload = bytearray(diag_payload(2 * SECOND, "motor_b"))
    assert struct.unpack_from("<I", payload, 20) == (1,)  # the status count
    payload[20:24] = struct.pack("<I", 2**32 - 1)
    bad = chunk(message(2 * SECOND, bytes(payload)), times=(2 * SECOND, 2 * SECOND))
    outcome = analyze(mcap_file(tmp_path / "sequence.mcap", *around(bad)))
    cost(outcome, "sequence of 2^32-1")
    report = report_of(outcome)
    assert fault_codes(report) == ["MOTOR_A", "MOTOR_C"]
    (warning,) = report["warnings"]
    assert "1 messages on /diagnostics cannot be decoded" in warning
    assert "sequence length 4294967295" in warning
    assert outcome.peak_rss_kib < HELD_KIB


# -- 4. log times past int64 -------------------------------------------------------------------

LATE = [2**63, 2**64 - 1]


def late_file(path: Path, t_ns: int, route: str) -> Path:
    """motor_a (1 s), motor_b (2 s), motor_x at ``t_ns``, motor_c (3 s), laid out per route."""
    late = message(t_ns, diag_payload(2 * SECOND, "motor_x"))
    if route == "top-level":
        records = good("motor_a", SECOND) + good("motor_b", 2 * SECOND) + late
        return mcap_file(path, *around(records)[:1], records, good("motor_c", 3 * SECOND))
    middle = chunk(good("motor_b", 2 * SECOND) + late, compression="zstd", times=(2 * SECOND, t_ns))
    stats = (SECOND, t_ns if route == "indexed-statistics" else 3 * SECOND)
    return mcap_file(path, *around(middle), indexed=route != "chunk", times=stats)


@pytest.mark.parametrize("route", ["top-level", "chunk", "indexed", "indexed-statistics"])
@pytest.mark.parametrize("t_ns", LATE, ids=["2^63", "2^64-1"])
def test_log_time_past_int64_is_damage_and_the_rest_is_kept(
    tmp_path: Path, t_ns: int, route: str
) -> None:
    path = late_file(tmp_path / "late.mcap", t_ns, route)
    report = report_of(analyze(path))
    assert fault_codes(report) == ["MOTOR_A", "MOTOR_B", "MOTOR_C"]
    (summary,) = report["inputs"]
    assert (summary["start_ns"], summary["end_ns"]) == (SECOND, 3 * SECOND)
    (warning,) = [w for w in report["warnings"] if "2^63 ns" in w and "skipped" in w]
    assert str(path) in warning
    assert "at byte" in warning
    assert f"({t_ns})" in warning
    if route == "indexed-statistics":
        assert any("summary section holds log times" in w for w in report["warnings"])


def test_late_log_time_reaches_no_output(tmp_path: Path) -> None:
    path = late_file(tmp_path / "late.mcap", 2**64 - 1, "chunk")
    out = tmp_path / "out"
    outcome = analyze(
        path,
        "--parquet",
        out / "parquet",
        "--html",
        out / "report.html",
        "--mcap",
        out / "report.mcap",
    )
    report = report_of(outcome)
    assert fault_codes(report) == ["MOTOR_A", "MOTOR_B", "MOTOR_C"]
    assert "saturated" not in outcome.stderr
    assert (out / "report.html").is_file()
    assert (out / "report.mcap").is_file()
