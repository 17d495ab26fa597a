"""Recordings whose readers hold arrays already: channels, their units and a time base, made a recording.

The readers of binary engineering formats (MATLAB ``.mat``, plain HDF5, WAV, UFF dataset 58, TDMS)
find arrays, a sample rate or a time vector, and unit labels in what the format stores.  Two helpers
turn that into a recording following vibkit's data contract, with the same options as every reader:

* :func:`pick_arrays`: from named arrays (a ``.mat`` file's variables, an HDF5 file's datasets), the
  time base (a time vector ``t``/``time`` [s], a rate ``fs``/``sample_rate`` [Hz] or a period
  ``dt`` [s]) and the channels (every numeric vector or matrix as long as the time base; a matrix
  gives one channel per column, samples along the axis as long as the time base);
* :func:`assemble`: channel selection (``channel=``), units (the format's label, or ``units=``
  given by the caller, converted to SI), time order (``repair_time=``), segments at gaps
  (``gap_factor=``), ``sample_rate=`` and ``resample=``, provenance.

Nothing is guessed: a file without a time base, or with arrays of different lengths and no way to
tell which are channels, raises :class:`~vibkit.io.errors.RecordingError` naming the file, what was
found and what would read it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..runtime.reader_options import spell
from .errors import RecordingError
from .recording import Channel, build_recording, metadata_attrs, safe_name, unique_names
from .text.units import parse_unit
from .timebase import check_order, diagnose, resample_linear

__all__ = ["Column", "Named", "assemble", "pick_arrays", "select_columns", "RATE_NAMES", "PERIOD_NAMES", "TIME_NAMES"]

#: names (case-insensitive, the last part of a nested name) of a scalar sample rate [Hz]
RATE_NAMES = (
    "fs",
    "sample_rate",
    "samplerate",
    "sampling_rate",
    "sample_rate_hz",
    "sampling_frequency",
    "samplingfrequency",
    "sr",
    "rate",
    "fsamp",
)
#: names of a scalar sample period [s]
PERIOD_NAMES = ("dt", "ts", "sample_period", "sampling_period", "delta_t", "deltat", "sampling_interval")
#: names of a time vector [s]
TIME_NAMES = ("t", "time", "time_s", "times", "timestamp")
_UNIT_KEYS = ("units", "unit", "Units", "Unit", "UNITS")


@dataclass
class Column:
    """One channel as the format holds it.

    Attributes
    ----------
    name : str
        The name as found (``"acc(:,2)"``, ``"Group/Channel"``, ``"node 12 +Z"``).
    values : numpy.ndarray
        The samples, in ``unit``.
    unit : str or None
        The unit label the format states, or None.
    attrs : dict
        Extra attrs for the variable (strings and numbers).
    var_name : str or None
        The variable name to use (else made from ``name``).
    """

    name: str
    values: np.ndarray
    unit: str | None = None
    attrs: dict = field(default_factory=dict)
    var_name: str | None = None


@dataclass
class Named:
    """One array of a file that names its arrays (a ``.mat`` variable, an HDF5 dataset).

    ``values`` is numeric (any shape) or text (a ``str`` or a list of ``str``); ``units`` is the
    unit the file attaches to it (an HDF5 ``units`` attribute), or None.  ``rate`` is a sample rate
    the file attaches to it (an HDF5 ``sample_rate`` attribute) [Hz], or None.
    """

    name: str
    values: object
    units: object = None
    rate: float | None = None


def _last(name: str) -> str:
    return name.replace("/", ".").split(".")[-1].lower()


def _scalar(v):
    a = np.asarray(v)
    if a.dtype.kind in "iuf" and a.size == 1:
        return float(a.reshape(()))
    return None


def pick_arrays(path, arrays, *, what, rate=None, rate_source="", given_rate=None, channel=None):
    """The time base and the channels of named arrays.

    Parameters
    ----------
    path : str
        The file (for messages).
    arrays : list of Named
    what : str
        What the arrays are called in messages (``"variables"``, ``"datasets"``).
    rate : float, optional
        A sample rate the file states outside the arrays (an HDF5 root attribute). [Hz]
    rate_source : str
        Where ``rate`` comes from (for the history).
    given_rate : float, optional
        The ``sample_rate=`` the caller gave: the time base where the file states none, the rate
        where the file's rates disagree. [Hz]
    channel : str or list of str, optional
        The ``channel=`` the caller gave: only the arrays it names (``data`` or a column ``data[2]``,
        ``data_2``) are channels, so arrays of other lengths do not stand in the way.

    Returns
    -------
    columns : list of Column
    time : numpy.ndarray or None
        The time vector [s], or None when the rate gives the time base.
    rate : float or None
        The sample rate [Hz], or None when a time vector gives the time base.
    history : list of str
    """
    history = []
    texts = {a.name: a.values for a in arrays if isinstance(a.values, (str, list))}
    numeric = [a for a in arrays if not isinstance(a.values, (str, list)) and np.asarray(a.values).dtype.kind in "iufb"]
    rates, periods, times, data = [], [], [], []
    for a in numeric:
        low, s = _last(a.name), _scalar(a.values)
        if s is not None:
            if low in RATE_NAMES:
                rates.append((a.name, s))
            elif low in PERIOD_NAMES:
                periods.append((a.name, s))
            continue
        arr = np.asarray(a.values)
        if low in TIME_NAMES and arr.size >= 2 and max(arr.shape) == arr.size:
            times.append((a.name, arr.reshape(-1).astype(np.float64)))
            continue
        if arr.ndim > 2 and sum(d > 1 for d in arr.shape) > 2:
            history.append(
                f"{a.name}: {arr.ndim}-D array of shape {arr.shape} skipped (channels are vectors or matrices)"
            )
            continue
        data.append(a)
        if a.rate is not None:
            rates.append((f"attribute of {a.name}", float(a.rate)))
    if rate is not None:
        rates.append((rate_source, float(rate)))
    if channel is not None:
        wanted = [str(w).strip().lower() for w in ([channel] if isinstance(channel, str) else channel)]
        data = [a for a in data if any(_names_array(a.name, w) for w in wanted)] or data
    if len(times) > 1:
        raise RecordingError(
            path,
            None,
            f"several time vectors ({', '.join(n for n, _ in times)}); expected one, or read with {spell('channel')}",
        )
    time = times[0][1] if times else None
    fs = None
    if time is None:
        cands = [(n, v) for n, v in rates] + [(n, 1.0 / v) for n, v in periods if v > 0]
        values = {round(v, 9) for _, v in cands}
        if given_rate is not None and (not cands or len(values) > 1):
            cands, values = [("sample_rate given", float(given_rate))], {float(given_rate)}
        if not cands:
            raise RecordingError(
                path,
                None,
                f"no time base: expected a time vector ({'/'.join(TIME_NAMES[:2])}, seconds), a sample rate "
                f"({'/'.join(RATE_NAMES[:3])}, Hz) or a sample period (dt, seconds) among the {what} "
                f"({', '.join(a.name for a in arrays) or 'none'}); or give {spell('sample_rate')}",
            )
        if len(values) > 1:
            raise RecordingError(
                path,
                None,
                "sample rates that disagree: "
                + ", ".join(f"{n} = {v:g} Hz" for n, v in cands)
                + f"; give {spell('sample_rate')}",
            )
        name, fs = cands[0]
        if not (np.isfinite(fs) and fs > 0):
            raise RecordingError(path, None, f"sample rate {name} = {fs:g} Hz; expected a positive number")
        history.append(f"sample rate {fs:g} Hz from {name}")
    else:
        history.append(f"time from {times[0][0]} (seconds)")
    n = time.size if time is not None else None
    if n is None:
        lengths = {max(np.shape(a.values)) for a in data}
        if len(lengths) > 1:
            raise RecordingError(
                path,
                None,
                f"{what} of different lengths ("
                + ", ".join(f"{a.name}: {max(np.shape(a.values))}" for a in data)
                + f"); expected channels of one length: read those you want with {spell('channel')}",
            )
        n = lengths.pop() if lengths else 0
    columns = []
    for a in data:
        arr = np.asarray(a.values)
        if arr.ndim < 2:
            arr = arr.reshape(-1, 1)
        elif arr.ndim > 2:
            arr = arr.reshape([d for d in arr.shape if d > 1] or [1])
            arr = arr.reshape(-1, 1) if arr.ndim == 1 else arr
        if arr.shape[0] != n and arr.shape[1] == n:
            arr = arr.T
        if arr.shape[0] != n:
            history.append(f"{a.name}: shape {np.shape(a.values)} is not {n} samples long: skipped")
            continue
        units = a.units if a.units is not None else _unit_text(a.name, texts)
        for c in range(arr.shape[1]):
            u = units[c] if isinstance(units, list) and c < len(units) else (units if isinstance(units, str) else None)
            label = a.name if arr.shape[1] == 1 else f"{a.name}[{c + 1}]"
            vname = safe_name(a.name, "channel") + ("" if arr.shape[1] == 1 else f"_{c + 1}")
            columns.append(Column(label, arr[:, c].astype(np.float64), u, {"source_name": label}, vname))
    if not columns:
        raise RecordingError(
            path, None, f"no numeric vector or matrix of {n} samples among the {what}; expected the channels"
        )
    return columns, time, fs, history


def _names_array(name, wanted):
    """Whether ``wanted`` (lower case) names array ``name`` or one of its columns."""
    forms = (name.lower(), safe_name(name, "").lower())
    return any(wanted == f or wanted.startswith((f + "[", f + "_")) for f in forms if f)


def _unit_text(name, texts):
    """Units text for array ``name``: ``<name>_units``/``<name>_unit``, else ``units`` beside it (same struct)."""
    prefix = name.rsplit(".", 1)[0] + "." if "." in name else ""
    for key in (f"{name}_units", f"{name}_unit", *(prefix + k for k in _UNIT_KEYS)):
        if key in texts:
            v = texts[key]
            return [str(x).strip() for x in v] if isinstance(v, list) else str(v).strip()
    return None


def select_columns(path, columns, want):
    """The columns ``want`` names (``channel=``: a name or a list), matched case-insensitively; all if None."""
    if want is None:
        return columns
    wanted = [want] if isinstance(want, str) else list(want)
    out = []
    for w in wanted:
        wl = str(w).strip().lower()
        hit = [c for c in columns if wl in (c.name.lower(), (c.var_name or "").lower(), safe_name(c.name, "").lower())]
        if not hit:
            raise RecordingError(
                path, None, f"no channel {w!r} ({spell('channel')}); channels: " + ", ".join(c.name for c in columns)
            )
        out += [c for c in hit if c not in out]
    return out


def _convert(path, col, given, history):
    """(values, SI unit, quantity, attrs) of a column under its label or the ``units=`` given."""
    attrs = dict(col.attrs)
    text = given if given is not None else col.unit
    origin = "given" if given is not None else "in the file"
    if text is None or not str(text).strip() or str(text).strip().upper() == "NONE":
        history.append(f"channel '{col.name}': no unit in the file; kept as found (pass {spell('units')} to state it)")
        return col.values, "unknown", "other", attrs
    u = parse_unit(str(text))
    if u is None:
        if given is not None:
            raise ValueError(
                f"units for channel {col.name!r} of {path}: {text!r} is not a unit vibkit knows; expected e.g. "
                "'m/s^2', 'g', 'm', 'counts' or a scaled one like 'g/2048'"
            )
        history.append(f"channel '{col.name}': unit {text!r} ({origin}) kept as found")
        attrs["original_units"] = str(text)
        return col.values, str(text).strip(), "other", attrs
    attrs["original_units"] = str(text)
    if u.factor is None:
        history.append(f"channel '{col.name}' in {text} ({origin}), kept in counts")
        return col.values, "counts", "other", attrs
    note = f" -> {u.si} (x {u.factor:.9g})" if u.factor != 1 or u.si != str(text) else ""
    history.append(f"channel '{col.name}' in {text} ({origin}){note}")
    return col.values * u.factor, u.si, u.quantity, attrs


def assemble(path, data, *, reader, columns, options, history, time=None, rate=None, metadata=None):
    """A recording from columns and a time base (a time vector [s] or a sample rate [Hz]).

    ``options`` are :func:`vibkit.io.read_recording`'s reading options; this uses ``channel``,
    ``units``, ``sample_rate``, ``resample``, ``gap_factor`` and ``repair_time``.  ``metadata`` is a
    list of (key, value) pairs.
    """
    history = list(history)
    given_rate = options.get("sample_rate")
    if time is None and rate is None and given_rate is None:
        raise RecordingError(
            path, None, f"no time base in the file; expected a sample rate, or give {spell('sample_rate')}"
        )
    columns = select_columns(path, columns, options.get("channel"))
    units = options.get("units")
    if isinstance(units, dict):
        names = {k for c in columns for k in (c.name, c.var_name, safe_name(c.name, ""))}
        unknown = [k for k in units if k not in names]
        if unknown:
            raise ValueError(
                f"units: no channel {unknown[0]!r} in {path}; channels: " + ", ".join(c.name for c in columns)
            )
    n = columns[0].values.size
    if any(c.values.size != n for c in columns):
        raise RecordingError(
            path,
            None,
            "channels of different lengths ("
            + ", ".join(f"{c.name}: {c.values.size}" for c in columns)
            + f"); read them one at a time with {spell('channel')}",
        )
    if n < 2:
        raise RecordingError(path, None, f"holds {n} sample(s); expected at least 2")
    if time is None:
        fs0 = float(given_rate) if rate is None else float(rate)
        if rate is None:
            history.append(f"sample rate {fs0:g} Hz (sample_rate given)")
        t = np.arange(n) / fs0
    else:
        t = np.asarray(time, dtype=np.float64).reshape(-1)
        if t.size != n:
            raise RecordingError(path, None, f"time vector of {t.size} samples for channels of {n}; expected equal")
        bad = np.flatnonzero(~np.isfinite(t))
        if bad.size:
            raise RecordingError(path, None, f"time is not a finite number at sample {bad[0]}; expected seconds")
    channels, used = [], []
    for col in columns:
        given = None
        if isinstance(units, str):
            given = units
        elif isinstance(units, dict):
            for k, u in units.items():
                if k in (col.name, col.var_name, safe_name(col.name, "")):
                    given = u
        values, unit, q, attrs = _convert(path, col, given, history)
        used.append(col.var_name or safe_name(col.name, "channel"))
        channels.append((values, unit, q, attrs, col.name))
    names = unique_names(used)
    chans = [
        Channel(names[k], np.asarray(v, dtype=np.float64), u, ln, q, a) for k, (v, u, q, a, ln) in enumerate(channels)
    ]
    keep, notes, t = check_order(t, None, path=path, column="time", repair=bool(options.get("repair_time")))
    history += notes
    t = t[keep]
    for ch in chans:
        ch.values = ch.values[keep]
    diag = diagnose(t, gap_factor=options.get("gap_factor", 5.0))
    if given_rate is not None:
        fs = float(given_rate)
        if time is not None or rate is not None:
            history.append(f"nominal sample rate {fs:g} Hz (sample_rate given)")
    elif rate is not None:
        fs = float(rate)
    else:
        fs = 1.0 / diag.period_s
        history.append(f"sample rate {fs:.6g} Hz from the mean time step")
    segment = None
    if diag.n_segments > 1:
        history.append(
            f"{diag.n_segments} segments split at gaps > {options.get('gap_factor', 5.0):g} sample periods; "
            "kept as segments, not bridged"
        )
        segment = diag.segment
    if options.get("resample") == "linear":
        t, cols, seg = resample_linear(t, {c.name: c.values for c in chans}, diag.segment, fs)
        for ch in chans:
            ch.values = cols[ch.name]
        segment = seg if diag.n_segments > 1 else None
        history.append(f"resampled linearly to {fs:g} Hz, each segment on its own")
    meta = metadata_attrs([*(metadata or []), ("segment_count", diag.n_segments)])
    return build_recording(
        time=t,
        channels=chans,
        segment=segment,
        path=path,
        data_bytes=data,
        reader=reader,
        sample_rate_hz=fs,
        history=history,
        metadata=meta,
    )
