"""Cells of a text recording: what a cell holds, splitting lines into cells, parsing columns of cells.

Shared by the layout reader (:mod:`.layout`), the fast path (:mod:`.fastpath`),
the time column (:mod:`.timecolumn`) and the channels (:mod:`.columns`) of
:mod:`vibkit.io.text.csv`.
"""

from __future__ import annotations

import csv as _csv
import re

import numpy as np
import pandas as pd

__all__ = ["DELIMITERS"]

#: delimiters tried, in order of preference on ties (" " means runs of whitespace)
DELIMITERS = (",", ";", "\t", "|", " ")
_DELIM_NAMES = {",": "','", ";": "';'", "\t": "tab", "|": "'|'", " ": "whitespace"}
_NUM = {
    ".": re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"),
    ",": re.compile(r"[+-]?(?:[0-9]+(?:,[0-9]*)?|,[0-9]+)(?:[eE][+-]?[0-9]+)?"),
}
_NOT_NUMBER_CHAR = {".": re.compile(r"[^0-9eE+\-.\n]"), ",": re.compile(r"[^0-9eE+\-,\n]")}
_MAYBE_COMMENT = "#%/!; \t"
_MISSING = frozenset({"", "nan", "-nan", "+nan", "na", "n/a", "#n/a", "null", "none"})
_INFINITE = frozenset({"inf", "+inf", "-inf", "infinity", "+infinity", "-infinity"})
_STAMP_ISO = re.compile(
    r"[0-9]{4}-[0-9]{2}-[0-9]{2}[T ][0-9]{2}:[0-9]{2}(?::[0-9]{2}(?:[.,][0-9]+)?)?(?:Z|[+-][0-9]{2}:?[0-9]{2})?"
)
_STAMP_DMY = re.compile(r"[0-9]{1,2}[/.-][0-9]{1,2}[/.-][0-9]{4}[ T][0-9]{1,2}:[0-9]{2}(?::[0-9]{2}(?:[.,][0-9]+)?)?")
_STAMP_TOD = re.compile(r"[0-9]{1,2}:[0-9]{2}:[0-9]{2}(?:[.,:][0-9]+)?")
_COMMENT = ("#", "%", "//", "!")
#: the longest of the missing and infinite words: a longer cell is neither
_LONGEST_WORD = max(len(w) for w in _MISSING | _INFINITE)


def _kind(cell: str, dec: str) -> str:
    """'num', 'missing', 'stamp' or 'text'."""
    if _NUM[dec].fullmatch(cell):  # the common case first: a number is none of the missing or infinite words
        return "num"
    if len(cell) <= _LONGEST_WORD:
        low = cell.lower()
        if low in _MISSING:
            return "missing"
        if low in _INFINITE:
            return "num"
    # every stamp holds a ':' (hours:minutes)
    if ":" in cell and (_STAMP_ISO.fullmatch(cell) or _STAMP_DMY.fullmatch(cell) or _STAMP_TOD.fullmatch(cell)):
        return "stamp"
    return "text"


class _Splitter:
    """Split a line into stripped cells for one delimiter."""

    def __init__(self, delim: str, trailing: bool):
        self.d = delim
        self.trailing = trailing

    def __call__(self, line: str) -> list[str]:
        d = self.d
        if d == " ":
            return line.split()
        if '"' in line:
            try:
                cells = next(_csv.reader([line], delimiter=d), [])
            except _csv.Error:
                cells = line.split(d)
        else:
            cells = line.split(d)
        cells = [c.strip() for c in cells]
        if self.trailing and len(cells) > 1 and cells[-1] == "" and line.rstrip().endswith(d):
            cells.pop()
        return cells


def _is_comment(line: str, delim: str) -> bool:
    s = line.lstrip()
    return s.startswith(_COMMENT) or (delim != ";" and s.startswith(";"))


def _mostly_numbers(kinds) -> bool:
    """A row that reads as data whatever its columns: numbers outnumber text, few cells are text."""
    num, stamp, text = kinds.count("num"), kinds.count("stamp"), kinds.count("text")
    return num >= 1 and text < num + stamp and 2 * text < len(kinds)


def _data_like(cells, n, dec, numcols) -> bool:
    """A data row: n cells, every numeric column holding a number, a stamp or nothing, one number at least."""
    if len(cells) != n:
        return False
    kinds = [_kind(c, dec) for c in cells]
    return "num" in kinds and all(k != "text" for k, isnum in zip(kinds, numcols) if isnum)


def _parse_numbers(cells, dec):
    """Values, missing mask, indices of non-numbers, indices of infinities."""
    if isinstance(cells, np.ndarray) and cells.dtype.kind in "fiu":  # parsed by the fast path
        if cells.dtype.kind != "f":  # long integers (epoch ns) kept exact for the time column
            return cells, np.zeros(cells.size, dtype=bool), np.empty(0, dtype=np.intp), np.empty(0, dtype=np.intp)
        return cells, np.isnan(cells), np.empty(0, dtype=np.intp), np.flatnonzero(np.isinf(cells))
    joined = "\n".join(cells)
    if not _NOT_NUMBER_CHAR[dec].search(joined):  # fast path: only digits, signs, exponents, marks
        try:
            vals = np.array(joined.replace(",", ".").split("\n") if dec == "," else cells, dtype=np.float64)
        except ValueError:  # e.g. an empty cell or '1e': the cell-by-cell path below says which
            pass
        else:
            empty = np.empty(0, dtype=np.intp)
            return vals, np.zeros(len(cells), dtype=bool), empty, np.flatnonzero(np.isinf(vals))
    s = pd.Series(cells, dtype=object)
    low = s.str.lower()
    missing = low.isin(_MISSING).to_numpy()
    isnum = s.str.fullmatch(_NUM[dec].pattern).fillna(False).to_numpy(dtype=bool)
    infinite = low.isin(_INFINITE).to_numpy()  # 'inf', '-Infinity': reported among the infinities
    bad = np.flatnonzero(~missing & ~isnum & ~infinite)
    vals = np.full(len(cells), np.nan)
    vals[infinite] = np.where(low[infinite].str.startswith("-").to_numpy(dtype=bool), -np.inf, np.inf)
    if isnum.any():
        t = s[isnum]
        if dec == ",":
            t = t.str.replace(",", ".", regex=False)
        vals[isnum] = pd.to_numeric(t, errors="coerce").to_numpy(dtype=float)
    inf = np.flatnonzero(np.isinf(vals))
    return vals, missing, bad, inf
