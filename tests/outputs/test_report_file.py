"""Compressed JSON reports: ``--json FILE.gz`` / ``FILE.zst`` written reproducibly and atomically,
read back by ``diff`` and the golden-report fixture, and refused in one line when hostile."""

from __future__ import annotations

import gzip
import json
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
import zstandard

from medkit_replay.cli import main
from medkit_replay.diffing.reports import report_bytes
from medkit_replay.pipeline import replay
from medkit_replay.pytest_plugin.goldens import assert_matches_golden

if TYPE_CHECKING:
    from collections.abc import Callable

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "nav2_mission.jsonl"
NAV2 = ROOT / "rules" / "nav2" / "fault_manager.yaml"
BRINGUP = ROOT / "rules" / "bringup" / "fault_manager.yaml"

DECOMPRESS: dict[str, Callable[[bytes], bytes]] = {
    ".gz": gzip.decompress,
    ".zst": lambda data: zstandard.ZstdDecompressor().decompressobj().decompress(data),
}


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    status = main(argv)
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return status, out, err


def analyze(target: Path, capsys: pytest.CaptureFixture[str], config: Path = NAV2) -> Path:
    argv = ["analyze", str(EXAMPLE), "--config", str(config), "--json", str(target), "--quiet"]
    assert run(argv, capsys)[0] == 0
    return target


@pytest.mark.parametrize("suffix", [".gz", ".zst"])
def test_compressed_report_is_the_plain_one_compressed_the_same_every_time(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], suffix: str
) -> None:
    plain = analyze(tmp_path / "report.json", capsys).read_bytes()
    first = analyze(tmp_path / f"report.json{suffix}", capsys).read_bytes()
    (tmp_path / "again").mkdir()
    second = analyze(tmp_path / "again" / f"other-name.json{suffix}", capsys).read_bytes()
    assert DECOMPRESS[suffix](first) == plain
    assert first == second  # no time, no file name in the header
    assert len(first) < len(plain) / 5
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "again",
        "report.json",
        f"report.json{suffix}",
    ]  # nothing partial left beside them


def test_gzip_header_names_no_file_and_no_time(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = analyze(tmp_path / "report.json.gz", capsys).read_bytes()
    flags, mtime = data[3], int.from_bytes(data[4:8], "little")
    assert data[:3] == b"\x1f\x8b\x08" and flags == 0 and mtime == 0


def test_suffix_is_case_insensitive_and_stdout_stays_plain(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    data = analyze(tmp_path / "REPORT.JSON.GZ", capsys).read_bytes()
    assert data[:2] == b"\x1f\x8b"
    status, out, _ = run(
        ["analyze", str(EXAMPLE), "--config", str(NAV2), "--json", "-", "--quiet"], capsys
    )
    assert status == 0 and json.loads(out)["schema"] == "medkit-replay/report/v1"


@pytest.mark.parametrize("suffix", [".gz", ".zst"])
def test_diff_reads_compressed_reports(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], suffix: str
) -> None:
    packed = analyze(tmp_path / f"base.json{suffix}", capsys)
    plain = analyze(tmp_path / "base.json", capsys)
    other = analyze(tmp_path / f"other.json{suffix}", capsys, BRINGUP)
    assert run(["diff", str(packed), str(plain), "--quiet"], capsys)[0] == 0
    assert run(["diff", str(plain), str(packed), "--quiet"], capsys)[0] == 0
    assert run(["diff", str(packed), str(other), "--quiet"], capsys)[0] == 1
    # A recording replayed now against a compressed baseline.
    argv = ["diff", str(packed), str(EXAMPLE), "--config", str(NAV2), "--quiet"]
    assert run(argv, capsys)[0] == 0


@pytest.mark.parametrize("suffix", [".gz", ".zst"])
def test_update_writes_the_baseline_compressed_as_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], suffix: str
) -> None:
    baseline = tmp_path / f"base.json{suffix}"
    plain = analyze(tmp_path / "current.json", capsys)
    argv = ["diff", str(baseline), str(EXAMPLE), "--config", str(NAV2), "--update", "--quiet"]
    assert run(argv, capsys)[0] == 0
    assert DECOMPRESS[suffix](baseline.read_bytes()) == plain.read_bytes()
    other = analyze(tmp_path / "other.json", capsys, BRINGUP)
    assert run(["diff", str(baseline), str(other), "--update", "--quiet"], capsys)[0] == 0
    assert DECOMPRESS[suffix](baseline.read_bytes()) == other.read_bytes()


@pytest.mark.parametrize("suffix", [".gz", ".zst"])
def test_golden_fixture_reads_and_writes_compressed_goldens(tmp_path: Path, suffix: str) -> None:
    result = replay([EXAMPLE], [NAV2])
    golden = tmp_path / f"golden.json{suffix}"
    assert_matches_golden(result, golden, update=True)
    assert golden.read_bytes()[:2] in (b"\x1f\x8b", b"\x28\xb5")
    assert_matches_golden(result, golden, update=False)
    with pytest.raises(AssertionError, match="differs from its golden"):
        assert_matches_golden(replay([EXAMPLE], [BRINGUP]), golden, update=False)


def _packed(suffix: str, text: bytes) -> bytes:
    if suffix == ".gz":
        return gzip.compress(text, mtime=0)
    return zstandard.ZstdCompressor().compress(text)


def _bomb(suffix: str, size: int) -> bytes:
    """A report's opening and then ``size`` spaces, compressed: a few KB that expand far."""
    return _packed(suffix, b"{" + b" " * size)


@pytest.mark.parametrize("suffix", [".gz", ".zst"])
def test_a_decompression_bomb_is_refused_in_one_line(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    suffix: str,
) -> None:
    monkeypatch.setenv("MEDKIT_REPLAY_MAX_REPORT_MB", "4")
    bomb = tmp_path / f"bomb.json{suffix}"
    bomb.write_bytes(_bomb(suffix, 16 * 1024 * 1024))
    assert bomb.stat().st_size < 64 * 1024
    good = analyze(tmp_path / "good.json", capsys)
    status, out, err = run(["diff", str(good), str(bomb), "--quiet"], capsys)
    assert status == 2 and out == ""
    assert err == (
        f"medkit-replay: error: {bomb}: a {'gzip' if suffix == '.gz' else 'zstd'} report that "
        "expands past 4 MiB (raise it with --max-report-mb or MEDKIT_REPLAY_MAX_REPORT_MB)\n"
    )


@pytest.mark.parametrize("suffix", [".gz", ".zst"])
def test_damaged_or_foreign_compressed_files_are_refused_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], suffix: str
) -> None:
    good = analyze(tmp_path / f"good.json{suffix}", capsys)
    data = good.read_bytes()
    cut = tmp_path / f"cut.json{suffix}"
    cut.write_bytes(data[: len(data) // 2])
    flipped = tmp_path / f"flipped.json{suffix}"
    flipped.write_bytes(data[:40] + bytes(b ^ 0x5A for b in data[40:80]) + data[80:])
    foreign = tmp_path / f"foreign.json{suffix}"
    foreign.write_bytes(_packed(suffix, b"[1]"))
    for path, message in (
        (cut, "cannot decompress"),
        (flipped, "cannot decompress"),
        (foreign, "does not start with '{'"),
    ):
        status, _, err = run(["diff", str(good), str(path), "--quiet"], capsys)
        assert status == 2, path
        assert len(err.splitlines()) == 1 and message in err and str(path) in err, err


def test_report_bytes_of_a_plain_report_are_its_bytes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    plain = analyze(tmp_path / "r.json", capsys)
    assert report_bytes(plain, 1 << 30) == plain.read_bytes()
