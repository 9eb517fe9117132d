"""The one guard every CSV file we write puts its cells through (replay tables, fleet tables).

Spreadsheets run a cell that starts like a formula (OWASP "CSV injection"), so text cells are
neutralised; numbers, booleans and missing values stay as they are. JSON and Parquet keep text.
"""

from __future__ import annotations

from typing import IO, TYPE_CHECKING, Literal

if TYPE_CHECKING:
    import pandas as pd

FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")
"""A text cell starting with one of these is read as a formula (or hides one) by spreadsheets."""
QUOTE = "'"


def neutralise(value: object) -> object:
    """A text cell starting with ``=``, ``+``, ``-``, ``@``, a tab or a carriage return gets a
    single quote in front (``'=HYPERLINK(...)``, ``'-3`` for the *text* -3), so a spreadsheet
    shows it as text and never runs it. Anything that is not text (a negative counter, -3, as
    an integer; a boolean; a missing value) is returned unchanged and stays a number."""
    if isinstance(value, str) and value.startswith(FORMULA_STARTS):
        return QUOTE + value
    return value


def _text_columns(frame: pd.DataFrame) -> list[str]:
    # pandas only here: a writer of plain rows (a sweep's tables) imports this module without it.
    from pandas.api.types import is_bool_dtype, is_numeric_dtype  # noqa: PLC0415

    return [
        column
        for column in frame.columns
        if not (is_numeric_dtype(frame[column].dtype) or is_bool_dtype(frame[column].dtype))
    ]


def neutralised(frame: pd.DataFrame) -> pd.DataFrame:
    """A copy of ``frame`` whose text cells went through :func:`neutralise`; numeric and
    boolean columns are left as they are (a mixed column is looked at cell by cell)."""
    safe = frame.copy()
    for column in _text_columns(safe):
        safe[column] = safe[column].map(neutralise)
    return safe


def write_frame(frame: pd.DataFrame, stream: IO[str]) -> None:
    """``frame`` as CSV (``\\n`` line ends, no index) with its text cells neutralised.

    Python's csv module quotes a field holding a line feed but not one holding a lone carriage
    return when lines end in ``\\n``, and readers take that CR for the end of the row: a
    table with a CR in any text cell is written with every text cell quoted (numbers are not),
    which reads back as the same values.
    """
    safe = neutralised(frame)
    has_cr = any(
        isinstance(value, str) and "\r" in value
        for column in _text_columns(safe)
        for value in safe[column]
    )
    quoting: Literal[0, 2] = 2 if has_cr else 0  # csv.QUOTE_NONNUMERIC, csv.QUOTE_MINIMAL
    safe.to_csv(stream, index=False, lineterminator="\n", quoting=quoting)
