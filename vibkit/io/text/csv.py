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

The reader's parts: :mod:`.layout` (encoding, delimiter, header, units row),
:mod:`.metadata` (metadata lines, sample rate and scale in them),
:mod:`.fastpath` (rows parsed by pandas' C reader), :mod:`.timecolumn` (the time
column and its unit), :mod:`.columns` (names, channels, units) and
:mod:`.cells` (what a cell holds); this module reads the rows line by line when
the fast path cannot, and builds the time base.
"""

from __future__ import annotations

import numpy as np

from ...runtime.reader_options import spell
from ..channels import mark_status
from ..errors import RecordingError
from ..largefile import LargeFile
from ..recording import build_recording, metadata_attrs
from ..timebase import check_order, diagnose, held_update_rate, quantum, resample_linear
from .cells import _MAYBE_COMMENT, DELIMITERS, _is_comment
from .columns import _build_channels, _column_names, _select_channels, _unit_overrides
from .fastpath import _HEAD_BYTES, _Fallback, _fast_rows
from .layout import _decode, _decode_head, _read_layout
from .loggers import app_units
from .metadata import _meta_pair, _rate_from_meta, _scale_from_meta, start_from_meta
from .timecolumn import _choose_time_column, _date_and_time, _joined_stamps, _read_time

__all__ = ["read_csv", "DELIMITERS"]


def _pct(fraction: float) -> str:
    """A fraction as a short percentage; round-off below 1e-6 % shows as 0."""
    return "0" if abs(fraction) < 1e-8 else f"{100 * fraction:.2g}"


def read_csv(
    path,
    data: bytes,
    *,
    channel=None,
    sample_rate=None,
    time_column=None,
    time_unit=None,
    units=None,
    resample=None,
    gap_factor=5.0,
    repair_time=False,
    delimiter=None,
    decimal=None,
    encoding=None,
    date_order=None,
):
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
    kw = dict(
        channel=channel,
        sample_rate=sample_rate,
        time_column=time_column,
        time_unit=time_unit,
        units=units,
        resample=resample,
        gap_factor=gap_factor,
        repair_time=repair_time,
        delimiter=delimiter,
        decimal=decimal,
        encoding=encoding,
        date_order=date_order,
    )
    try:
        return _read_csv(path, data, fast=True, **kw)
    except _Fallback as why:
        if isinstance(data, LargeFile):  # the line-by-line reader reads the file whole
            data = data.read_all()
        try:
            return _read_csv(path, data, fast=False, **kw)
        except MemoryError:
            raise RecordingError(
                path,
                None,
                f"not enough memory: {len(data) / 1e6:.0f} MB of rows need the "
                f"line-by-line reader ({why}); remove that from the file or read it in "
                "parts",
            ) from None


def _read_csv(
    path,
    data: bytes,
    *,
    fast,
    channel=None,
    sample_rate=None,
    time_column=None,
    time_unit=None,
    units=None,
    resample=None,
    gap_factor=5.0,
    repair_time=False,
    delimiter=None,
    decimal=None,
    encoding=None,
    date_order=None,
):
    """:func:`read_csv` through the fast path (``fast=True``, may raise :class:`_Fallback`) or line by line."""
    history = []
    pdata, complete, codec = data, True, None
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
    lay = _read_layout(path, text, delimiter, decimal, complete, history)
    if fast:
        cols, rownums, nrows = _fast_rows_checked(path, lay, pdata, codec, history)
    else:
        cols, rownums, nrows = _read_rows_by_line(path, lay, history)

    n, dec, header_line = lay.n, lay.dec, lay.header_line
    colnames = _column_names(lay.header, n, lay.unit_row, header_line, lay.unit_line, history)
    rate_meta = _rate_from_meta(lay.pairs)
    scale_meta = _scale_from_meta(lay.pairs)
    for j, u in app_units(path, colnames.names, [s[1] for s in colnames.split], lay.free, history).items():
        colnames.split[j] = (colnames.split[j][0], u, None)
    tcol, clocks = _choose_time_column(
        path, time_column, colnames, n, header_line, history, cols, dec, headerless=lay.header is None
    )
    tcol, clocks, date_col = _date_and_time(tcol, clocks, cols, colnames, history)
    chan_idx, explicit = _select_channels(path, channel, tcol, colnames, n, header_line, clocks)
    override = _unit_overrides(path, units, chan_idx, colnames)

    t = None
    time_attrs = {}
    extra_attrs = {}
    tname = None
    if tcol is not None:
        tname = colnames.shown[tcol]
        t = _read_time(
            path,
            cols[tcol] if date_col is None else _joined_stamps(cols[date_col], cols[tcol]),
            tname,
            colnames.split[tcol][1],
            dec,
            rownums,
            header_line,
            time_unit,
            rate_meta,
            history,
            extra_attrs,
            date_order,
        )
        time_attrs["column"] = tname
    channels = _build_channels(
        path, cols, rownums, dec, chan_idx, explicit, override, colnames, scale_meta, header_line, history
    )
    del cols  # the cells as parsed: the channels hold what they need of them
    mark_status(channels, history)
    t, fs, segment = _time_base(
        path,
        t,
        tname,
        channels,
        nrows,
        rownums,
        header_line,
        sample_rate,
        rate_meta,
        resample,
        gap_factor,
        repair_time,
        history,
        extra_attrs,
    )

    pairs, free = lay.pairs, lay.free
    if free:
        pairs.append((0, "comment", "\n".join(free)))
    metadata = metadata_attrs([(k, v) for _, k, v in pairs])
    metadata.update(extra_attrs)
    if "start_time" not in extra_attrs:  # no time stamps: the start a metadata line states, as ISO 8601
        found = start_from_meta(pairs)
        if found is not None and found[0] is None:
            _, lineno, key, value = found
            history.append(
                f"metadata line {lineno} ('{key}: {value}') may be day/month or month/day: not read as the start "
                "(give the date: --date)"
            )
        elif found is not None:
            iso, lineno, key, value = found
            metadata["start_time"] = iso
            history.append(f"start time {iso} from metadata line {lineno} ('{key}: {value}')")
    return build_recording(
        time=t,
        channels=channels,
        segment=segment,
        path=path,
        data_bytes=data,
        reader="vibkit.io.csv",
        sample_rate_hz=fs,
        history=history,
        metadata=metadata,
        time_attrs=time_attrs,
    )


def _fast_rows_checked(path, lay, pdata, codec, history):
    """(columns, file line of each row, row count) parsed by pandas' C reader; :class:`_Fallback` for < 2 rows."""
    first, split = lay.first, lay.split
    cols, rownums = _fast_rows(
        path,
        pdata,
        first,
        lay.n,
        lay.delim,
        lay.dec,
        lay.trailing,
        split(lay.lines[first]),
        split,
        codec,
        lay.header_line,
    )
    nrows = len(rownums)
    if nrows < 2:
        raise _Fallback("fewer than 2 rows")
    history.append(f"{nrows} data rows from line {first + 1} parsed by pandas' C reader")
    return cols, rownums, nrows


def _read_rows_by_line(path, lay, history):
    """(columns of cells, file line of each row, row count), reading the data lines one by one.

    Comment lines among the data are skipped, their metadata appended to
    ``lay.pairs`` and ``lay.free``.
    """
    lines, d, n, dec, split, header_line = lay.lines, lay.delim, lay.n, lay.dec, lay.split, lay.header_line
    pairs, free = lay.pairs, lay.free
    rows, rownums, after = [], [], []
    plain = d != " " and not lay.trailing  # fast path: split, strip only lines with spaces
    for i in range(lay.first, len(lines)):
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
        history.append(
            f"{len(after)} comment line(s) among or after the data skipped (line {after[0]}"
            + (f" ... {after[-1]})" if len(after) > 1 else ")")
        )
    rownums = np.asarray(rownums)
    if len(rows) < 2:
        raise RecordingError(path, int(rownums[0]), "only one data row; expected at least 2 samples")
    cols = list(zip(*rows))
    return cols, rownums, len(rows)


def _time_base(
    path,
    t,
    tname,
    channels,
    nrows,
    rownums,
    header_line,
    sample_rate,
    rate_meta,
    resample,
    gap_factor,
    repair_time,
    history,
    extra_attrs,
):
    """(time [s], sample rate [Hz], segment or None): from the time column, else from the sample rate.

    Checks order (repairing it with ``repair_time``), splits segments at gaps,
    measures jitter and resamples when asked; the channels are cut and
    resampled with the time.
    """
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
            history.append(
                f"no time column; time = sample index / {fs:g} Hz (header line {rate_meta[1]}, '{rate_meta[2]}')"
            )
        else:
            raise RecordingError(
                path,
                header_line,
                "no time column and no sample rate in the header; "
                f"expected a time column ({spell('time_column')}) or a sample rate ({spell('sample_rate')})",
            )
        t = np.arange(nrows) / fs
        jitter = 0.0
    else:
        keep, notes, t = check_order(t, rownums, path=path, column=tname, repair=repair_time)
        history += notes
        if not _every_row(keep, t.size):  # repaired, or phyphox's repeated first stamp
            t = t[keep]
            for ch in channels:
                ch.values = ch.values[keep]
        del keep
        if t.size < 2:
            raise RecordingError(
                path, int(rownums[0]), "only one sample left after repairing time; expected at least 2"
            )
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
            history.append(
                f"{diag.n_segments} segments split at gaps > {gap_factor:g} sample periods "
                f"(gaps {diag.gaps_s.min():.6g} to {diag.gaps_s.max():.6g} s); kept as segments, "
                "not bridged"
            )
            segment = diag.segment
        _held_samples(t, channels, measured, history, extra_attrs)
        _sparse_channels(t, channels, history)
        policy = "resampled below" if resample == "linear" else "kept as is"
        history.append(f"jitter rms {_pct(diag.jitter_rms)} % of the period (max {_pct(diag.jitter_max)} %), {policy}")
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
    return t, fs, segment


def _every_row(keep, n) -> bool:
    """Whether ``keep`` is 0, 1 ... n - 1 (compared in blocks: no record-long temporaries)."""
    block = 1 << 20
    return keep.size == n and all(
        np.array_equal(keep[i : i + block], np.arange(i, min(i + block, n))) for i in range(0, n, block)
    )


def _held_samples(t, channels, row_rate, history, extra_attrs):
    """Mark channels whose values are held between updates (multi-sensor phone exports) with their true rate."""
    rates, steps = {}, {}
    for ch in channels:
        q = quantum(ch.values)
        if q is not None:
            ch.attrs["quantum"] = q
            steps[ch.name] = q
        r = held_update_rate(t, ch.values)
        if r is not None:
            ch.attrs["update_rate_hz"] = r
            ch.attrs["nyquist_hz"] = r / 2
            rates[ch.name] = r
    if steps:
        history.append(
            "quantised: "
            + ", ".join(f"{k} in steps of {v:.4g}" for k, v in steps.items())
            + " (repeated values come from the resolution, not held between updates; attr quantum)"
        )
    if rates:
        lo = min(rates.values())
        every = len(rates) == len(channels)
        history.append(
            f"held samples: rows come at {row_rate:.4g} Hz but the values of "
            + ", ".join(f"{k} change {v:.3g}" for k, v in rates.items())
            + f" times a second (repeated between updates); true update rate {lo:.3g} Hz, so nothing "
            f"above its Nyquist frequency {lo / 2:.3g} Hz is in "
            + ("the data" if every else "those channels (attrs update_rate_hz, nyquist_hz)")
        )
        if every:
            extra_attrs["update_rate_hz"] = float(lo)
            extra_attrs["nyquist_hz"] = float(lo / 2)


def _sparse_channels(t, channels, history):
    """Mark channels that hold a value only in some rows (a row whenever any sensor updates): their own samples.

    The cells a sensor left empty stay NaN: each such channel's samples are its finite values at their
    own times (:func:`vibkit.io.channels.channel_series`), never filled in; attrs ``sparse``,
    ``own_samples`` and ``own_rate_hz``.
    """
    notes = []
    filled = None  # how many channels hold a value in each row: counted only when a channel may be sparse
    for ch in channels:
        ok = np.isfinite(ch.values)
        n = int(ok.sum())
        if n < 2 or n > 0.9 * ok.size:
            continue
        if filled is None:
            filled = np.zeros(t.size, dtype=int)
            for other in channels:
                filled += np.isfinite(other.values)
        # at least a tenth of the rows empty, and those rows hold another sensor's value
        if np.all(filled[~ok] > 0):
            tt = t[ok]
            ch.attrs.update({"sparse": 1, "own_samples": n, "own_rate_hz": float((n - 1) / (tt[-1] - tt[0]))})
            notes.append(f"{ch.name} {n} samples ({ch.attrs['own_rate_hz']:.4g} Hz)")
    if notes:
        history.append(
            "sparse columns (a row whenever any sensor updates): "
            + ", ".join(notes)
            + "; each keeps its own samples at their own times, NaN between them (attr sparse)"
        )
