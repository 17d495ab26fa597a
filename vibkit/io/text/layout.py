"""The layout of a text recording: encoding, delimiter, decimal mark, header, units row, metadata.

:func:`_read_layout` works out where the data rows start and what sits above
them; the rows themselves are read by :mod:`.fastpath` or line by line in
:mod:`vibkit.io.text.csv`.
"""

from __future__ import annotations

import re
from collections import Counter
from dataclasses import dataclass

from ...runtime.reader_options import spell
from ..errors import RecordingError
from ..largefile import LargeFile
from .cells import (
    _COMMENT,
    _DELIM_NAMES,
    _MISSING,
    _NUM,
    DELIMITERS,
    _data_like,
    _is_comment,
    _kind,
    _mostly_numbers,
    _Splitter,
)
from .fastpath import _HEAD_BYTES, _Fallback
from .metadata import _header_from_meta, _metadata
from .units import is_time_name, parse_time_unit, parse_unit

__all__ = ["MAX_COLUMNS", "utf16_without_bom", "streamable_text"]

#: columns a text recording may have (a row per sample, a column per channel); a wider line is refused before
#: the layout is worked out, which looks at every cell of the last 200 lines
MAX_COLUMNS = 4096


def _check_width(path, lines) -> None:
    """Refuse a line of more than :data:`MAX_COLUMNS` fields (by any delimiter) among the first and the last
    200 lines: counted in C, before any cell is classified."""
    seen = list(enumerate(lines[:200])) + list(enumerate(lines[-200:], start=max(len(lines) - 200, 0)))
    for i, ln in seen:
        if len(ln) <= MAX_COLUMNS:  # fewer characters than the limit: fewer fields too
            continue
        n = max(ln.count(d) for d in DELIMITERS if d != " ") + 1
        if n <= MAX_COLUMNS and len(ln) > 64 * MAX_COLUMNS:
            n = len(ln.split())
        if n > MAX_COLUMNS:
            raise RecordingError(
                path,
                i + 1,
                f"{n} columns, more than the {MAX_COLUMNS} a recording may have (one row per sample, one column "
                "per channel); a file with one row per channel must be transposed",
            )


_CONTROL = re.compile("[\x00-\x08\x0b\x0e-\x1f\x7f-\x9f]")
_BOMS = (
    (b"\xff\xfe\x00\x00", "utf-32"),
    (b"\x00\x00\xfe\xff", "utf-32"),
    (b"\xff\xfe", "utf-16"),
    (b"\xfe\xff", "utf-16"),
)


def _hash_header(line: str, delim: str, n: int, split) -> bool:
    """A header whose first column is named '#' (a sample counter): '#,time (s),x (mm)', not a comment."""
    s = line.lstrip()
    return delim != " " and s.startswith("#" + delim) and len(split(s)) == n


def _is_unit_cell(cell: str) -> bool:
    """An empty cell or a unit alone ('s', '[ms]', '(g)', 'mm'), as in a units row below the header."""
    u = cell.strip("()[]{} ")
    return not u or parse_unit(u) is not None or parse_time_unit(u) is not None


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
            raise RecordingError(path, None, f"cannot decode as {spell('encoding', encoding)}: {exc}") from None
    for bom, codec in _BOMS:
        if data.startswith(bom):
            try:
                return data.decode(codec), [f"encoding {codec.upper()} (byte-order mark)"]
            except UnicodeDecodeError as exc:
                raise RecordingError(
                    path,
                    None,
                    f"starts with a {codec.upper()} byte-order mark but cannot be "
                    f"decoded as {codec.upper()} ({exc.reason} at byte {exc.start})",
                ) from None
    codec = utf16_without_bom(data)
    if codec is not None:
        try:
            return data.decode(codec), [f"encoding {codec.upper()} (no byte-order mark; every other byte is zero)"]
        except UnicodeDecodeError as exc:
            raise RecordingError(
                path,
                None,
                f"looks like {codec.upper()} text without a byte-order mark but "
                f"cannot be decoded as such ({exc.reason} at byte {exc.start}); "
                f"pass {spell('encoding')}",
            ) from None
    head = data[:65536]
    nul = head.find(b"\x00")
    if nul >= 0:
        raise RecordingError(
            path,
            None,
            f"binary content (NUL byte at offset {nul}); "
            "expected a text file, netCDF/HDF5 or a waveform format obspy reads",
        )
    try:
        text, notes = data.decode("utf-8-sig"), []
    except UnicodeDecodeError:
        try:
            text, notes = data.decode("cp1252"), ["encoding cp1252 (the file is not valid UTF-8)"]
        except UnicodeDecodeError:
            text, notes = data.decode("latin-1"), ["encoding latin-1 (the file is neither UTF-8 nor cp1252)"]
    sample = text[:65536]
    ctrl = len(_CONTROL.findall(sample)) if _CONTROL.search(sample) else 0
    if sample and ctrl > max(2, 0.01 * len(sample)):
        raise RecordingError(
            path,
            None,
            f"binary content ({ctrl} control bytes in the first {len(sample)}); "
            "expected a text file, netCDF/HDF5 or a waveform format obspy reads",
        )
    return text, notes


def streamable_text(head: bytes) -> bool:
    """Whether a text file with this head can be parsed from its bytes as they are (no transcoding first)."""
    return not head.startswith(tuple(b for b, _ in _BOMS)) and utf16_without_bom(head) is None


def _decode_head(path, data, encoding):
    """(text of the first complete lines, notes, codec for the rest, bytes to parse) for the fast path.

    ``data`` is the file's bytes, or a :class:`~vibkit.io.largefile.LargeFile` (streamed; its head needs no
    transcoding and no encoding is forced)."""
    if isinstance(data, LargeFile):
        head = data.head[: data.head.rfind(b"\n") + 1]
        if not head:
            raise _Fallback("no complete line in the first MiB")
        text, notes = _decode(path, head, None)
        codec = "utf-8" if not notes else notes[0].split()[1]
        return text, notes, codec, data, False
    if encoding is not None or data.startswith(tuple(b for b, _ in _BOMS)) or utf16_without_bom(data):
        text, notes = _decode(path, data, encoding)  # transcoded whole: pandas reads the UTF-8 bytes
        return text, notes, "utf-8", text.encode("utf-8"), True
    if len(data) <= _HEAD_BYTES:
        text, notes = _decode(path, data, None)
        codec = "utf-8" if not notes else notes[0].split()[1]
        return text, notes, codec, data, True
    head = data[:_HEAD_BYTES]
    head = head[: head.rfind(b"\n") + 1]
    if not head:
        raise _Fallback("no complete line in the first MiB")
    text, notes = _decode(path, head, None)
    codec = "utf-8" if not notes else notes[0].split()[1]
    return text, notes, codec, data, False


#: a line of numbers (no spaces, no quotes) and delimiters, by (delimiter, decimal mark): its cells are numbers
_NUMBERS_ROW = {
    (d, dec): re.compile(f"{_NUM[dec].pattern}(?:{re.escape(d)}{_NUM[dec].pattern})*")
    for d in ",;\t|"
    for dec in ".,"
    if d != dec
}


def _one_cell(body, d) -> bool:
    """Whether every line of ``body`` splits at ``d`` into one cell, the line stripped: no line holds the delimiter
    (whitespace aside) or a quote. The sniff then takes each line as that cell without splitting it (a small file's
    200 lines were split for each delimiter it does not use)."""
    return d != " " and not any(d in ln or '"' in ln for ln in body)


def _sniff(lines, delimiter, decimal, text=None):
    """Choose delimiter, decimal mark, field count and numeric columns from the end of the file.

    ``text`` is the text the lines were split from (a delimiter it does not hold is tried once for all)."""
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
    # a row's kinds by its cells and decimal mark: a line without a delimiter splits into the same one cell
    # for every delimiter, so each is classified once ((cells, dec) -> kinds, or None when not mostly numbers)
    seen = {}
    absent = None  # the first of ';', tab, '|' found nowhere in the text
    for order, d in enumerate(delims):
        if text is not None and d in ";\t|" and d not in text:
            # a delimiter found nowhere splits every line as any other such one does: the same reading,
            # which loses to the earlier delimiter on the tie
            if absent is not None:
                continue
            absent = d
        trailing = d != " " and sum(ln.rstrip().endswith(d) for ln in tail) >= 0.9 * len(tail)
        split = _Splitter(d, trailing)
        body = [ln for ln in tail if not _is_comment(ln, d)]
        if not body:
            continue
        cells = {}  # the line's cells, split once for both decimal marks
        one_cell = _one_cell(body, d)
        decs = (decimal,) if decimal is not None else ((".",) if d == "," else (".", ","))
        for dec in decs:
            whole = _NUMBERS_ROW.get((d, dec))
            kinds = [_row_kinds((ln.strip(),), dec, seen) for ln in body] if one_cell else []
            for ln in () if one_cell else body:
                if whole is not None and whole.fullmatch(ln):  # numbers and delimiters only: no split needed
                    kinds.append(["num"] * (ln.count(d) + 1))
                    continue
                r = cells.get(ln)
                if r is None:
                    r = cells[ln] = tuple(split(ln))
                kinds.append(_row_kinds(r, dec, seen))
            kinds = [k for k in kinds if k is not None]  # not headers, notes or metadata
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


def _row_kinds(cells: tuple, dec: str, seen: dict):
    """The kinds of a row's cells, or None when the row is not mostly numbers; remembered in ``seen``."""
    key = (cells, dec)
    kinds = seen.get(key, False)
    if kinds is False:
        kinds = [_kind(c, dec) for c in cells]
        kinds = seen[key] = kinds if _mostly_numbers(kinds) else None
    return kinds


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


@dataclass
class _Layout:
    """Where the data rows of a text recording start and what sits above them."""

    lines: list  # the text's lines (of the first MiB on the fast path)
    delim: str  # " " means runs of whitespace
    dec: str  # decimal mark
    n: int  # fields per data row
    trailing: bool  # every row ends with the delimiter
    split: _Splitter
    first: int  # 0-based line of the first data row
    header: list | None  # column names as found
    header_line: int | None  # 1-based
    unit_row: list | None
    unit_line: int | None
    pairs: list  # (line, key, value) of the metadata lines
    free: list  # free comment text


def _read_layout(path, text: str, delimiter, decimal, complete: bool, history: list) -> _Layout:
    """The layout of ``text``, the notes on it appended to ``history``.

    ``complete`` is False when ``text`` holds only the first MiB of the file:
    a layout that cannot be told from it raises :class:`_Fallback`.
    """
    lines = text.split("\n") if "\r" not in text else re.split(r"\r\n|\r|\n", text)
    if lines and lines[-1] == "":
        lines.pop()
    if not any(ln.strip() for ln in lines):
        raise RecordingError(path, None, "file holds only blank lines; expected a header and rows of numbers")
    _check_width(path, lines)

    sniff = _sniff(lines, delimiter, decimal, text)
    if sniff is None and not complete:
        raise _Fallback("the first MiB cannot be laid out alone")
    if sniff is None:
        _no_data(path, lines)
    d, dec, n, trailing, numcols = sniff
    split = _Splitter(d, trailing)

    first, nonblank = _first_data_row(lines, d, dec, n, numcols, split)
    if first is None and not complete:
        raise _Fallback("the first MiB cannot be laid out alone")
    if first is None:
        allmiss = [i for i, c in nonblank if len(c) == n and all(_kind(x, dec) == "missing" for x in c)]
        if allmiss:
            raise RecordingError(
                path, allmiss[0] + 1, "all values are missing (NaN or empty); expected at least one number per row"
            )
        i_last = nonblank[-1][0] + 1 if nonblank else None
        raise RecordingError(path, i_last, "no data rows found (expected rows of numbers below the header)")
    if delimiter is None and d != ",":
        history.append(f"delimiter {_DELIM_NAMES[d]} detected")
    elif delimiter is not None:
        history.append(f"delimiter {_DELIM_NAMES[d]} (given)")
    if decimal is None:
        if dec == "," and any(
            "," in c for ln in lines[first : first + 200] for c in split(ln) if not _is_comment(ln, d)
        ):
            history.append("decimal comma detected")
        elif dec == ",":
            dec = "."

    header, header_line, unit_row, unit_line = _header_rows(path, nonblank, n, dec, first)
    if header is None and delimiter is None and decimal is None:
        _split_decimals(path, lines, first, d, n, split)
    meta_lines = [i for i in range(first) if lines[i].strip() and i + 1 not in (header_line, unit_line)]
    pairs, free = _metadata(lines, meta_lines, d, dec)
    if header is None:
        found = _header_from_meta(pairs, n)
        if found is not None:
            header, header_line, key = found
            history.append(f"column names from header line {header_line} ('{key}')")
    elif header_line:
        history.append(f"header row on line {header_line}")
    if pairs:
        history.append(f"{len(pairs)} metadata line(s) above the data kept as attrs")
    return _Layout(lines, d, dec, n, trailing, split, first, header, header_line, unit_row, unit_line, pairs, free)


def _split_decimals(path, lines, first, d, n, split):
    """Raise for rows of whole numbers, twice as many as the names on the line above them, split by commas: a
    decimal comma in a comma-separated file ('0,005' read as 0 and 5), which no option reads back."""
    above = next((lines[i] for i in range(first - 1, -1, -1) if lines[i].strip()), None)
    if d != "," or n % 2 or above is None:
        return
    names = split(above)
    rows = [split(ln) for ln in lines[first : first + 50] if ln.strip()]
    if (
        2 * len(names) == n
        and not any(re.fullmatch(r"[-+]?[0-9.eE+-]+", c.strip()) for c in names)
        and all(re.fullmatch(r"[-+]?[0-9]+", c.strip()) for row in rows for c in row)
    ):
        raise RecordingError(
            path,
            first + 1,
            f"rows of {n} whole numbers under {len(names)} column names ({above.strip()!r}): decimal commas in a "
            "comma-separated file ('0,005' splits into 0 and 5)? save it with ';' or a tab between the columns",
        )


def _no_data(path, lines):
    """Raise the error for text in which no delimiter and decimal mark give rows of numbers."""
    body = [i for i, ln in enumerate(lines) if ln.strip() and not ln.lstrip().startswith(_COMMENT)]
    last = max(i for i, ln in enumerate(lines) if ln.strip()) + 1
    if not body:
        raise RecordingError(path, last, "found only comment lines; expected rows of numbers")
    for i in body:
        cells = [c.strip('"') for c in re.split(r"[,;\t| ]+", lines[i].strip())]
        if all(c.lower() in _MISSING for c in cells):
            raise RecordingError(path, i + 1, "all values are missing (NaN or empty); expected rows of numbers")
    raise RecordingError(path, last, "no data rows found (expected rows of numbers below the header)")


def _first_data_row(lines, d, dec, n, numcols, split):
    """(0-based line of the first data row or None, [(line, cells)] of the non-comment lines above it)."""
    nonblank = []
    for i, ln in enumerate(lines):
        if not ln.strip() or _is_comment(ln, d) and not _hash_header(ln, d, n, split):
            continue
        cells = split(ln)
        if all(c == "" for c in cells):
            continue
        if _data_like(cells, n, dec, numcols):
            return i, nonblank
        nonblank.append((i, cells))
    return None, nonblank


#: a column name with its unit: ``t [s]``, ``disp (mm)``
_NAME_WITH_UNIT = re.compile(r".*\S\s*[\[(][^\])]+[\])]\s*")


def _header_rows(path, nonblank, n, dec, first=None):
    """(header cells, its 1-based line, units row cells, its line) from the lines above the data; Nones if absent.

    A line of column names just above the data with one name more or fewer than the rows have fields (a name
    with its unit among them, or a time column's) is refused: read as metadata it turned the time column into
    a channel and named the columns channel_0 ... (a stranger's logger file)."""
    header, header_line = None, None
    unit_row, unit_line = None, None
    if (
        len(nonblank) > 1
        and len(nonblank[-1][1]) == n
        and len(nonblank[-2][1]) == n
        and any(nonblank[-1][1])
        and all(_is_unit_cell(c) for c in nonblank[-1][1])
        and all(_kind(c, dec) in ("text", "missing") for c in nonblank[-2][1])
    ):
        unit_line, unit_row = nonblank[-1][0] + 1, nonblank[-1][1]  # a row of units below the names
        nonblank = nonblank[:-1]
    if nonblank:
        hi, hcells = nonblank[-1]
        kinds = [_kind(c, dec) for c in hcells]
        if len(hcells) == n and "num" not in kinds and "stamp" not in kinds and "text" in kinds:
            header, header_line = hcells, hi + 1
        elif (
            len(hcells) == n
            and "num" in kinds
            and "text" in kinds
            and len(nonblank) > 1
            and len(nonblank[-2][1]) == n
            and all(_kind(c, dec) in ("text", "missing") for c in nonblank[-2][1])
        ):
            j = kinds.index("text")
            col = nonblank[-2][1][j]
            raise RecordingError(path, hi + 1, f"expected a number in column '{col}', found '{hcells[j]}'")
        elif len(hcells) != n and _mostly_numbers(kinds):  # a ragged first data row
            raise RecordingError(path, hi + 1, f"expected {n} fields, found {len(hcells)}")
        elif (
            first is not None
            and hi == first - 1
            and abs(len(hcells) - n) == 1
            and len(hcells) >= 2
            and all(k == "text" for k in kinds)
            and any(_NAME_WITH_UNIT.fullmatch(c) or is_time_name(c) for c in hcells)
        ):
            names = ", ".join(repr(c) for c in hcells)
            raise RecordingError(
                path,
                first + 1,
                f"expected {len(hcells)} fields (as in the header on line {hi + 1}: {names}), found {n}: a column "
                "named and not written, or written and not named",
            )
    return header, header_line, unit_row, unit_line
