"""The shared guards every layer relies on: bounded regular-file reads, YAML bounds, atomic files.

Each is tried with the hostile input it exists for: FIFOs, /dev/zero, alias bombs, cycles.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest
import yaml

from medkit_replay.files import (
    FileRefusedError,
    check_regular,
    open_regular,
    read_limited,
    read_limited_text,
)
from medkit_replay.outputs.atomic import (
    OutputOverlapError,
    atomic_binary,
    atomic_text,
    refuse_overlap,
    write_text_atomic,
)
from medkit_replay.yaml_bounds import YamlBoundsError, check_graph, compose_bounded

BILLION_LAUGHS = """\
a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]
b: &b [*a,*a,*a,*a,*a,*a,*a,*a,*a]
c: &c [*b,*b,*b,*b,*b,*b,*b,*b,*b]
d: &d [*c,*c,*c,*c,*c,*c,*c,*c,*c]
e: &e [*d,*d,*d,*d,*d,*d,*d,*d,*d]
f: &f [*e,*e,*e,*e,*e,*e,*e,*e,*e]
g: &g [*f,*f,*f,*f,*f,*f,*f,*f,*f]
h: &h [*g,*g,*g,*g,*g,*g,*g,*g,*g]
i: &i [*h,*h,*h,*h,*h,*h,*h,*h,*h]
"""


def compose(text: str) -> yaml.Node | None:
    return compose_bounded(lambda: yaml.compose(text, Loader=yaml.SafeLoader))


# --- regular files, bounded -------------------------------------------------------------


def test_fifo_is_refused_without_blocking(tmp_path: Path) -> None:
    fifo = tmp_path / "params.yaml"
    os.mkfifo(fifo)
    with pytest.raises(FileRefusedError, match="a FIFO, not a regular file"):
        read_limited(fifo)
    with pytest.raises(FileRefusedError, match="FIFO"):
        check_regular(fifo)


@pytest.mark.parametrize(("path", "kind"), [("/dev/zero", "character device"), ("/", "directory")])
def test_devices_and_directories_are_refused(path: str, kind: str) -> None:
    with pytest.raises(FileRefusedError, match=kind):
        open_regular(path)


def test_a_file_past_the_bound_is_refused(tmp_path: Path) -> None:
    big = tmp_path / "big.yaml"
    big.write_bytes(b"x" * 1001)
    with pytest.raises(FileRefusedError, match="larger than 1,000 bytes"):
        read_limited(big, limit=1000)
    assert read_limited(big, limit=1001) == b"x" * 1001


def test_refusal_reads_as_one_line_and_is_an_oserror(tmp_path: Path) -> None:
    fifo = tmp_path / "f"
    os.mkfifo(fifo)
    with pytest.raises(OSError, match="FIFO") as caught:
        read_limited_text(fifo)
    assert "\n" not in str(caught.value)
    assert "Errno" not in str(caught.value)


def test_missing_file_is_the_usual_error(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        read_limited(tmp_path / "nope")


# --- YAML bounds ------------------------------------------------------------------------


def test_billion_laughs_is_refused_cheaply() -> None:
    with pytest.raises(YamlBoundsError, match="more than 1,000,000 nodes"):
        compose(BILLION_LAUGHS)


def test_recursive_alias_is_refused() -> None:
    with pytest.raises(YamlBoundsError, match="refers to itself"):
        compose("a: &x [1, *x]\n")


def test_deep_nesting_is_refused_with_its_line() -> None:
    text = "a:\n" + "".join("  " * n + f"k{n}:\n" for n in range(1, 80)) + "  " * 80 + "v\n"
    with pytest.raises(YamlBoundsError, match="deeper than 64") as caught:
        compose(text)
    assert caught.value.line is not None


def test_nesting_too_deep_for_the_composer_is_refused() -> None:
    with pytest.raises(YamlBoundsError, match="deeper"):
        compose("[" * 5000 + "]" * 5000)


def test_shared_aliases_within_bounds_pass() -> None:
    root = compose("base: &b {x: 1, y: [1, 2]}\none: *b\ntwo: *b\n")
    assert isinstance(root, yaml.MappingNode)
    check_graph(None)


def test_bounds_are_parameters() -> None:
    root = yaml.compose("[1, 2, 3]", Loader=yaml.SafeLoader)
    with pytest.raises(YamlBoundsError):
        check_graph(root, max_nodes=3)
    check_graph(root, max_nodes=4)
    with pytest.raises(YamlBoundsError):
        check_graph(root, max_depth=1)


# --- atomic outputs ---------------------------------------------------------------------


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path: Path) -> None:
    target = tmp_path / "report.json"
    target.write_text("old\n")
    with pytest.raises(RuntimeError), atomic_text(target) as stream:
        stream.write("half a rep")
        raise RuntimeError
    assert target.read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.json"]


def test_interrupt_keeps_the_old_file(tmp_path: Path) -> None:
    target = tmp_path / "events.mcap"
    target.write_bytes(b"old")
    with pytest.raises(KeyboardInterrupt), atomic_binary(target) as stream:
        stream.write(b"new")
        raise KeyboardInterrupt
    assert target.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["events.mcap"]


def test_the_target_keeps_its_mode(tmp_path: Path) -> None:
    target = tmp_path / "baseline.json"
    target.write_text("old")
    target.chmod(0o640)
    write_text_atomic(target, "new")
    assert target.read_text() == "new"
    assert stat.S_IMODE(target.stat().st_mode) == 0o640


def test_a_new_file_gets_the_umask_mode(tmp_path: Path) -> None:
    old = os.umask(0o022)
    try:
        write_text_atomic(tmp_path / "new.json", "x")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "new.json").stat().st_mode) == 0o644


def test_a_device_target_is_written_in_place() -> None:
    write_text_atomic(Path("/dev/null"), "discarded")
    assert stat.S_ISCHR(Path("/dev/null").stat().st_mode)


def test_a_directory_target_is_refused(tmp_path: Path) -> None:
    with pytest.raises(IsADirectoryError):
        write_text_atomic(tmp_path, "x")


# --- outputs never over inputs ----------------------------------------------------------


def test_output_equal_to_an_input_is_refused(tmp_path: Path) -> None:
    bag = tmp_path / "run.mcap"
    bag.write_bytes(b"data")
    with pytest.raises(OutputOverlapError, match="--json output is the input"):
        refuse_overlap([bag], [("--json", bag)])


def test_output_inside_an_input_folder_is_refused(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    bag.mkdir()
    (bag / "metadata.yaml").write_text("x")
    with pytest.raises(OutputOverlapError, match="--html output is inside the input"):
        refuse_overlap([bag], [("--html", bag / "metadata.yaml")])
    with pytest.raises(OutputOverlapError, match="--csv output is the input"):
        refuse_overlap([bag], [("--csv", bag)])
    with pytest.raises(OutputOverlapError, match="inside"):
        refuse_overlap([bag], [("--csv", bag / "tables")])


def test_links_are_seen_through(tmp_path: Path) -> None:
    bag = tmp_path / "run.mcap"
    bag.write_bytes(b"data")
    (tmp_path / "soft.mcap").symlink_to(bag)
    os.link(bag, tmp_path / "hard.mcap")
    with pytest.raises(OutputOverlapError):
        refuse_overlap([bag], [("--mcap", tmp_path / "soft.mcap")])
    with pytest.raises(OutputOverlapError, match="same file as the input"):
        refuse_overlap([bag], [("--mcap", tmp_path / "hard.mcap")])


def test_two_outputs_on_one_path_are_refused(tmp_path: Path) -> None:
    out = tmp_path / "out"
    with pytest.raises(OutputOverlapError, match="--html and --json name the same file"):
        refuse_overlap([], [("--json", out), ("--html", out)])


def test_distinct_outputs_beside_inputs_pass(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    bag.mkdir()
    refuse_overlap(
        [bag],
        [("--json", tmp_path / "r.json"), ("--html", tmp_path / "r.html")],
    )
    refuse_overlap([bag], [("--json", Path("/dev/null")), ("--html", Path("/dev/null"))])
