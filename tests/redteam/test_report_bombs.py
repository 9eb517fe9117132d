"""Compressed reports read back (``diff``, ``diff --update``, golden reports): bombs refused at
the report size limit with little memory, concatenated frames and members read as zstd -d does.

Bombs run in a child process under ``resource.setrlimit`` (tests/redteam/support.py).
"""

from __future__ import annotations

import gzip
import textwrap
import zlib
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
import zstandard

from medkit_replay.cli import main
from medkit_replay.diffing.reports import EXPANSION_FLOOR, MAX_EXPANSION, report_bytes
from medkit_replay.files import MIB
from tests.redteam.support import Outcome, assert_one_line_error, run_limited

if TYPE_CHECKING:
    from collections.abc import Callable

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "nav2_mission.jsonl"
NAV2 = ROOT / "rules" / "nav2" / "fault_manager.yaml"
BOMB_SIZE = 3 << 30
"""What each bomb expands to: 3 GiB, twice the memory the child may use."""
SMALL_PEAK_KIB = 400 * 1024
"""A refused bomb costs no more than the interpreter and the replay's modules do."""
LIMIT_HINT = "raise it with --max-report-mb or MEDKIT_REPLAY_MAX_REPORT_MB"


def zstd_bomb(total: int) -> bytes:
    """One zstd frame: '{' (a raw block), then ``total`` spaces as RLE blocks (4 bytes per
    128 KiB); no content size stated."""
    block = 128 * 1024
    head = b"\x28\xb5\x2f\xfd\x00\x38"  # magic; no content size; window 128 KiB
    brace = (1 << 3).to_bytes(3, "little") + b"{"
    more = ((block << 3) | 2).to_bytes(3, "little") + b" "
    last = ((block << 3) | 3).to_bytes(3, "little") + b" "
    return head + brace + more * (total // block - 1) + last


def gzip_bomb(total: int) -> bytes:
    """One gzip member: '{' then ``total`` spaces, the same flushed deflate block of 1 MiB
    repeated (about 1,000 times smaller). Its trailer is never reached: the CRC is left 0."""
    packer = zlib.compressobj(9, zlib.DEFLATED, -15)
    brace = packer.compress(b"{") + packer.flush(zlib.Z_FULL_FLUSH)
    spaces = packer.compress(b" " * MIB) + packer.flush(zlib.Z_FULL_FLUSH)
    end = packer.flush()
    size = (1 + total) & 0xFFFFFFFF
    header = b"\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\xff"
    return (
        header
        + brace
        + spaces * (total // MIB)
        + end
        + (0).to_bytes(4, "little")
        + (size.to_bytes(4, "little"))
    )


BOMBS = {"zstd": (zstd_bomb, ".zst"), "gzip": (gzip_bomb, ".gz")}


def bomb_file(tmp_path: Path, compression: str, total: int = BOMB_SIZE) -> Path:
    build, suffix = BOMBS[compression]
    path = tmp_path / f"bomb.json{suffix}"
    path.write_bytes(build(total))
    return path


@pytest.fixture(scope="module")
def plain(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A real report of the example mission, written by ``analyze``."""
    path = tmp_path_factory.mktemp("report") / "report.json"
    status = main(["analyze", str(EXAMPLE), "--config", str(NAV2), "--json", str(path), "--quiet"])
    assert status == 0
    return path


def diff(*argv: str | Path, env: dict[str, str] | None = None) -> Outcome:
    return run_limited(["diff", *argv, "--quiet"], env=env, cpu_seconds=60, timeout=120)


def assert_small_refusal(outcome: Outcome, path: Path, *needles: str) -> None:
    assert_one_line_error(outcome, str(path), *needles)
    assert outcome.peak_rss_kib < SMALL_PEAK_KIB, outcome.peak_rss_kib


@pytest.mark.parametrize("compression", ["zstd", "gzip"])
def test_a_bomb_is_refused_at_the_default_limit_with_little_memory(
    tmp_path: Path, plain: Path, compression: str
) -> None:
    bomb = bomb_file(tmp_path, compression)
    assert bomb.stat().st_size < 4 * MIB
    outcome = diff(plain, bomb)
    if compression == "gzip":  # deflate expands at most ~1,000x: the size limit comes first
        assert_small_refusal(outcome, bomb, "gzip report that expands past 1,024 MiB")
        assert LIMIT_HINT in outcome.stderr
    else:
        assert_small_refusal(outcome, bomb, f"expands more than {MAX_EXPANSION:,} times its size")


def test_a_bomb_past_the_ratio_is_refused_whatever_the_size_limit(
    tmp_path: Path, plain: Path
) -> None:
    bomb = bomb_file(tmp_path, "zstd", 3 * 512 * MIB)  # 1.5 GiB from ~50 KB
    packed = bomb.stat().st_size
    outcome = diff(plain, bomb, "--max-report-mb", "4096")
    assert_small_refusal(
        outcome,
        bomb,
        f"a zstd report of {packed:,} bytes that expands more than {MAX_EXPANSION:,} times",
    )


def test_a_small_report_of_repeated_text_is_under_the_ratio_floor(tmp_path: Path) -> None:
    text = b'{"warnings": ["' + b"x" * (8 * MIB) + b'"]}'
    path = tmp_path / "repeated.json.zst"
    path.write_bytes(zstandard.ZstdCompressor(level=19).compress(text))
    assert len(text) > MAX_EXPANSION * path.stat().st_size  # past the ratio, under the floor
    assert len(text) < EXPANSION_FLOOR
    assert report_bytes(path, 64 * MIB) == text


@pytest.mark.parametrize("compression", ["zstd", "gzip"])
def test_update_refuses_a_bomb_on_either_side_and_keeps_the_baseline(
    tmp_path: Path, plain: Path, compression: str
) -> None:
    bomb = bomb_file(tmp_path, compression)
    small = {"MEDKIT_REPLAY_MAX_REPORT_MB": "64"}
    baseline = tmp_path / "baseline.json"
    baseline.write_bytes(plain.read_bytes())
    other = tmp_path / ("baseline.json.gz" if compression == "zstd" else "baseline.json.zst")
    for target in (baseline, other):  # the bomb as CURRENT: plain, and recompressed
        outcome = diff(target, bomb, "--update", env=small)
        assert_small_refusal(outcome, bomb, "expands past 64 MiB")
    assert baseline.read_bytes() == plain.read_bytes()
    assert not other.exists()
    before = bomb.read_bytes()
    outcome = diff(bomb, plain, "--update", env=small)  # the bomb as the baseline
    assert_small_refusal(outcome, bomb, "expands past 64 MiB")
    assert bomb.read_bytes() == before


@pytest.mark.parametrize("compression", ["zstd", "gzip"])
def test_a_golden_bomb_fails_the_test_in_one_line(tmp_path: Path, compression: str) -> None:
    bomb = bomb_file(tmp_path, compression)
    test_file = tmp_path / "test_golden_bomb.py"
    test_file.write_text(
        textwrap.dedent(
            f"""
            from medkit_replay.pipeline import replay
            from medkit_replay.pytest_plugin import assert_matches_golden

            def test_golden():
                result = replay([{str(EXAMPLE)!r}], [{str(NAV2)!r}])
                assert_matches_golden(result, {str(bomb)!r})
            """
        )
    )
    outcome = run_limited(
        [test_file, "-q", "-p", "no:cacheprovider", "--golden-max-report-mb", "64"],
        module="pytest",
        cwd=tmp_path,
        timeout=120,
    )
    assert outcome.status == 1, outcome.stdout[-2000:]
    assert f"{bomb}: a {compression} report that expands past 64 MiB" in outcome.stdout
    assert "1 failed" in outcome.stdout
    assert outcome.peak_rss_kib < SMALL_PEAK_KIB, outcome.peak_rss_kib


def halves(data: bytes) -> tuple[bytes, bytes]:
    return data[: len(data) // 2], data[len(data) // 2 :]


def test_concatenated_zstd_frames_and_gzip_members_read_as_one(tmp_path: Path, plain: Path) -> None:
    text = plain.read_bytes()
    one, two = halves(text)
    zstd = zstandard.ZstdCompressor()
    skippable = (0x184D2A50).to_bytes(4, "little") + (4).to_bytes(4, "little") + b"note"
    files = {
        "frames.json.zst": zstd.compress(one) + zstd.compress(two),  # what pzstd and cat make
        "skip.json.zst": zstd.compress(one) + skippable + zstd.compress(two),
        "members.json.gz": gzip.compress(one, mtime=0) + gzip.compress(two, mtime=0),
    }
    for name, data in files.items():
        path = tmp_path / name
        path.write_bytes(data)
        assert report_bytes(path, MIB) == text, name
        assert main(["diff", str(plain), str(path), "--quiet"]) == 0, name
        assert main(["diff", str(path), str(plain), "--quiet"]) == 0, name


def test_a_cut_second_frame_is_refused(
    tmp_path: Path, plain: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    one, two = halves(plain.read_bytes())
    zstd = zstandard.ZstdCompressor()
    second = zstd.compress(two)
    cut = tmp_path / "cut.json.zst"
    cut.write_bytes(zstd.compress(one) + second[: len(second) // 2])
    assert main(["diff", str(plain), str(cut), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err == f"medkit-replay: error: {cut}: cannot decompress the zstd report: " + (
        "the zstd frame is cut short\n"
    )
    trailing = tmp_path / "trailing.json.zst"
    trailing.write_bytes(zstd.compress(one + two) + b"\0\0\0\0")
    assert main(["diff", str(plain), str(trailing), "--quiet"]) == 2
    assert "cannot decompress the zstd report" in capsys.readouterr().err


@pytest.mark.parametrize("suffix", ["", ".gz", ".zst"])
def test_a_report_right_under_the_limit_is_read_and_one_byte_more_is_not(
    tmp_path: Path, plain: Path, suffix: str, capsys: pytest.CaptureFixture[str]
) -> None:
    text = plain.read_bytes()
    packers: dict[str, Callable[[bytes], bytes]] = {
        "": bytes,
        ".gz": lambda d: gzip.compress(d, mtime=0),
        ".zst": lambda d: bytes(zstandard.ZstdCompressor().compress(d)),
    }
    pack = packers[suffix]
    exact = tmp_path / f"exact.json{suffix}"
    exact.write_bytes(pack(text + b" " * (MIB - len(text))))
    over = tmp_path / f"over.json{suffix}"
    over.write_bytes(pack(text + b" " * (MIB + 1 - len(text))))
    assert main(["diff", str(plain), str(exact), "--quiet", "--max-report-mb", "1"]) == 0
    assert main(["diff", str(plain), str(over), "--quiet", "--max-report-mb", "1"]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert str(over) in line and "1 MiB" in line and LIMIT_HINT in line


def test_a_bad_limit_variable_is_one_line(
    tmp_path: Path, plain: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("MEDKIT_REPLAY_MAX_REPORT_MB", "lots")
    assert main(["diff", str(plain), str(plain), "--quiet"]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert "MEDKIT_REPLAY_MAX_REPORT_MB='lots' is not a whole number of MiB" in line
