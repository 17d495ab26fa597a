"""Read CSV and text exports of field recordings (loggers, phones, spreadsheets).

What the reader works out from the file itself, each decision recorded in the
dataset's ``history``:

* text encoding (UTF-8, else Windows-1252 as Spanish spreadsheets write);
* delimiter (``,`` ``;`` tab ``|`` or whitespace) and decimal comma (``0,49``);
* metadata lines above the header (``key: value``, ``key;value``, ``;Tag, ...``
  comment lines), kept as attrs, and free comment text;
* the header row (or a ``Headers`` metadata line as GCDC loggers write), and a
  row of units below it (``s;g;mm``) when there is one;
* the time column (s, ms, us, timestamps) or, with none, the sample rate from the
  header or the ``sample_rate`` option;
* units from column names (``(m/s^2)``, ``[g]``, ``_mm``, ``gFz``), converted to SI;
  raw counts converted with a scale from the header (``2048 counts per g``);
* bursts separated by gaps (segments), jitter, repeated or backward stamps.

Nothing is guessed silently: what cannot be read raises :class:`RecordingError`
naming the file, the line and what was expected.
"""

from __future__ import annotations

import csv as _csv
import io as _io
import itertools
import math
import re
from collections import Counter
from datetime import datetime, timezone

import numpy as np
import pandas as pd

from .errors import RecordingError
from .channels import COUNTER_ATTR, is_counter_name, is_counter_ramp
from .recording import Channel, build_recording, metadata_attrs, safe_name, unique_names
from .timebase import check_order, diagnose, resample_linear
from .units import is_time_name, parse_time_unit, parse_unit, split_name_unit

__all__ = ["read_csv", "DELIMITERS"]

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
_STAMP_ISO = re.compile(
    r"[0-9]{4}-[0-9]{2}-[0-9]{2}[T ][0-9]{2}:[0-9]{2}(?::[0-9]{2}(?:[.,][0-9]+)?)?(?:Z|[+-][0-9]{2}:?[0-9]{2})?")
_STAMP_DMY = re.compile(
    r"[0-9]{1,2}[/.-][0-9]{1,2}[/.-][0-9]{4}[ T][0-9]{1,2}:[0-9]{2}(?::[0-9]{2}(?:[.,][0-9]+)?)?")
_STAMP_TOD = re.compile(r"[0-9]{1,2}:[0-9]{2}:[0-9]{2}(?:[.,:][0-9]+)?")
_COMMENT = ("#", "%", "//", "!")
_CONTROL = re.compile("[\x00-\x08\x0b\x0e-\x1f\x7f-\x9f]")
_RATE_KEY = re.compile(r"sampl\w*[\s_-]*(?:rate|freq)|samplerate|^fs\b|frecuencia\s*de\s*muestreo"
                       r"|sampling|muestreo|abtastrate", re.IGNORECASE)
_SCALE = re.compile(r"([0-9]+(?:[.,][0-9]*)?(?:[eE][+-]?[0-9]+)?)\s*,?\s*(?:counts?|lsb|cts|digits)\s*"
                    r"(?:/|per)\s*([^\s,;]+)", re.IGNORECASE)


#: text files larger than this are laid out from their first bytes and parsed by pandas' C reader
_HEAD_BYTES = 1 << 20
#: rows holding a missing value that the fast path checks one by one before handing over to the slow path
_MAX_ROWS_TO_CHECK = 100_000
#: the missing-value words of _MISSING in every mix of case, as pandas' reader matches them exactly
_NA_STRINGS = sorted({"".join(c) for w in _MISSING for c in itertools.product(*[(ch.lower(), ch.upper()) for ch in w])})
#: plausible Unix epoch times [s]: 1979-07 to 2103-02; each unit's range is 1000x the next, so they never overlap
_EPOCH_RANGE_S = (3e8, 4.2e9)
_EPOCH_UNITS = (("s", 1.0), ("ms", 1e-3), ("us", 1e-6), ("ns", 1e-9))
_BOMS = ((b"\xff\xfe\x00\x00", "utf-32"), (b"\x00\x00\xfe\xff", "utf-32"), (b"\xff\xfe", "utf-16"),
         (b"\xfe\xff", "utf-16"))


class _Fallback(Exception):
    """The fast path cannot read this file exactly as the line-by-line path would: use that one."""


def _pct(fraction: float) -> str:
    """A fraction as a short percentage; round-off below 1e-6 % shows as 0."""
    return "0" if abs(fraction) < 1e-8 else f"{100 * fraction:.2g}"


def _kind(cell: str, dec: str) -> str:
    """'num', 'missing', 'stamp' or 'text'."""
    if cell.lower() in _MISSING:
        return "missing"
    if _NUM[dec].fullmatch(cell):
        return "num"
    if _STAMP_ISO.fullmatch(cell) or _STAMP_DMY.fullmatch(cell) or _STAMP_TOD.fullmatch(cell):
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


def _hash_header(line: str, delim: str, n: int, split) -> bool:
    """A header whose first column is named '#' (a sample counter): '#,time (s),x (mm)', not a comment."""
    s = line.lstrip()
    return delim != " " and s.startswith("#" + delim) and len(split(s)) == n


def _is_unit_cell(cell: str) -> bool:
    """An empty cell or a unit alone ('s', '[ms]', '(g)', 'mm'), as in a units row below the header."""
    u = cell.strip("()[]{} ")
    return not u or parse_unit(u) is not None or parse_time_unit(u) is not None


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


def utf16_without_bom(data: bytes):
    """'utf-16-le' or 'utf-16-be' when text looks like UTF-16 without a byte-order mark, else None.

    ASCII text in UTF-16 has a zero in every other byte (odd bytes for little
    endian): at least 90 % of those zero and under 10 % of the others.
    """
    head = data[:65536]
    if len(head) < 8 or len(head) % 2 or b"\x00" not in head:
        return None
    even, odd = head[0::2], head[1::2]
    if odd.count(0) >= 0.9 * len(odd) and even.count(0) < 0.1 * len(even):
        return "utf-16-le"
    if even.count(0) >= 0.9 * len(even) and odd.count(0) < 0.1 * len(odd):
        return "utf-16-be"
    return None


def _decode(path, data: bytes, encoding):
    if encoding is not None:
        try:
            return data.decode(encoding), [f"encoding {encoding} (given)"]
        except (UnicodeDecodeError, LookupError) as exc:
            raise RecordingError(path, None, f"cannot decode as {encoding}: {exc}") from None
    for bom, codec in _BOMS:
        if data.startswith(bom):
            try:
                return data.decode(codec), [f"encoding {codec.upper()} (byte-order mark)"]
            except UnicodeDecodeError as exc:
                raise RecordingError(path, None, f"starts with a {codec.upper()} byte-order mark but cannot be "
                                     f"decoded as {codec.upper()} ({exc.reason} at byte {exc.start})") from None
    codec = utf16_without_bom(data)
    if codec is not None:
        try:
            return data.decode(codec), [f"encoding {codec.upper()} (no byte-order mark; every other byte is zero)"]
        except UnicodeDecodeError as exc:
            raise RecordingError(path, None, f"looks like {codec.upper()} text without a byte-order mark but "
                                 f"cannot be decoded as such ({exc.reason} at byte {exc.start}); "
                                 "pass encoding=") from None
    head = data[:65536]
    nul = head.find(b"\x00")
    if nul >= 0:
        raise RecordingError(path, None, f"binary content (NUL byte at offset {nul}); "
                                         "expected a text file, netCDF/HDF5 or a waveform format obspy reads")
    try:
        text, notes = data.decode("utf-8-sig"), []
    except UnicodeDecodeError:
        try:
            text, notes = data.decode("cp1252"), ["encoding cp1252 (the file is not valid UTF-8)"]
        except UnicodeDecodeError:
            text, notes = data.decode("latin-1"), ["encoding latin-1 (the file is neither UTF-8 nor cp1252)"]
    sample = text[:65536]
    ctrl = len(_CONTROL.findall(sample))
    if sample and ctrl > max(2, 0.01 * len(sample)):
        raise RecordingError(path, None, f"binary content ({ctrl} control bytes in the first {len(sample)}); "
                                         "expected a text file, netCDF/HDF5 or a waveform format obspy reads")
    return text, notes


def _sniff(lines, delimiter, decimal):
    """Choose delimiter, decimal mark, field count and numeric columns from the end of the file."""
    tail = []
    for ln in reversed(lines):  # the last 200 lines that may hold data
        if ln.strip() and not ln.lstrip().startswith(_COMMENT):
            tail.append(ln)
            if len(tail) == 200:
                break
    tail.reverse()
    if not tail:
        return None
    delims = DELIMITERS if delimiter is None else (delimiter,)
    found = []
    for order, d in enumerate(delims):
        trailing = d != " " and sum(ln.rstrip().endswith(d) for ln in tail) >= 0.9 * len(tail)
        split = _Splitter(d, trailing)
        rows = [split(ln) for ln in tail if not _is_comment(ln, d)]
        if not rows:
            continue
        decs = (decimal,) if decimal is not None else ((".",) if d == "," else (".", ","))
        for dec in decs:
            kinds = [[_kind(c, dec) for c in r] for r in rows]
            kinds = [k for k in kinds if _mostly_numbers(k)]  # not headers, notes or metadata
            if not kinds:
                continue
            freq, n = max((f, k) for k, f in Counter(len(k) for k in kinds).items())
            kinds = [k for k in kinds if len(k) == n]
            n_num = sum(k.count("num") for k in kinds)
            numcols = []
            for j in range(n):
                col = [k[j] for k in kinds]
                numcols.append("num" in col and sum(x != "text" for x in col) >= 0.9 * len(col))
            if not any(numcols):
                continue
            header_match = _header_matches(lines, split, n, dec, d, numcols)
            found.append((n_num, header_match, freq, -order, dec == ".", (d, dec, n, trailing, numcols)))
    if not found:
        return None
    most = max(f[0] for f in found)
    # among readings that find at least half the numbers of the best one, prefer a header row that
    # splits like the data ("0,49" under a one-column header is a decimal comma), then more numbers
    best = max(found, key=lambda f: (2 * f[0] >= most, f[1], f[0], f[2], f[3], f[4]))
    return best[5]


def _header_matches(lines, split, n, dec, d, numcols) -> bool:
    prev = None
    for ln in lines:
        if not ln.strip() or _is_comment(ln, d):
            continue
        cells = split(ln)
        if _data_like(cells, n, dec, numcols):
            if prev is None:
                return False
            return len(prev) == n and all(_kind(c, dec) in ("text", "missing") for c in prev)
        prev = cells
    return False


def _meta_pair(line: str, delim: str, dec: str):
    """('key', value) from a metadata line, or (None, text) for free text."""
    s = line.strip()
    s = s.lstrip("#;%/! \t").strip()
    if not s:
        return None, ""
    seps = [":", "=", "\t"] + ([delim] if delim not in (" ", "\t") else [])
    pos = [(s.find(c), c) for c in seps if s.find(c) > 0]
    if not pos:
        return None, (s.rstrip(delim + " ") if delim != " " else s)
    p, _ = min(pos)
    key = s[:p].strip().strip('"').strip()
    value = s[p + 1:].strip()
    if delim not in (" ",):
        value = value.strip(delim + " ")
    value = value.strip('"').strip()
    if (not key or len(key) > 48 or len(key.split()) > 5 or not re.search(r"[A-Za-z]", key)
            or not value):
        return None, (s.rstrip(delim + " ") if delim != " " else s)
    for dm in (dec, "."):
        if _NUM[dm].fullmatch(value):
            v = value.replace(",", ".")
            return key, (int(v) if re.fullmatch(r"[+-]?[0-9]+", v) and abs(int(v)) < 2**53 else float(v))
    return key, value


def _rate_from_meta(pairs):
    """(rate [Hz], line, key) from a sample-rate metadata pair, or None."""
    for lineno, key, value in pairs:
        if not _RATE_KEY.search(key):
            continue
        text = f"{value}"
        m = re.search(r"([0-9]+(?:[.,][0-9]*)?(?:[eE][+-]?[0-9]+)?)\s*,?\s*([A-Za-z/]*)", text)
        if not m:
            continue
        rate = float(m.group(1).replace(",", "."))
        unit = (m.group(2) or "").lower()
        if "khz" in unit or "khz" in key.lower():
            rate *= 1e3
        elif unit and not (unit.startswith(("hz", "sps", "samples", "s/s", "muestras"))):
            continue
        if math.isfinite(rate) and rate > 0:
            return rate, lineno, key
    return None


def _scale_from_meta(pairs):
    """(factor counts->SI, si unit, line, text) from a 'N counts per <unit>' metadata pair, or None."""
    for lineno, key, value in pairs:
        m = _SCALE.search(f"{value}")
        if not m:
            continue
        per = float(m.group(1).replace(",", "."))
        unit = parse_unit(m.group(2))
        if unit is None or unit.factor is None or not per > 0:
            continue
        return unit.factor / per, unit, lineno, f"{key}: {value}"
    return None


def _match_column(want, headers, names, vars_):
    w = " ".join(str(want).split()).lower()
    for j in range(len(headers)):
        if w in (" ".join(str(headers[j]).split()).lower(), names[j].lower(), vars_[j].lower()):
            return j
    return None


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
    bad = np.flatnonzero(~missing & ~isnum)
    vals = np.full(len(cells), np.nan)
    if isnum.any():
        t = s[isnum]
        if dec == ",":
            t = t.str.replace(",", ".", regex=False)
        vals[isnum] = pd.to_numeric(t, errors="coerce").to_numpy(dtype=float)
    inf = np.flatnonzero(np.isinf(vals))
    return vals, missing, bad, inf


def _parse_stamps(cells):
    """Seconds since the first stamp, the first stamp as text, the format name; None if not stamps."""
    s = pd.Series(cells, dtype=object)
    first = s.iloc[0]
    if _STAMP_ISO.fullmatch(first):
        t = pd.to_datetime(s.str.replace(",", ".", regex=False), format="ISO8601", utc=True, errors="coerce")
        kind = "ISO 8601 timestamps"
        ok = t.notna().to_numpy()
    elif _STAMP_DMY.fullmatch(first):
        norm = s.str.replace(r"^([0-9]{1,2})[/.-]([0-9]{1,2})[/.-]([0-9]{4})[ T]", r"\3-\2-\1 ", regex=True)
        norm = norm.str.replace(",", ".", regex=False)
        t = pd.to_datetime(norm, format="ISO8601", errors="coerce")
        kind = "day/month/year timestamps"
        ok = t.notna().to_numpy()
    elif _STAMP_TOD.fullmatch(first):
        norm = s.str.replace(r"^([0-9]{1,2}:[0-9]{2}:[0-9]{2})[.,:]([0-9]+)$", r"\1.\2", regex=True)
        t = pd.to_timedelta(norm.where(norm.str.fullmatch(r"[0-9]{1,2}:[0-9]{2}:[0-9]{2}(\.[0-9]+)?"), None),
                            errors="coerce")
        kind = "time-of-day stamps"
        ok = t.notna().to_numpy()
    else:
        return None
    if not ok[0]:
        return None
    secs = (t - t.iloc[0]).dt.total_seconds().to_numpy(dtype=float, na_value=np.nan)
    return secs, str(first), kind, ok


def _line_offset(data: bytes, index: int) -> int:
    """Byte offset of 0-based line ``index`` in data whose lines end with LF or CRLF."""
    pos = -1
    for _ in range(index):
        pos = data.find(b"\n", pos + 1)
        if pos < 0:
            raise _Fallback("fewer lines than expected")
    return pos + 1


def _fast_rows(path, data, first, n, d, dec, trailing, first_cells, split, encoding, header_line):
    """The data rows from line ``first`` on, parsed by pandas' C reader.

    Returns the columns (float64 arrays, or object arrays of the cells as found
    for columns whose first cell is not a number) and the 1-based file line of
    each row.  Raises :class:`_Fallback` for anything the line-by-line reader
    treats in its own way (comment lines, lone CR line ends, infinities, rows
    pandas cannot convert ...), so the two readers give the same dataset.
    """
    offset = _line_offset(data, first)
    if data.find(b"\r", offset) >= 0 and data.count(b"\r", offset) != data.count(b"\r\n", offset):
        raise _Fallback("lone CR line ends")
    # without quotes (which may hold line ends) every line is one row of pandas: no need to count them
    quoted = data.find(b'"', offset) >= 0
    nlines = None
    if quoted:
        nlines = data.count(b"\n", offset) + (0 if data.endswith(b"\n") or offset >= len(data) else 1)
    ncols = n + (1 if trailing else 0)
    objcols = [j for j in range(n) if _kind(first_cells[j], dec) in ("stamp", "text")]
    # integers too long for float64 (epoch ns, us) are read exactly, as int64
    intcols = [j for j in range(n) if j not in objcols and re.fullmatch(r"[+-]?[0-9]{16,19}", first_cells[j])]
    dtype = {j: (object if j in objcols else np.int64 if j in intcols else np.float64) for j in range(ncols)}
    buf = _io.BytesIO(data)
    buf.seek(offset)
    try:
        df = pd.read_csv(buf, sep=r"\s+" if d == " " else d, decimal=dec, header=None, names=list(range(ncols)),
                         index_col=False, dtype=dtype, keep_default_na=False,
                         na_values={j: _NA_STRINGS for j in range(ncols) if j not in objcols + intcols},
                         skip_blank_lines=False, engine="c", quotechar='"', encoding=encoding)
    except (ValueError, TypeError, UnicodeDecodeError, pd.errors.ParserError, OverflowError):
        raise _Fallback("a row pandas' reader cannot take") from None
    finally:
        buf.close()
    if nlines is None:
        nlines = len(df)
    elif len(df) != nlines:
        raise _Fallback("quoted line ends")
    cols = [df[j].to_numpy(dtype=object if j in objcols else np.int64 if j in intcols else np.float64, copy=False)
            for j in range(n)]
    if trailing:
        last = df[ncols - 1].to_numpy(dtype=np.float64)
        if not np.all(np.isnan(last)):
            raise _Fallback("text after the last delimiter")
    del df
    flagged = np.zeros(nlines, dtype=bool)
    for j, c in enumerate(cols):
        if j in objcols:
            flagged |= (c == "")
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
            if not ln.strip():
                drop.append(i)
                continue
            if _is_comment(ln, d):
                raise _Fallback("comment lines among the data")  # the line-by-line reader records them
            cells = split(ln)
            if all(c == "" for c in cells):
                drop.append(i)
                continue
            if len(cells) != n:
                like = f" (as in the header on line {header_line})" if header_line else ""
                raise RecordingError(path, first + i + 1, f"expected {n} fields{like}, found {len(cells)}")
        if drop:
            keep = np.ones(nlines, dtype=bool)
            keep[drop] = False
    rownums = range(first + 1, first + 1 + nlines)  # file line of each row, without an array
    if keep is not None:
        cols = [c[keep] for c in cols]
        rownums = np.arange(first + 1, first + 1 + nlines)[keep]
    return cols, rownums


def _epoch_unit(path, vals, tname, line):
    """(factor to s, unit) when a unitless time column holds Unix epoch times, else None."""
    v0 = float(vals[0])
    for unit, f in _EPOCH_UNITS:
        if _EPOCH_RANGE_S[0] <= abs(v0) * f <= _EPOCH_RANGE_S[1]:
            break
    else:
        return None
    k = min(vals.size, 100_001)
    steps = np.diff(vals[:k])
    step = float(np.median(steps)) * f if steps.size else math.nan
    if step > 0 and not 1e-7 <= step <= 1e4:  # 10 MHz to one sample every 3 hours (repeats: check_order)
        raise RecordingError(path, line, f"time column '{tname}' has no unit and holds {v0:.17g}, a Unix epoch "
                             f"time in {unit} by its size, but its steps ({step / f:.6g} {unit}) do not give a "
                             "sample rate between 1e-4 Hz and 10 MHz; pass time_unit= (s, ms, us, ns)")
    return f, unit


def read_csv(path, data: bytes, *, channel=None, sample_rate=None, time_column=None, time_unit=None,
             units=None, resample=None, gap_factor=5.0, repair_time=False, delimiter=None, decimal=None,
             encoding=None):
    """Read a CSV or text export into a recording Dataset.

    Parameters are those of :func:`vibkit.io.read_recording`; ``data`` holds the
    file's bytes.

    Returns
    -------
    xarray.Dataset

    Raises
    ------
    RecordingError
        The file cannot be read without guessing (message names file and line).

    Notes
    -----
    The layout (encoding, delimiter, decimal mark, metadata, header, units row,
    first data row) is worked out from the first MiB; the data rows are then
    parsed by pandas' C reader.  Anything that reader cannot take exactly as the
    line-by-line reader would (comment lines among the data, text in numbers,
    ragged long rows, infinities, lone CR line ends) sends the file through the
    line-by-line reader, which says where and what.
    """
    kw = dict(channel=channel, sample_rate=sample_rate, time_column=time_column, time_unit=time_unit, units=units,
              resample=resample, gap_factor=gap_factor, repair_time=repair_time, delimiter=delimiter,
              decimal=decimal, encoding=encoding)
    try:
        return _read_csv(path, data, fast=True, **kw)
    except _Fallback as why:
        try:
            return _read_csv(path, data, fast=False, **kw)
        except MemoryError:
            raise RecordingError(path, None, f"not enough memory: {len(data) / 1e6:.0f} MB of rows need the "
                                 f"line-by-line reader ({why}); remove that from the file or read it in "
                                 "parts") from None


def _decode_head(path, data, encoding):
    """(text of the first complete lines, notes, codec for the rest, bytes to parse) for the fast path."""
    if encoding is not None or data.startswith(tuple(b for b, _ in _BOMS)) or utf16_without_bom(data):
        text, notes = _decode(path, data, encoding)  # transcoded whole: pandas reads the UTF-8 bytes
        return text, notes, "utf-8", text.encode("utf-8"), True
    if len(data) <= _HEAD_BYTES:
        text, notes = _decode(path, data, None)
        codec = "utf-8" if not notes else notes[0].split()[1]
        return text, notes, codec, data, True
    head = data[:_HEAD_BYTES]
    head = head[:head.rfind(b"\n") + 1]
    if not head:
        raise _Fallback("no complete line in the first MiB")
    text, notes = _decode(path, head, None)
    codec = "utf-8" if not notes else notes[0].split()[1]
    return text, notes, codec, data, False


def _read_csv(path, data: bytes, *, fast, channel=None, sample_rate=None, time_column=None, time_unit=None,
              units=None, resample=None, gap_factor=5.0, repair_time=False, delimiter=None, decimal=None,
              encoding=None):
    history = []
    pdata, complete = data, True
    if fast:
        try:
            text, notes, codec, pdata, complete = _decode_head(path, data, encoding)
        except RecordingError:
            if len(data) <= _HEAD_BYTES:
                raise
            raise _Fallback("the first MiB cannot be laid out alone") from None
    else:
        text, notes = _decode(path, data, encoding)
    history += notes
    lines = re.split(r"\r\n|\r|\n", text)
    if lines and lines[-1] == "":
        lines.pop()
    if not any(ln.strip() for ln in lines):
        raise RecordingError(path, None, "file holds only blank lines; expected a header and rows of numbers")

    sniff = _sniff(lines, delimiter, decimal)
    if sniff is None and not complete:
        raise _Fallback("the first MiB cannot be laid out alone")
    if sniff is None:
        body = [i for i, ln in enumerate(lines) if ln.strip() and not ln.lstrip().startswith(_COMMENT)]
        last = max(i for i, ln in enumerate(lines) if ln.strip()) + 1
        if not body:
            raise RecordingError(path, last, "found only comment lines; expected rows of numbers")
        for i in body:
            cells = [c.strip('"') for c in re.split(r"[,;\t| ]+", lines[i].strip())]
            if all(c.lower() in _MISSING for c in cells):
                raise RecordingError(path, i + 1, "all values are missing (NaN or empty); "
                                                  "expected rows of numbers")
        raise RecordingError(path, last, "no data rows found (expected rows of numbers below the header)")
    d, dec, n, trailing, numcols = sniff
    split = _Splitter(d, trailing)

    # first data row
    first = None
    nonblank = []  # (index, cells) of non-comment, non-blank lines before the data
    for i, ln in enumerate(lines):
        if not ln.strip() or _is_comment(ln, d) and not _hash_header(ln, d, n, split):
            continue
        cells = split(ln)
        if all(c == "" for c in cells):
            continue
        if _data_like(cells, n, dec, numcols):
            first = i
            break
        nonblank.append((i, cells))
    if first is None and not complete:
        raise _Fallback("the first MiB cannot be laid out alone")
    if first is None:
        allmiss = [i for i, c in nonblank if len(c) == n and all(_kind(x, dec) == "missing" for x in c)]
        if allmiss:
            raise RecordingError(path, allmiss[0] + 1, "all values are missing (NaN or empty); "
                                                       "expected at least one number per row")
        i_last = nonblank[-1][0] + 1 if nonblank else None
        raise RecordingError(path, i_last, "no data rows found (expected rows of numbers below the header)")
    if delimiter is None and d != ",":
        history.append(f"delimiter {_DELIM_NAMES[d]} detected")
    elif delimiter is not None:
        history.append(f"delimiter {_DELIM_NAMES[d]} (given)")
    if decimal is None:
        if dec == "," and any("," in c for ln in lines[first:first + 200] for c in split(ln)
                              if not _is_comment(ln, d)):
            history.append("decimal comma detected")
        elif dec == ",":
            dec = "."

    # header row
    header, header_line, meta_lines = None, None, []
    unit_row, unit_line = None, None
    if (len(nonblank) > 1 and len(nonblank[-1][1]) == n and len(nonblank[-2][1]) == n
            and any(nonblank[-1][1]) and all(_is_unit_cell(c) for c in nonblank[-1][1])
            and all(_kind(c, dec) in ("text", "missing") for c in nonblank[-2][1])):
        unit_line, unit_row = nonblank[-1][0] + 1, nonblank[-1][1]  # a row of units below the names
        nonblank = nonblank[:-1]
    if nonblank:
        hi, hcells = nonblank[-1]
        kinds = [_kind(c, dec) for c in hcells]
        if len(hcells) == n and "num" not in kinds and "stamp" not in kinds and "text" in kinds:
            header, header_line = hcells, hi + 1
        elif (len(hcells) == n and "num" in kinds and "text" in kinds and len(nonblank) > 1
              and len(nonblank[-2][1]) == n
              and all(_kind(c, dec) in ("text", "missing") for c in nonblank[-2][1])):
            j = kinds.index("text")
            col = nonblank[-2][1][j]
            raise RecordingError(path, hi + 1, f"expected a number in column '{col}', found '{hcells[j]}'")
        elif len(hcells) != n and _mostly_numbers(kinds):  # a ragged first data row
            raise RecordingError(path, hi + 1, f"expected {n} fields, found {len(hcells)}")
    for i in range(first):
        if lines[i].strip() and i + 1 not in (header_line, unit_line):
            meta_lines.append(i)

    # metadata
    pairs, free = [], []
    for i in meta_lines:
        key, value = _meta_pair(lines[i], d, dec)
        if key is None:
            if value:
                free.append(value)
        else:
            pairs.append((i + 1, key, value))
    if header is None:
        for lineno, key, value in pairs:
            if key.lower() in ("headers", "header", "columns") and isinstance(value, str):
                cells = [c.strip() for c in re.split(r"[,;\t]", value)]
                if len(cells) == n:
                    header, header_line = cells, lineno
                    history.append(f"column names from header line {lineno} ('{key}')")
                    break
    elif header_line:
        history.append(f"header row on line {header_line}")
    if pairs:
        history.append(f"{len(pairs)} metadata line(s) above the data kept as attrs")

    # data rows
    rows, rownums, after = [], [], []
    if fast:
        cols, rownums = _fast_rows(path, pdata, first, n, d, dec, trailing, split(lines[first]), split, codec,
                                   header_line)
        nrows = len(rownums)
        if nrows < 2:
            raise _Fallback("fewer than 2 rows")
        history.append(f"{nrows} data rows from line {first + 1} parsed by pandas' C reader")
    plain = d != " " and not trailing  # fast path: split, strip only lines with spaces
    for i in range(first, len(lines) if not fast else first):
        ln = lines[i]
        if plain and ln and ln[0] not in _MAYBE_COMMENT and '"' not in ln:
            cells = ln.split(d)
            if " " in ln or "\t" in ln:
                cells = [c.strip() for c in cells]
            if len(cells) == n and any(cells):
                rows.append(cells)
                rownums.append(i + 1)
                continue
        if not ln.strip():
            continue
        if _is_comment(ln, d):
            after.append(i + 1)
            key, value = _meta_pair(ln, d, dec)
            if key is not None:
                pairs.append((i + 1, key, value))
            elif value:
                free.append(value)
            continue
        cells = split(ln)
        if all(c == "" for c in cells):  # spreadsheets pad with empty rows (';;')
            continue
        if len(cells) != n:
            like = f" (as in the header on line {header_line})" if header_line else ""
            raise RecordingError(path, i + 1, f"expected {n} fields{like}, found {len(cells)}")
        rows.append(cells)
        rownums.append(i + 1)
    if after:
        history.append(f"{len(after)} comment line(s) among or after the data skipped (line {after[0]}"
                       + (f" ... {after[-1]})" if len(after) > 1 else ")"))
    if not fast:
        rownums = np.asarray(rownums)
        if len(rows) < 2:
            raise RecordingError(path, int(rownums[0]), "only one data row; expected at least 2 samples")
        cols = list(zip(*rows))
        nrows = len(rows)
        del rows

    # names
    if header is None:
        header = [f"column {j + 1}" for j in range(n)]
        history.append(f"no header row; columns named channel_0 ... channel_{n - 1}")
        split_names = [(f"channel_{j}", None, None) for j in range(n)]
    else:
        split_names = [split_name_unit(h) if h else (f"channel_{j}", None, None) for j, h in enumerate(header)]
    if unit_row is not None and header_line is not None:
        for j, u in enumerate(unit_row):
            u = u.strip("()[]{} ")
            if u and split_names[j][1] is None:
                split_names[j] = (split_names[j][0], u, None)
        history.append(f"units row on line {unit_line}")
    names = [s[0] for s in split_names]
    vars_ = unique_names([safe_name(nm, f"channel_{j}") for j, nm in enumerate(names)])
    vars_ = [v + "_channel" if v in ("time", "segment") else v for v in vars_]
    header_disp = [h if h else f"column {j + 1}" for j, h in enumerate(header)]

    # metadata values needed below
    rate_meta = _rate_from_meta(pairs)
    scale_meta = _scale_from_meta(pairs)

    # time column
    tcol = None
    if time_column is False:
        history.append("no time column (time_column=False given)")
    elif time_column is not None:
        if isinstance(time_column, (int, np.integer)) and not isinstance(time_column, bool):
            if not 0 <= int(time_column) < n:
                raise RecordingError(path, header_line, f"time_column={time_column} is out of range: the file has "
                                     f"{n} column(s), numbered from 0")
            tcol = int(time_column)
        else:
            tcol = _match_column(time_column, header_disp, names, vars_)
            if tcol is None:
                raise RecordingError(path, header_line, f"no time column {time_column!r}; columns: "
                                     + ", ".join(repr(h) for h in header_disp))
    else:
        for j, (nm, ut, _) in enumerate(split_names):
            if is_time_name(nm) and (ut is None or parse_unit(ut) is None):
                tcol = j
                break

    # channel selection
    chan_idx = [j for j in range(n) if j != tcol]
    explicit = channel is not None
    if explicit:
        wanted = [channel] if isinstance(channel, str) else list(channel)
        picked = []
        for w in wanted:
            j = _match_column(w, header_disp, names, vars_)
            if j is None or j == tcol:
                raise RecordingError(path, header_line, f"no channel {w!r}; channels: "
                                     + ", ".join(repr(header_disp[k]) for k in chan_idx))
            picked.append(j)
        chan_idx = list(dict.fromkeys(picked))
    if not chan_idx:
        raise RecordingError(path, header_line, "no data column besides the time column")

    # unit overrides
    if units is not None and not isinstance(units, (str, dict)):
        raise ValueError(f"units must be a unit string or a dict column -> unit, got {type(units).__name__}")
    override = {}
    if isinstance(units, dict):
        for key, u in units.items():
            j = _match_column(key, header_disp, names, vars_)
            if j is None:
                raise ValueError(f"units: no column {key!r} in {path}; columns: "
                                 + ", ".join(repr(h) for h in header_disp))
            override[j] = u
    elif isinstance(units, str):
        override = {j: units for j in chan_idx}

    # time values
    t = None
    time_attrs = {}
    extra_attrs = {}
    if tcol is not None:
        tname = header_disp[tcol]
        tcells = cols[tcol]
        numeric = isinstance(tcells, np.ndarray) and tcells.dtype.kind in "fiu"
        if numeric and tcells.dtype.kind == "f" and np.isnan(tcells).any():
            raise _Fallback("a missing time")  # the line-by-line reader quotes the cell
        stamps = None if numeric or _NUM[dec].fullmatch(tcells[0]) else _parse_stamps(tcells)
        if stamps is not None:
            t, start, kind, ok = stamps
            if not ok.all():
                i = int(np.flatnonzero(~ok)[0])
                raise RecordingError(path, int(rownums[i]), f"expected a time stamp like '{start}' "
                                     f"in column '{tname}', found '{tcells[i]}'")
            history.append(f"time column '{tname}' holds {kind}; time = seconds since {start}")
            extra_attrs["start_time"] = start
        else:
            vals, missing, bad, inf = _parse_numbers(tcells, dec)
            badall = np.union1d(np.union1d(bad, inf), np.flatnonzero(missing))
            if badall.size:
                i = int(badall[0])
                raise RecordingError(path, int(rownums[i]), f"expected a time in column '{tname}', "
                                     f"found '{tcells[i]}'")
            unit_text = split_names[tcol][1]
            if time_unit is not None:
                f = parse_time_unit(time_unit)
                if f is None:
                    raise ValueError(f"time_unit={time_unit!r} is not a time unit (expected s, ms, us, ns, min, h) "
                                 f"for {path}")
                history.append(f"time column '{tname}' in {time_unit} (given)" + ("" if f == 1 else f" -> s (x {f:g})"))
            elif unit_text is not None and parse_time_unit(unit_text) is not None:
                f = parse_time_unit(unit_text)
                history.append(f"time column '{tname}' in {unit_text}" + ("" if f == 1 else f" -> s (x {f:g})"))
            elif unit_text is not None:
                raise RecordingError(path, header_line, f"time column '{tname}' has unit '{unit_text}'; "
                                     "expected s, ms, us or time stamps (pass time_unit=)")
            else:
                f = 1.0
                step = float(np.median(np.diff(vals))) if vals.size > 1 else 0.0
                if rate_meta and step > 0 and abs(step * rate_meta[0] / 1e3 - 1) < 0.05:
                    f = 1e-3
                    history.append(f"time column '{tname}' has no unit; read as ms because its steps match "
                                   f"the header's sample rate {rate_meta[0]:g} Hz")
                else:
                    epoch = _epoch_unit(path, vals, tname, int(rownums[0]))
                    if epoch is None:
                        history.append(f"time column '{tname}' has no unit; read as s")
                    else:
                        f, eunit = epoch
                        start = datetime.fromtimestamp(float(vals[0]) * f, tz=timezone.utc)
                        history.append(f"time column '{tname}' has no unit; its values ({vals[0]:.17g} ...) are "
                                       f"Unix epoch times in {eunit} by their size and steps; read as {eunit} "
                                       f"(start {start.isoformat()}; pass time_unit= to override)")
                        extra_attrs.setdefault("start_time", start.isoformat())
            if vals.size and abs(vals[0]) * f > 1e6:
                extra_attrs["time_offset_s"] = float(vals[0] * f)
                history.append(f"time shifted by {vals[0] * f:.6f} s so that it starts at 0 (epoch-like values)")
                t = (vals - vals[0]) * f
            else:
                t = vals * f
        time_attrs["column"] = tname

    # channels
    channels = []
    for j in chan_idx:
        head = header_disp[j]
        nm, unit_text, note = split_names[j]
        cells = cols[j]
        vals, missing, bad, inf = _parse_numbers(cells, dec)
        if bad.size and bad.size == np.count_nonzero(~missing) and not explicit and len(chan_idx) > 1:
            history.append(f"column '{head}' holds text, not numbers; skipped")
            continue
        if bad.size:
            i = int(bad[0])
            raise RecordingError(path, int(rownums[i]), f"expected a number in column '{head}', found '{cells[i]}'")
        if inf.size:
            i = int(inf[0])
            raise RecordingError(path, int(rownums[i]), f"expected a finite number in column '{head}', "
                                 f"found '{cells[i]}'")
        nmiss = int(np.count_nonzero(np.isnan(vals)))
        if nmiss == vals.size:
            msg = (f"all values in column '{head}' are missing (NaN or empty), lines "
                   f"{rownums[0]}-{rownums[-1]}; expected numbers")
            if explicit or len(chan_idx) == 1:
                raise RecordingError(path, None, msg)
            history.append(msg.replace("; expected numbers", "; column skipped"))
            continue
        if nmiss:
            history.append(f"column '{head}': {nmiss} missing value(s) kept as NaN")
        attrs = {"column": head, "source_name": head}
        named = is_counter_name(nm) and unit_text is None and np.all(np.isnan(vals) | (vals == np.round(vals)))
        if named or is_counter_ramp(vals):
            attrs[COUNTER_ATTR] = 1
            why = "its name" if named else "a +1 integer ramp"
            history.append(f"column '{head}' counts samples ({why}); never the default channel")
        if j in override:
            u_text = override[j]
            unit = parse_unit(u_text) if isinstance(u_text, str) else None
            if unit is None:
                raise ValueError(f"units[{head!r}]={u_text!r} (for {path}) is not a unit vibkit knows; expected e.g. "
                                 "'m/s^2', 'g', 'mm', 'm', 'mm/s', 'counts' or a scaled one like 'g/2048'")
            source = f"{u_text} (given)"
        elif unit_text is not None:
            unit = parse_unit(unit_text)
            source = unit_text
            if note:
                history.append(note)
        else:
            unit, source = None, None
        if (unit is None and unit_text is None or unit is not None and unit.factor is None) and scale_meta:
            factor, su, lineno, stext = scale_meta
            history.append(f"column '{head}' in counts, scale from header line {lineno} ('{stext}') "
                           f"-> {su.si} (x {factor:.9g})")
            vals = vals * factor
            attrs["original_units"] = "counts"
            ch_units, quantity = su.si, su.quantity
        elif unit is None:
            if unit_text is None:
                history.append(f"column '{head}' has no unit; values kept as found (units 'unknown'; "
                               f"pass units={{'{vars_[j]}': ...}})")
                ch_units = "unknown"
            else:
                history.append(f"unit '{unit_text}' of column '{head}' not recognised; values kept as found")
                ch_units = unit_text
            quantity = "other"
        elif unit.factor is None:
            history.append(f"column '{head}' in counts with no scale; kept in counts "
                           f"(pass units={{'{vars_[j]}': 'g/<counts per g>'}})")
            ch_units, quantity = "counts", "other"
            attrs["original_units"] = source
        else:
            if unit.factor != 1.0:
                history.append(f"column '{head}' in {source} -> {unit.si} (x {unit.factor:.9g})")
                vals = vals * unit.factor
            elif j in override:
                history.append(f"column '{head}' in {source}")
            attrs["original_units"] = unit.text
            ch_units, quantity = unit.si, unit.quantity
        channels.append(Channel(vars_[j], vals, ch_units, nm, quantity, attrs))
    if not channels:
        raise RecordingError(path, header_line, "no numeric data column found")

    # time base
    if sample_rate is not None:
        fs_given = float(sample_rate)
    else:
        fs_given = None
    segment = None
    if t is None:
        if fs_given is not None:
            fs = fs_given
            history.append(f"no time column; time = sample index / {fs:g} Hz (sample_rate given)")
        elif rate_meta is not None:
            fs = rate_meta[0]
            history.append(f"no time column; time = sample index / {fs:g} Hz "
                           f"(header line {rate_meta[1]}, '{rate_meta[2]}')")
        else:
            raise RecordingError(path, header_line, "no time column and no sample rate in the header; "
                                 "expected a time column (time_column=) or a sample rate (sample_rate=)")
        t = np.arange(nrows) / fs
        jitter = 0.0
    else:
        keep, notes, t = check_order(t, rownums, path=path, column=header_disp[tcol], repair=repair_time)
        history += notes
        if repair_time and (keep.size != t.size or np.any(keep != np.arange(t.size))):  # unrepaired: all kept
            t = t[keep]
            for ch in channels:
                ch.values = ch.values[keep]
        if t.size < 2:
            raise RecordingError(path, int(rownums[0]), "only one sample left after repairing time; "
                                 "expected at least 2")
        diag = diagnose(t, gap_factor=gap_factor)
        measured = 1.0 / diag.period_s
        if fs_given is not None:
            fs = fs_given
            src = "sample_rate given"
        elif rate_meta is not None:
            fs = rate_meta[0]
            src = f"header line {rate_meta[1]}, '{rate_meta[2]}'"
        else:
            fs = measured
            src = None
        if src is None:
            history.append(f"sample rate {fs:.6g} Hz from the mean time step inside segments")
        else:
            history.append(f"sample rate {fs:.6g} Hz ({src}); the time stamps give {measured:.6g} Hz")
            if abs(measured / fs - 1) > 0.01:
                history.append(f"nominal and measured sample rates differ by {100 * (measured / fs - 1):+.2g} %")
        jitter = diag.jitter_rms
        if diag.n_segments > 1:
            history.append(f"{diag.n_segments} segments split at gaps > {gap_factor:g} sample periods "
                           f"(gaps {diag.gaps_s.min():.6g} to {diag.gaps_s.max():.6g} s); kept as segments, "
                           "not bridged")
            segment = diag.segment
        policy = "resampled below" if resample == "linear" else "kept as is"
        history.append(f"jitter rms {_pct(diag.jitter_rms)} % of the period "
                       f"(max {_pct(diag.jitter_max)} %), {policy}")
        if resample == "linear":
            cols_in = {ch.name: ch.values for ch in channels}
            seg_in = diag.segment
            t, cols_out, seg_out = resample_linear(t, cols_in, seg_in, fs)
            for ch in channels:
                ch.values = cols_out[ch.name]
            segment = seg_out if diag.n_segments > 1 else None
            history.append(f"resampled linearly to {fs:g} Hz, each segment on its own")
        extra_attrs["time_jitter_rms_percent"] = float(100 * jitter)
        extra_attrs["segment_count"] = int(diag.n_segments)
    if free:
        pairs.append((0, "comment", "\n".join(free)))
    metadata = metadata_attrs([(k, v) for _, k, v in pairs])
    metadata.update(extra_attrs)
    return build_recording(time=t, channels=channels, segment=segment, path=path, data_bytes=data,
                           reader="vibkit.io.csv", sample_rate_hz=fs, history=history,
                           metadata=metadata, time_attrs=time_attrs)
