"""Universal File Format (UFF/UNV) files: the time responses of dataset 58 (ASCII and binary ``58b``).

A UFF file is a sequence of datasets, each between two delimiter lines ``    -1``; the line after
the opening delimiter gives the dataset number (``    58``; ``    58b`` for binary data, followed by
the byte order, the number of header lines and the number of data bytes).  Dataset 58 ("function
at nodal DOF", SDRC/Siemens I-DEAS universal file specification) is eleven header records and the
data:

====== =====================================================================================
record what vibkit takes from it
====== =====================================================================================
1-5    ID lines (record 1: the description, record 4: often the date)
6      function type (1: time response), response entity name, node and direction
7      ordinate data type (2/4 real single/double, 5/6 complex), number of points, spacing
       (1 even, 0 uneven), abscissa minimum and increment
8      abscissa: data type (17 time), axis label and units label
9      ordinate: data type (12 acceleration, 11 velocity, 8 displacement ...), labels, units label
10, 11 ordinate denominator, z axis (not used)
12     the values: real evenly spaced, one value each; unevenly spaced, (x, y) pairs
====== =====================================================================================

Each dataset 58 that holds a time response is one channel, named after its response node and
direction (``node 12 +Z``), in the unit of record 9's units label (converted to SI; ``units=``
overrides).  Datasets of other numbers (151 header, 164 units, 2411 nodes ...) are skipped and
said in the history; a dataset 58 holding a spectrum or a frequency response (function types 2-9)
or complex values is refused, as are channels that do not share one time base (read one with
``channel=``).  The abscissa increment is written with six significant digits (``9.76563E-04``):
a whole rate in Hz that gives the same six digits (1024 Hz) is taken, and said.
"""

from __future__ import annotations

import re

import numpy as np

from ..runtime.reader_options import spell
from .errors import RecordingError
from .sampled import Column, assemble, select_columns

__all__ = ["sniff_uff", "read_uff", "rate_from_increment"]

_DELIM = re.compile(rb"\A[ \t]*-1[ \t]*\r?\n[ \t]*([0-9]+b?)\b")
_CLOSE = re.compile(r"[ \t\r\n]*-1[ \t]*(?:\r?\n|\Z)")
_FLOAT = re.compile(r"[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[EeDd][-+]?[0-9]+)?")
_DIRECTIONS = {0: "", 1: "+X", 2: "+Y", 3: "+Z", 4: "+RX", 5: "+RY", 6: "+RZ", -1: "-X", -2: "-Y", -3: "-Z"}
_FUNCTIONS = {
    0: "general or unknown",
    1: "time response",
    2: "auto spectrum",
    3: "cross spectrum",
    4: "frequency response function",
    5: "transmissibility",
    6: "coherence",
    7: "auto correlation",
    8: "cross correlation",
    9: "power spectral density",
}


#: dataset numbers of the universal file format that open files (header 151, units 164, nodes 15/2411,
#: elements 2412, functions 58, data at nodes 55/2414 ...): a column of integers that happens to start
#: with -1 is not taken for UFF unless its second value is one of these
DATASETS = frozenset(b"15 18 55 58 82 151 164 781 1858 2400 2411 2412 2414 2420 2429 2430 2435 2452 2467 2477".split())


def sniff_uff(probe) -> bool:
    """Content that opens with a ``-1`` delimiter line and a known dataset number (any suffix)."""
    m = _DELIM.match(probe.head.lstrip(b"\xef\xbb\xbf\r\n"))
    return m is not None and m.group(1).rstrip(b"b") in DATASETS


def rate_from_increment(text: str) -> tuple[float, str | None]:
    """The sample rate [Hz] an abscissa increment written as ``text`` [s] states, and a note when rounded.

    ``1 / increment``, unless a whole number of Hz, written with as many significant digits as
    ``text`` has, gives the same number (``9.76562E-04`` and ``9.76563E-04`` are 1/1024 s rounded to
    even or up): then that whole rate.
    """
    dx = float(text.replace("D", "E").replace("d", "e"))
    fs = 1.0 / dx
    whole = round(fs)
    mant = re.match(r"\s*[-+]?([0-9]*)\.?([0-9]*)", text).groups()
    sig = len((mant[0] + mant[1]).lstrip("0")) or 1
    last = 10.0 ** (np.floor(np.log10(abs(dx))) - (sig - 1)) if dx else 0.0  # one unit in the last digit written
    if whole > 0 and whole != fs and abs(1.0 / whole - dx) <= 0.5 * last * (1 + 1e-9):
        return float(whole), (
            f"abscissa increment {text.strip()} s is 1/{whole} s written with {sig} significant digits: "
            f"sample rate {whole} Hz (1/increment would give {fs:.7g} Hz)"
        )
    return fs, None


def _int(path, line_no, text, what):
    try:
        return int(text.strip() or "0")
    except ValueError:
        raise RecordingError(
            path, line_no, f"expected an integer ({what}) in dataset 58, found {text.strip()!r}"
        ) from None


def _label(text):
    t = text.strip()
    return None if not t or t.upper() == "NONE" else t


class _Lines:
    """The file as lines with their byte offsets (latin-1: one character per byte)."""

    def __init__(self, text):
        self.text = text
        self.starts = [0] + [m.end() for m in re.finditer("\n", text)]
        if self.starts[-1] == len(text):
            self.starts.pop()

    def __len__(self):
        return len(self.starts)

    def __getitem__(self, i):
        end = self.starts[i + 1] if i + 1 < len(self.starts) else len(self.text)
        return self.text[self.starts[i] : end].rstrip("\r\n")

    def index_at(self, offset):
        import bisect

        return bisect.bisect_left(self.starts, offset)


def _datasets(path, text):
    """[(dataset number, 0-based index of its number line)] and the lines."""
    lines = _Lines(text)
    out, i = [], 0
    while i < len(lines):
        if lines[i].strip() == "":
            i += 1
            continue
        if lines[i].strip() != "-1":
            raise RecordingError(
                path, i + 1, f"expected the delimiter line '    -1' of a UFF dataset, found {lines[i][:40]!r}"
            )
        if i + 1 >= len(lines):
            break
        num = lines[i + 1].split()[0] if lines[i + 1].split() else ""
        out.append((num, i + 1))
        j = i + 2
        if num.lower() == "58b":
            fields = lines[i + 1].split()
            if len(fields) < 5:
                raise RecordingError(
                    path, i + 2, "binary dataset 58b header without its byte count; expected 58b bo 2 11 bytes"
                )
            nhead, nbytes = _int(path, i + 2, fields[3], "header lines"), _int(path, i + 2, fields[4], "data bytes")
            data_start = lines.starts[j + nhead] if j + nhead < len(lines) else len(text)
            m = _CLOSE.match(text, data_start + nbytes)
            if m is None:
                raise RecordingError(
                    path,
                    i + 2,
                    f"binary dataset 58b is not closed by a '-1' delimiter line after its {nbytes} data bytes",
                )
            i = lines.index_at(m.end())
            continue
        while j < len(lines) and lines[j].strip() != "-1":
            j += 1
        if j >= len(lines):
            raise RecordingError(
                path, i + 1, f"dataset {num} is not closed by a '-1' delimiter line; the file is cut short"
            )
        i = j + 1
    return out, lines


def _dataset58(path, text, lines, k, binary):
    """(Column, start time [s], sample rate [Hz], x or None, note) of the dataset 58 whose number line is ``k``."""
    h = [lines[k + 1 + r] if k + 1 + r < len(lines) else "" for r in range(11)]
    ln = k + 2  # 1-based line of record 1
    func = _int(path, ln + 5, h[5][0:5], "function type")
    node = _int(path, ln + 5, h[5][41:51], "response node") if h[5][41:51].strip() else 0
    direction = _int(path, ln + 5, h[5][51:55], "response direction") if h[5][51:55].strip() else 0
    entity = _label(h[5][31:41]) or "node"
    ord_type = _int(path, ln + 6, h[6][0:10], "ordinate data type")
    n = _int(path, ln + 6, h[6][10:20], "number of points")
    even = _int(path, ln + 6, h[6][20:30], "abscissa spacing")
    nums = _FLOAT.findall(h[6][30:])
    if len(nums) < 2:
        raise RecordingError(path, ln + 6, "expected the abscissa minimum and increment in record 7 of dataset 58")
    x_type = _int(path, ln + 7, h[7][0:10], "abscissa data type")
    x_unit = _label(h[7][47:67]) or ""
    y_label, y_unit = _label(h[8][26:46]), _label(h[8][47:67])
    timelike = func == 1 or (func == 0 and (x_type == 17 or x_unit.lower() in ("s", "sec", "ms")))
    if not timelike:
        raise RecordingError(
            path,
            ln + 5,
            f"dataset 58 holds function type {func} ({_FUNCTIONS.get(func, 'unknown')}), abscissa type {x_type}; "
            "expected a time response (function type 1) to read as a recording",
        )
    if ord_type not in (2, 4):
        raise RecordingError(
            path,
            ln + 6,
            f"dataset 58 has ordinate data type {ord_type} (complex or unknown); expected real values (2 or 4)",
        )
    count = n if even else 2 * n
    if binary:
        fields = lines[k].split()
        order = "<" if fields[1:2] == ["1"] else ">"
        start = lines.starts[k + 12] if k + 12 < len(lines) else len(text)
        raw = text[start : start + count * 8].encode("latin-1")
        dt = np.dtype(order + "f8")
        if len(raw) < count * 8:
            raise RecordingError(path, ln, f"binary dataset 58b holds {len(raw)} data bytes; expected {count * 8}")
        vals = np.frombuffer(raw, dtype=dt).astype(np.float64)
    else:
        out, r = [], k + 12
        while r < len(lines) and lines[r].strip() != "-1" and len(out) < count:
            out += _FLOAT.findall(lines[r].replace("D", "E").replace("d", "e"))
            r += 1
        if len(out) != count:
            raise RecordingError(
                path, r + 1, f"dataset 58 (line {k + 1}) holds {len(out)} values; record 7 says {count}"
            )
        vals = np.array([float(v) for v in out])
    scale = 1e-3 if x_unit.lower() == "ms" else 1.0
    label = f"{entity} {node} {_DIRECTIONS.get(direction, str(direction))}".strip()
    attrs = {"source_name": label, "uff_node": node, "uff_direction": direction, "uff_function_type": func}
    if _label(h[0]):
        attrs["description"] = h[0].strip()
    if y_label:
        attrs["axis_label"] = y_label
    if even:
        fs, note = rate_from_increment(nums[1])
        fs = fs / scale
        col = Column(label, vals, y_unit, attrs)
        return col, float(nums[0]) * scale, fs, None, note
    x, y = vals[0::2] * scale, vals[1::2]
    return Column(label, y, y_unit, attrs), float(x[0]), None, x, None


def read_uff(path, data, options):
    """A UFF/UNV file's dataset-58 time responses (see the module docstring)."""
    text = data.decode("latin-1")
    if text.startswith("\ufeff") or data.startswith(b"\xef\xbb\xbf"):
        text = data[3:].decode("latin-1")
    sets, lines = _datasets(path, text)
    history, found = [], []
    skipped = [num for num, _ in sets if num.lower() not in ("58", "58b")]
    if skipped:
        history.append("UFF datasets other than 58 skipped: " + ", ".join(dict.fromkeys(skipped)))
    for num, k in sets:
        if num.lower() in ("58", "58b"):
            found.append((k, _dataset58(path, text, lines, k, num.lower() == "58b")))
    if not found:
        raise RecordingError(
            path,
            None,
            "UFF file without dataset 58 (datasets: "
            + (", ".join(dict.fromkeys(n for n, _ in sets)) or "none")
            + "); expected time responses in dataset 58",
        )
    cols = select_columns(path, [c for _, (c, *_rest) in found], options.get("channel"))
    chosen = [(k, rest) for k, rest in found if rest[0] in cols]
    k0, (c0, t0, fs0, x0, note0) = chosen[0]
    for k, (c, t_start, fs, x, _note) in chosen[1:]:
        same = (
            c.values.size == c0.values.size
            and (fs is None) == (fs0 is None)
            and (fs is None or abs(fs / fs0 - 1) < 1e-9)
            and (x is None or np.allclose(x, x0, rtol=0, atol=1e-9 * max(1.0, abs(x0[-1]))))
            and abs(t_start - t0) <= (0.01 / fs0 if fs0 else 0)
        )
        if not same:
            raise RecordingError(
                path,
                k + 1,
                f"dataset 58 '{c.name}' does not share the time base of '{c0.name}' (line {k0 + 1}); "
                f"read one at a time with {spell('channel')}",
            )
    history.append(f"UFF file: {len(found)} dataset(s) 58 (time responses), {len(chosen)} read")
    if note0:
        history.append(note0)
    time = None if x0 is None else x0 - x0[0]
    if fs0 is not None:
        history.append(f"sample rate {fs0:g} Hz from the abscissa increment")
    meta = [("format", "UFF dataset 58"), ("start_offset_s", t0)]
    return assemble(
        path,
        data,
        reader="vibkit.io.uff",
        columns=cols,
        options=options,
        history=history,
        time=time,
        rate=fs0,
        metadata=meta,
    )
