"""The entity_thresholds YAML loader: upstream's YamlLoadTest (Y-01..Y-04) and §1.12's [I] notes.

Files are written to tmp_path; values are read as yaml-cpp 0.7 converts them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

from medkit_replay.config.entity_thresholds_file import load_entity_thresholds
from medkit_replay.engine import (
    DebounceConfig,
    EntityThresholdResolver,
    FaultManager,
    FaultManagerConfig,
)
from medkit_replay.engine.thresholds import EntityOverride
from medkit_replay.errors import ConfigWarning
from medkit_replay.model import ReportRequest

if TYPE_CHECKING:
    from pathlib import Path


def write(tmp_path: Path, text: str) -> Path:
    """The YAML text as a file."""
    path = tmp_path / "entity_thresholds.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def entry(
    prefix: str,
    conf: int | None = None,
    heal_enabled: bool | None = None,
    heal: int | None = None,
) -> EntityOverride:
    """One expected entry."""
    return EntityOverride(
        prefix=prefix,
        confirmation_threshold=conf,
        healing_enabled=heal_enabled,
        healing_threshold=heal,
    )


def test_y01_load_valid_file(tmp_path: Path) -> None:
    """Y-01 YamlLoadTest.LoadValidFile: 3 entries; motor_left -5/10, healing_enabled unset [A]."""
    path = write(
        tmp_path,
        """
/sensors/lidar:
  confirmation_threshold: -1
  healing_threshold: 1
/powertrain/motor_left:
  confirmation_threshold: -5
  healing_threshold: 10
/safety:
  healing_enabled: false
""",
    )
    entries, warnings = load_entity_thresholds(path)
    assert len(entries) == 3
    motor = next(e for e in entries if e.prefix == "/powertrain/motor_left")
    assert motor.confirmation_threshold == -5
    assert motor.healing_threshold == 10
    assert motor.healing_enabled is None
    assert entries == (
        entry("/sensors/lidar", conf=-1, heal=1),
        entry("/powertrain/motor_left", conf=-5, heal=10),
        entry("/safety", heal_enabled=False),
    )
    assert warnings == ()


def test_y02_missing_file_returns_empty(tmp_path: Path) -> None:
    """Y-02 MissingFileReturnsEmpty [A]; the error is reported with the path."""
    path = tmp_path / "absent.yaml"
    entries, warnings = load_entity_thresholds(path)
    assert entries == ()
    (message,) = warnings
    assert message.startswith(f"{path}: ")
    assert "not found" in message
    assert not path.exists()


def test_y03_malformed_yaml_returns_empty(tmp_path: Path) -> None:
    """Y-03 MalformedYamlReturnsEmpty ("{{{{not valid yaml") [A]."""
    path = write(tmp_path, "{{{{not valid yaml")
    entries, warnings = load_entity_thresholds(path)
    assert entries == ()
    (message,) = warnings
    assert message.startswith(f"{path}")
    assert "Failed to parse entity thresholds config" in message


def test_y04_positive_confirmation_threshold_auto_negated(tmp_path: Path) -> None:
    """Y-04 PositiveConfirmationThresholdAutoNegated: 5 → -5 [A], with upstream's warning."""
    path = write(tmp_path, "/sensors:\n  confirmation_threshold: 5\n")
    entries, warnings = load_entity_thresholds(path)
    assert entries == (entry("/sensors", conf=-5),)
    (message,) = warnings
    assert message == (
        f"{path}:2: confirmation_threshold for '/sensors' should be <= 0, got 5. Using -5."
    )


def test_negative_healing_threshold_negated(tmp_path: Path) -> None:
    """§4.6 [I]: healing_threshold -4 → 4."""
    path = write(tmp_path, "/a:\n  healing_threshold: -4\n")
    entries, warnings = load_entity_thresholds(path)
    assert entries == (entry("/a", heal=4),)
    assert warnings == (f"{path}:2: healing_threshold for '/a' should be >= 0, got -4. Using 4.",)


def test_zero_confirmation_kept_at_load_and_sanitised_by_the_node(tmp_path: Path) -> None:
    """§4.6 [I]: conf 0 is kept by the loader; the merged value is sanitised to -1."""
    entries, warnings = load_entity_thresholds(write(tmp_path, "/a: {confirmation_threshold: 0}\n"))
    assert entries == (entry("/a", conf=0),)
    assert warnings == ()
    resolver = EntityThresholdResolver(DebounceConfig(confirmation_threshold=-4), entries)
    assert resolver.resolve("/a/b").confirmation_threshold == -1


def test_non_map_value_skips_that_prefix(tmp_path: Path) -> None:
    """§1.12/§4.6 [I]: a non-map value skips its prefix with a warning; the rest apply."""
    path = write(
        tmp_path,
        "/a: 5\n/b: {confirmation_threshold: -2}\n/c: [1]\n/d: ~\n/e:\n/f: {healing_enabled: on}\n",
    )
    entries, warnings = load_entity_thresholds(path)
    assert entries == (entry("/b", conf=-2), entry("/f", heal_enabled=True))
    assert warnings == tuple(
        f"{path}:{line}: Skipping non-map entry for prefix '{prefix}'"
        for line, prefix in ((1, "/a"), (3, "/c"), (4, "/d"), (5, "/e"))
    )


@pytest.mark.parametrize(
    ("bad", "line"),
    [
        ("{confirmation_threshold: 2.5}", 2),
        ("{confirmation_threshold: 1e3}", 2),
        ("{healing_enabled: 1}", 2),
        ("{healing_threshold: ~}", 2),
        ("{confirmation_threshold:}", 2),
        ("{confirmation_threshold: [1]}", 2),
        ("{healing_threshold: 2147483648}", 2),
        ("{healing_enabled: oN}", 2),
    ],
)
def test_conversion_error_drops_that_entry_and_every_later_one(
    tmp_path: Path, bad: str, line: int
) -> None:
    """§1.12: a value that does not convert stops the reading; the entries before it apply."""
    path = write(
        tmp_path,
        f"/first: {{confirmation_threshold: -2}}\n/bad: {bad}\n/later: {{healing_threshold: 1}}\n",
    )
    entries, warnings = load_entity_thresholds(path)
    assert entries == (entry("/first", conf=-2),)
    (message,) = warnings
    assert message.startswith(f"{path}:{line}: Failed to parse entity thresholds config: ")
    assert "dropped" in message


def test_a_bad_field_drops_the_whole_entry(tmp_path: Path) -> None:
    """§1.12: the entry holding the bad value is dropped even if its other fields were fine."""
    path = write(tmp_path, "/a:\n  confirmation_threshold: -3\n  healing_enabled: maybe\n")
    entries, warnings = load_entity_thresholds(path)
    assert entries == ()
    assert len(warnings) == 1


def test_a_non_scalar_key_stops_the_reading(tmp_path: Path) -> None:
    """A key that is not a string (a sequence) is a conversion error too."""
    path = write(tmp_path, "/a: {confirmation_threshold: -2}\n? [x]\n: {}\n/c: {}\n")
    entries, warnings = load_entity_thresholds(path)
    assert entries == (entry("/a", conf=-2),)
    assert len(warnings) == 1


@pytest.mark.parametrize(
    ("fields", "expected"),
    [
        ("confirmation_threshold: 1", entry("/p", conf=-1)),
        ("confirmation_threshold: -1", entry("/p", conf=-1)),
        ("healing_threshold: 0", entry("/p", heal=0)),
        ("healing_threshold: -1", entry("/p", heal=1)),
        ("confirmation_threshold: 010", entry("/p", conf=-8)),
        ("confirmation_threshold: 0x10", entry("/p", conf=-16)),
        ("confirmation_threshold: '-07'", entry("/p", conf=-7)),
        ("confirmation_threshold: -0x3", entry("/p", conf=-3)),
        ("healing_threshold: +3", entry("/p", heal=3)),
        ("healing_threshold: '5'", entry("/p", heal=5)),
        ("healing_enabled: Y", entry("/p", heal_enabled=True)),
        ("healing_enabled: NO", entry("/p", heal_enabled=False)),
        ("healing_enabled: 'Off'", entry("/p", heal_enabled=False)),
        ("healing_enabled: yes", entry("/p", heal_enabled=True)),
    ],
)
def test_values_read_as_yaml_cpp_converts_them(
    tmp_path: Path, fields: str, expected: EntityOverride
) -> None:
    """§1.12: decimal, octal, hex with a sign; y/n/yes/no/true/false/on/off; quoting ignored."""
    entries, _ = load_entity_thresholds(write(tmp_path, f"/p:\n  {fields}\n"))
    assert entries == (expected,)


def test_every_field_optional_and_unknown_keys_ignored(tmp_path: Path) -> None:
    """§1.12: every field optional; unknown keys ignored, as upstream does, and warned with
    the closest known field."""
    text = "/a: {}\n/b: {foo: bar, confirmation_threshold: -2, healing_treshold: x}\n"
    path = write(tmp_path, text)
    entries, warnings = load_entity_thresholds(path)
    assert entries == (entry("/a"), entry("/b", conf=-2))
    expected = "confirmation_threshold, healing_enabled, healing_threshold"
    assert warnings == (
        f"{path}:2: entity '/b': unknown key 'foo' (expected one of: {expected}); "
        "upstream ignores it",
        f"{path}:2: entity '/b': unknown key 'healing_treshold' "
        "(did you mean 'healing_threshold'?); upstream ignores it",
    )
    located = [(w.line, w.suggestion) for w in warnings if isinstance(w, ConfigWarning)]
    assert located == [(2, None), (2, "healing_threshold")]


def test_duplicate_keys_in_an_entry_first_wins(tmp_path: Path) -> None:
    """yaml-cpp looks a key up from the front: the second duplicate is never read."""
    path = write(tmp_path, "/a: {confirmation_threshold: -2, confirmation_threshold: bogus}\n")
    assert load_entity_thresholds(path) == ((entry("/a", conf=-2),), ())


def test_duplicate_prefixes_are_all_kept_in_file_order(tmp_path: Path) -> None:
    """yaml-cpp keeps duplicate map keys; the loader returns each entry."""
    path = write(tmp_path, "/a: {confirmation_threshold: -2}\n/a: {confirmation_threshold: -4}\n")
    entries, _ = load_entity_thresholds(path)
    assert entries == (entry("/a", conf=-2), entry("/a", conf=-4))


def test_int_min_healing_threshold_wraps_when_negated(tmp_path: Path) -> None:
    """int32 arithmetic: -(-2147483648) wraps back to -2147483648; not sanitised here."""
    entries, _ = load_entity_thresholds(write(tmp_path, "/a: {healing_threshold: -2147483648}\n"))
    assert entries == (entry("/a", heal=-2147483648),)


@pytest.mark.parametrize(
    ("text", "kind"),
    [("", "null"), ("# nothing\n", "null"), ("- a\n", "sequence"), ("just text\n", "scalar")],
)
def test_root_must_be_a_map(tmp_path: Path, text: str, kind: str) -> None:
    """§1.12: a root that is not a map → no overrides, with upstream's error."""
    path = write(tmp_path, text)
    entries, warnings = load_entity_thresholds(path)
    assert entries == ()
    (message,) = warnings
    assert message.startswith(f"{path}: Entity thresholds config must be a YAML map, got {kind}")


def test_loader_creates_nothing(tmp_path: Path) -> None:
    """The loader only reads: the folder and the file are unchanged."""
    path = write(tmp_path, "/a: {confirmation_threshold: 3}\n")
    before = (
        sorted(p.name for p in tmp_path.iterdir()),
        path.read_bytes(),
        path.stat().st_mtime_ns,
    )
    load_entity_thresholds(path)
    load_entity_thresholds(tmp_path / "missing.yaml")
    after = (sorted(p.name for p in tmp_path.iterdir()), path.read_bytes(), path.stat().st_mtime_ns)
    assert after == before


def test_ei_integration_file_drives_the_manager(tmp_path: Path) -> None:
    """EI-01..EI-06 (test_entity_thresholds_integration): global -5/off/10 plus the file."""
    path = write(
        tmp_path,
        "/sensors/lidar:\n  confirmation_threshold: -1\n  healing_enabled: true\n"
        "  healing_threshold: 1\n/powertrain/motor:\n  confirmation_threshold: -3\n"
        "  healing_threshold: 5\n",
    )
    entries, warnings = load_entity_thresholds(path)
    assert warnings == ()
    manager = FaultManager(
        FaultManagerConfig(
            debounce=DebounceConfig(
                confirmation_threshold=-5, healing_enabled=False, healing_threshold=10
            ),
            entity_overrides=entries,
        )
    )
    t = 0

    def fail(code: str, source: str) -> str:
        nonlocal t
        t += 1_000_000
        assert manager.report(
            ReportRequest(t_ns=t, fault_code=code, event_type=0, severity=2, source_id=source)
        )
        return manager.storage.faults[code].status

    assert fail("LIDAR.BLOCKED", "/sensors/lidar/front") == "CONFIRMED"  # EI-01
    assert fail("MOTOR.OVERHEAT", "/powertrain/motor/left") == "PREFAILED"  # EI-02
    assert fail("MOTOR.OVERHEAT", "/powertrain/motor/left") == "PREFAILED"
    assert fail("MOTOR.OVERHEAT", "/powertrain/motor/left") == "CONFIRMED"  # EI-03
    statuses = [fail("UNKNOWN.FAULT", "/some/unknown/subsystem") for _ in range(5)]
    assert statuses == ["PREFAILED"] * 4 + ["CONFIRMED"]  # EI-04 .. EI-06
