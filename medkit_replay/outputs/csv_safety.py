"""The one guard every CSV file we write puts its cells through (replay tables, fleet tables).

Spreadsheets run a cell that starts like a formula (OWASP "CSV injection"), so text cells are
neutralised; numbers, booleans and missing values stay as they are. JSON and Parquet keep text.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pandas.api.types import is_bool_dtype, is_numeric_dtype

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


def neutralised(frame: pd.DataFrame) -> pd.DataFrame:
    """A copy of ``frame`` whose text cells went through :func:`neutralise`; numeric and
    boolean columns are left as they are (a mixed column is looked at cell by cell)."""
    safe = frame.copy()
    for column in safe.columns:
        series = safe[column]
        if not (is_numeric_dtype(series.dtype) or is_bool_dtype(series.dtype)):
            safe[column] = series.map(neutralise)
    return safe
