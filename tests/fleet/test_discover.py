"""Finding a fleet's recordings: bag folders, split bags, bare files, scripts, nesting, order."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from medkit_replay.errors import InputError
from medkit_replay.fleet.discover import discover, discover_some, is_bag_directory, natural_key
from tests.fleet.fleet_support import FIXTURES, SAMPLES, build_fleet, report, write_script
from tests.inputs.builders import diag, write_bag


def names(paths: list[Path | str], root: Path) -> list[str]:
    return [Path(p).relative_to(root).as_posix() for p in paths]


def test_bag_folder_is_one_recording_and_its_storage_files_are_not_counted(
    tmp_path: Path,
) -> None:
    shutil.copytree(SAMPLES / "nav2_mission_mcap", tmp_path / "a")
    shutil.copytree(SAMPLES / "nav2_mission_sqlite3", tmp_path / "b")
    assert names(discover([tmp_path]), tmp_path) == ["a", "b"]


def test_split_bag_is_one_recording(tmp_path: Path) -> None:
    shutil.copytree(FIXTURES / "split_bag_mcap", tmp_path / "split")
    assert len(list((tmp_path / "split").glob("*.mcap"))) == 5
    assert names(discover([tmp_path]), tmp_path) == ["split"]


def test_nothing_below_a_bag_folder_is_looked_at(tmp_path: Path) -> None:
    bag = shutil.copytree(SAMPLES / "nav2_mission_mcap", tmp_path / "bag")
    write_script(bag / "nested" / "inner.jsonl", [report(1.0, "A")])
    shutil.copy(SAMPLES / "service_calls.mcap", bag / "nested")
    assert names(discover([tmp_path]), tmp_path) == ["bag"]


def test_compressed_bag_folder_is_one_recording(tmp_path: Path) -> None:
    write_bag(tmp_path / "zipped", [diag(n * 10**9) for n in range(1, 4)], compression="file")
    assert any(p.name.endswith(".mcap.zstd") for p in (tmp_path / "zipped").iterdir())
    assert names(discover([tmp_path]), tmp_path) == ["zipped"]


def test_bag_cut_before_its_metadata_is_one_recording(tmp_path: Path) -> None:
    cut = tmp_path / "run"
    cut.mkdir()
    for index, source in enumerate(sorted((FIXTURES / "no_metadata_mcap").glob("*.mcap"))):
        shutil.copy(source, cut / f"run_{index}.mcap")
    assert names(discover([tmp_path]), tmp_path) == ["run"]


def test_unrelated_bare_files_in_a_folder_are_recordings_of_their_own(tmp_path: Path) -> None:
    shutil.copytree(FIXTURES / "bare_files", tmp_path / "downloads")
    shutil.copytree(FIXTURES / "no_metadata_mcap", tmp_path / "loose")  # not named after it
    assert names(discover([tmp_path]), tmp_path) == [
        "downloads/only_services.mcap",
        "downloads/only_topics.mcap",
        "downloads/topics_and_services.db3",
        "downloads/topics_and_services.mcap",
        "loose/multiple_files_0.mcap",
        "loose/multiple_files_1.mcap",
        "loose/multiple_files_2.mcap",
    ]


def test_scripts_bare_files_and_bags_nested_side_by_side(tmp_path: Path) -> None:
    shutil.copy(SAMPLES / "service_calls.mcap", tmp_path)
    write_script(tmp_path / "site" / "day1" / "robot" / "deep.jsonl", [report(1.0, "A")])
    write_script(tmp_path / "top.jsonl", [report(1.0, "A")])
    shutil.copytree(SAMPLES / "nav2_mission_mcap", tmp_path / "site" / "day1" / "bag")
    (tmp_path / "site" / "readme.txt").write_text("x")
    (tmp_path / "site" / "params.yaml").write_text("x: 1\n")
    assert names(discover([tmp_path]), tmp_path) == [
        "service_calls.mcap",
        "site/day1/bag",
        "site/day1/robot/deep.jsonl",
        "top.jsonl",
    ]


def test_order_compares_numbers_as_numbers(tmp_path: Path) -> None:
    for index in (10, 2, 1, 33, 3):
        write_script(tmp_path / f"run_{index}" / "m.jsonl", [report(1.0, "A")])
    assert names(discover([tmp_path]), tmp_path) == [f"run_{i}/m.jsonl" for i in (1, 2, 3, 10, 33)]
    assert natural_key(Path("a/run_9")) < natural_key(Path("a/run_10"))


def test_hidden_entries_are_skipped(tmp_path: Path) -> None:
    write_script(tmp_path / ".cache" / "old.jsonl", [report(1.0, "A")])
    write_script(tmp_path / ".hidden.jsonl", [report(1.0, "A")])
    write_script(tmp_path / "seen.jsonl", [report(1.0, "A")])
    assert names(discover([tmp_path]), tmp_path) == ["seen.jsonl"]


def test_roots_keep_their_order_and_overlaps_count_once(tmp_path: Path) -> None:
    write_script(tmp_path / "b" / "one.jsonl", [report(1.0, "A")])
    write_script(tmp_path / "a" / "two.jsonl", [report(1.0, "A")])
    found = discover([tmp_path / "b", tmp_path, tmp_path / "a" / "two.jsonl"])
    assert names(found, tmp_path) == ["b/one.jsonl", "a/two.jsonl"]


def test_a_root_may_be_a_recording(tmp_path: Path) -> None:
    script = write_script(tmp_path / "one.jsonl", [report(1.0, "A")])
    bag = shutil.copytree(SAMPLES / "nav2_mission_mcap", tmp_path / "bag")
    assert discover([script, bag]) == [script, bag]


def test_symbolic_link_loops_end(tmp_path: Path) -> None:
    write_script(tmp_path / "a" / "one.jsonl", [report(1.0, "A")])
    (tmp_path / "a" / "loop").symlink_to(tmp_path, target_is_directory=True)
    assert names(discover([tmp_path]), tmp_path) == ["a/one.jsonl"]


def test_generated_fleet_is_found_whole(tmp_path: Path) -> None:
    fleet = build_fleet(tmp_path / "fleet", scripts=6)
    found = discover([fleet.root])
    assert sorted(found) == sorted(fleet.recordings)
    assert found == discover([fleet.root])  # the same order every time


def test_is_bag_directory_rules(tmp_path: Path) -> None:
    folder = tmp_path / "mission"
    folder.mkdir()
    assert not is_bag_directory(folder, [])
    assert is_bag_directory(folder, [folder / "mission_0.mcap", folder / "mission_1.mcap"])
    assert is_bag_directory(folder, [folder / "mission.db3"])
    assert is_bag_directory(folder, [folder / "mission_0.mcap.zstd"])
    assert not is_bag_directory(folder, [folder / "run_0.mcap"])
    assert not is_bag_directory(folder, [folder / "mission_0.mcap", folder / "other.mcap"])
    (folder / "metadata.yaml").write_text("x")
    assert is_bag_directory(folder, [])


def test_missing_root_is_an_input_error(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="input folder not found"):
        discover([tmp_path / "nope"])


def test_root_of_unknown_kind_is_an_input_error(tmp_path: Path) -> None:
    notes = tmp_path / "notes.txt"
    notes.write_text("x")
    with pytest.raises(InputError, match="not a folder nor a recording"):
        discover([notes])


def test_empty_folder_finds_nothing(tmp_path: Path) -> None:
    assert discover([tmp_path]) == []


def test_ros1_bags_are_recordings_also_while_active(tmp_path: Path) -> None:
    (tmp_path / "robot").mkdir()
    for name in ("a.bag", "b.bag.active", "c.active", "d.bag.orig"):
        (tmp_path / "robot" / name).write_bytes(b"")
    assert [Path(p).name for p in discover([tmp_path])] == ["a.bag", "b.bag.active"]


def test_a_command_that_needs_recordings_names_every_kind_it_looks_for(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    (tmp_path / "also").mkdir()
    assert discover([tmp_path / "empty"]) == []
    with pytest.raises(InputError) as raised:
        discover_some([tmp_path / "empty", tmp_path / "also"])
    assert str(raised.value) == (
        f"{tmp_path / 'empty'}, {tmp_path / 'also'}: no recording found "
        "(rosbag2 folders, .mcap, .db3, .bag or .jsonl files)"
    )
    script = write_script(tmp_path / "also" / "run.jsonl", [report(1.0, "PUMP_FAIL")])
    assert discover_some([tmp_path / "empty", tmp_path / "also"]) == [script]
