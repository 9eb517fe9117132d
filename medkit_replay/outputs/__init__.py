"""The report's forms, every one built from one Result: JSON, tables, terminal, HTML, MCAP.

``OUTPUTS`` lists the file outputs ``analyze`` writes, by option; a writer's module (pandas,
pyarrow, the MCAP writer) is imported only when that output is asked for.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Callable
    from pathlib import Path

    from medkit_replay.result import Result


def _csv() -> Callable[[Result, Path], object]:
    from medkit_replay.outputs.tables import write_csv  # noqa: PLC0415  # pandas

    return write_csv


def _parquet() -> Callable[[Result, Path], object]:
    from medkit_replay.outputs.parquet import require_pyarrow, write_parquet  # noqa: PLC0415

    require_pyarrow()
    return write_parquet


def _mcap() -> Callable[[Result, Path], object]:
    from medkit_replay.outputs.mcap_events import write_mcap  # noqa: PLC0415  # the MCAP writer

    return write_mcap


def _html() -> Callable[[Result, Path], object]:
    from medkit_replay.outputs.html import write_html  # noqa: PLC0415  # page assets

    return write_html


def _table_files(suffix: str) -> Callable[[Path], list[Path]]:
    def files(directory: Path) -> list[Path]:
        from medkit_replay.outputs.tables import TABLE_COLUMNS  # noqa: PLC0415  # pandas

        return [directory / f"{name}{suffix}" for name in TABLE_COLUMNS]

    return files


@dataclass(frozen=True, slots=True)
class FileOutput:
    """One file output: its option, its name in messages, how to get its writer, its help.

    ``load`` imports the writer (and says now, before a long replay, when an optional
    dependency is missing); ``files`` lists what a directory output writes into its directory
    (its option then takes a folder or a file's name, the others a file).
    """

    option: str
    label: str
    load: Callable[[], Callable[[Result, Path], object]]
    help: str
    files: Callable[[Path], list[Path]] | None = None


OUTPUTS: tuple[FileOutput, ...] = (
    FileOutput(
        "--csv",
        "CSV",
        _csv,
        "Write every report table as CSV into this directory.",
        _table_files(".csv"),
    ),
    FileOutput(
        "--parquet",
        "Parquet",
        _parquet,
        "Write every report table as Parquet into this directory (needs the 'parquet' extra).",
        _table_files(".parquet"),
    ),
    FileOutput(
        "--mcap",
        "MCAP",
        _mcap,
        "Write the replayed FaultEvents and status changes as an MCAP recording.",
    ),
    FileOutput(
        "--html",
        "HTML",
        _html,
        "Write a self-contained HTML report (fault timeline, counter traces, correlation).",
    ),
)
