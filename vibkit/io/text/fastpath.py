"""The fast path of the CSV reader: data rows parsed by pandas' C reader.

Anything that reader cannot take exactly as the line-by-line reader of
:mod:`vibkit.io.text.csv` would raises :class:`_Fallback`, and the file is read again
line by line, so both give the same dataset.
"""

from __future__ import annotations

import hashlib
import io as _io
import itertools
import re

import numpy as np
import pandas as pd

from ..errors import RecordingError
from ..largefile import LargeFile
from .cells import _COMMENT, _MISSING, _is_comment, _kind

__all__ = []

#: text files larger than this are laid out from their first bytes and parsed by pandas' C reader
_HEAD_BYTES = 1 << 20
#: rows holding a missing value that the fast path checks one by one before handing over to the slow path
_MAX_ROWS_TO_CHECK = 100_000
#: the missing-value words of _MISSING in every mix of case, as pandas' reader matches them exactly
_NA_STRINGS = sorted({"".join(c) for w in _MISSING for c in itertools.product(*[(ch.lower(), ch.upper()) for ch in w])})


class _Fallback(Exception):
    """The fast path cannot read this file exactly as the line-by-line path would: use that one."""


def _line_offset(data: bytes, index: int) -> int:
    """Byte offset of 0-based line ``index`` in data whose lines end with LF or CRLF."""
    pos = -1
    for _ in range(index):
        pos = data.find(b"\n", pos + 1)
        if pos < 0:
            raise _Fallback("fewer lines than expected")
    return pos + 1


def _parse_options(n, d, dec, trailing, first_cells, encoding):
    """(columns pandas parses, object columns, int64 columns, keywords of ``pandas.read_csv``)."""
    ncols = n + (1 if trailing else 0)
    objcols = [j for j in range(n) if _kind(first_cells[j], dec) in ("stamp", "text")]
    # integers too long for float64 (epoch ns, us) are read exactly, as int64
    intcols = [j for j in range(n) if j not in objcols and re.fullmatch(r"[+-]?[0-9]{16,19}", first_cells[j])]
    dtype = {j: (object if j in objcols else np.int64 if j in intcols else np.float64) for j in range(ncols)}
    options = dict(
        sep=r"\s+" if d == " " else d,
        decimal=dec,
        header=None,
        names=list(range(ncols)),
        index_col=False,
        dtype=dtype,
        keep_default_na=False,
        na_values={j: _NA_STRINGS for j in range(ncols) if j not in objcols + intcols},
        skip_blank_lines=False,
        engine="c",
        quotechar='"',
        encoding=encoding,
    )
    return ncols, objcols, intcols, options


def _fast_rows(path, data, first, n, d, dec, trailing, first_cells, split, encoding, header_line):
    """The data rows from line ``first`` on, parsed by pandas' C reader.

    Returns the columns (float64 arrays, or object arrays of the cells as found
    for columns whose first cell is not a number) and the 1-based file line of
    each row.  Raises :class:`_Fallback` for anything the line-by-line reader
    treats in its own way (comment lines, lone CR line ends, infinities, rows
    pandas cannot convert ...), so the two readers give the same dataset.
    """
    if isinstance(data, LargeFile):
        return _streamed_rows(path, data, first, n, d, dec, trailing, first_cells, split, encoding, header_line)
    offset = _line_offset(data, first)
    if data.find(b"\r", offset) >= 0 and data.count(b"\r", offset) != data.count(b"\r\n", offset):
        raise _Fallback("lone CR line ends")
    # without quotes (which may hold line ends) every line is one row of pandas: no need to count them
    quoted = data.find(b'"', offset) >= 0
    nlines = None
    if quoted:
        nlines = data.count(b"\n", offset) + (0 if data.endswith(b"\n") or offset >= len(data) else 1)
    ncols, objcols, intcols, options = _parse_options(n, d, dec, trailing, first_cells, encoding)
    buf = _io.BytesIO(data)
    buf.seek(offset)
    try:
        df = pd.read_csv(buf, **options)
    except (ValueError, TypeError, UnicodeDecodeError, pd.errors.ParserError, OverflowError):
        raise _Fallback("a row pandas' reader cannot take") from None
    finally:
        buf.close()
    if nlines is None:
        nlines = len(df)
    elif len(df) != nlines:
        raise _Fallback("quoted line ends")
    _check_chunk(df, objcols, trailing, ncols, d)
    cols = [
        df[j].to_numpy(dtype=object if j in objcols else np.int64 if j in intcols else np.float64, copy=False)
        for j in range(n)
    ]
    del df
    flagged = np.zeros(nlines, dtype=bool)
    for j, c in enumerate(cols):
        if j in objcols:
            flagged |= c == ""
        elif j in intcols:
            continue
        else:
            nan = np.isnan(c)
            if np.isinf(c).any():
                raise _Fallback("an infinite value")  # the line-by-line reader names the cell
            flagged |= nan
    rows = np.flatnonzero(flagged)
    keep = None
    if rows.size:
        if rows.size > _MAX_ROWS_TO_CHECK:
            raise _Fallback("many rows with missing values")
        ends = np.flatnonzero(np.frombuffer(data, dtype=np.uint8, offset=offset) == 10) + offset
        drop = []
        for i in rows:
            start = offset if i == 0 else int(ends[i - 1]) + 1
            end = int(ends[i]) if i < ends.size else len(data)
            ln = data[start:end].decode(encoding, errors="replace").rstrip("\r")
            if _empty_row(ln, d, n, split, path, first + i + 1, header_line):
                drop.append(i)
        if drop:
            keep = np.ones(nlines, dtype=bool)
            keep[drop] = False
    rownums = range(first + 1, first + 1 + nlines)  # file line of each row, without an array
    if keep is not None:
        cols = [c[keep] for c in cols]
        rownums = np.arange(first + 1, first + 1 + nlines)[keep]
    return cols, rownums


#: rows pandas' C reader parses at a time from a streamed file
_CHUNK_ROWS = 1 << 18


def _scan(data: LargeFile, offset: int):
    """One pass over a streamed file: its SHA-256 (kept in ``data``) and, from byte ``offset`` on, the counts
    of LF, CR and CRLF, whether a quote appears, and the last byte and the size."""
    h = hashlib.sha256()
    lf = cr = crlf = 0
    quoted, prev_cr, last, pos = False, False, b"", 0
    for block in data.blocks():
        h.update(block)
        part = block[max(offset - pos, 0) :]
        pos += len(block)
        if not part:
            continue
        lf += int(np.count_nonzero(np.frombuffer(part, dtype=np.uint8) == 10))  # 3x bytes.count
        if b"\r" in part:
            cr += part.count(b"\r")
            crlf += part.count(b"\r\n")
        crlf += 1 if prev_cr and part[:1] == b"\n" else 0
        prev_cr = part[-1:] == b"\r"
        quoted = quoted or b'"' in part
        last = part[-1:]
    data.set_sha256(h.hexdigest())
    return lf, cr, crlf, quoted, last, pos


def _streamed_rows(path, data, first, n, d, dec, trailing, first_cells, split, encoding, header_line):
    """:func:`_fast_rows` of a :class:`~vibkit.io.largefile.LargeFile`: the rows parsed in chunks into arrays
    of their final size, every check made chunk by chunk, so that memory holds the columns and one chunk."""
    offset = _line_offset(data.head, first)
    lf, cr, crlf, quoted, last, size = _scan(data, offset)
    if cr and cr != crlf:
        raise _Fallback("lone CR line ends")
    nlines = lf + (0 if last == b"\n" or offset >= size else 1)
    ncols, objcols, intcols, options = _parse_options(n, d, dec, trailing, first_cells, encoding)
    kinds = [object if j in objcols else np.int64 if j in intcols else np.float64 for j in range(n)]
    cols = [np.empty(nlines, dtype=k) for k in kinds]
    flagged = np.zeros(nlines, dtype=bool)
    pos = 0
    with data.open() as f:
        f.seek(offset)
        try:
            for df in pd.read_csv(f, chunksize=_CHUNK_ROWS, **options):
                k = len(df)
                if pos + k > nlines:
                    raise _Fallback("quoted line ends" if quoted else "rows pandas counts otherwise")
                _check_chunk(df, objcols, trailing, ncols, d)
                rows = slice(pos, pos + k)
                for j in range(n):
                    c = cols[j][rows] = df[j].to_numpy(dtype=kinds[j], copy=False)
                    if j in objcols:
                        flagged[rows] |= c == ""
                    elif j not in intcols:
                        if np.isinf(c).any():
                            raise _Fallback("an infinite value")  # the line-by-line reader names the cell
                        flagged[rows] |= np.isnan(c)
                pos += k
                del df
        except (ValueError, TypeError, UnicodeDecodeError, pd.errors.ParserError, OverflowError):
            raise _Fallback("a row pandas' reader cannot take") from None
    if pos != nlines:
        raise _Fallback("quoted line ends" if quoted else "rows pandas counts otherwise")
    rows = np.flatnonzero(flagged)
    del flagged
    keep = None
    if rows.size:
        if rows.size > _MAX_ROWS_TO_CHECK:
            raise _Fallback("many rows with missing values")
        drop = []
        with data.open() as f:
            f.seek(offset)
            wanted = iter(rows.tolist())
            i_next = next(wanted)
            for i, raw in enumerate(f):
                if i != i_next:
                    continue
                ln = (raw[:-1] if raw.endswith(b"\n") else raw).decode(encoding, errors="replace").rstrip("\r")
                if _empty_row(ln, d, n, split, path, first + i + 1, header_line):
                    drop.append(i)
                i_next = next(wanted, None)
                if i_next is None:
                    break
        if drop:
            keep = np.ones(nlines, dtype=bool)
            keep[drop] = False
    rownums = range(first + 1, first + 1 + nlines)
    if keep is not None:
        cols = [c[keep] for c in cols]
        rownums = np.arange(first + 1, first + 1 + nlines)[keep]
    return cols, rownums


def _check_chunk(df, objcols, trailing, ncols, d):
    """Raise :class:`_Fallback` for a chunk of rows the line-by-line reader would read in its own way."""
    if 0 in objcols and len(df):
        # a comment line whose other cells parse ('#,0,0') leaves no missing value to flag it
        lead = df[0].astype(str).str.lstrip()
        if (lead.str.startswith(_COMMENT) | (lead.str.startswith(";") if d != ";" else False)).any():
            raise _Fallback("comment lines among the data")  # the line-by-line reader records them
    if trailing and not np.all(np.isnan(df[ncols - 1].to_numpy(dtype=np.float64))):
        raise _Fallback("text after the last delimiter")


def _empty_row(ln, d, n, split, path, lineno, header_line) -> bool:
    """Whether a row with a missing value is a blank or empty line (dropped); raise for a comment line
    (:class:`_Fallback`) or a row of another field count (:class:`RecordingError`, naming ``lineno``)."""
    if not ln.strip():
        return True
    if _is_comment(ln, d):
        raise _Fallback("comment lines among the data")  # the line-by-line reader records them
    cells = split(ln)
    if all(c == "" for c in cells):
        return True
    if len(cells) != n:
        like = f" (as in the header on line {header_line})" if header_line else ""
        raise RecordingError(path, lineno, f"expected {n} fields{like}, found {len(cells)}")
    return False
