"""Waveform files that obspy reads (miniSEED, SAC, GSE2, SEG-Y ...).

One data variable per trace id (``NET.STA.LOC.CHA`` -> ``NET_STA_LOC_CHA``).
Several traces with the same id (a file with gaps) become segments of one
channel.  Where the format states a calibration to physical units, it is applied
and said in the history: K-NET ASCII (``Scale Factor 2000(gal)/8388608``: counts
-> gal -> m/s^2), Kinemetrics EVT (full scale and sensitivity: counts -> m/s^2),
SAC with ``idep`` volts, nm, nm/s or nm/s^2.  Other waveform files carry no physical
units: values stay in counts unless the caller gives a unit (``units="m/s^2"``,
``units={"HNZ": "g/2048"}``, applied to the raw counts); the decision is recorded.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..runtime.reader_options import spell
from .errors import RecordingError
from .recording import Channel, build_recording, metadata_attrs, safe_name
from .text.units import parse_unit
from .timebase import check_order, diagnose, resample_linear

__all__ = ["read_seismic"]


def _load(path):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:  # obspy's import warns about importlib.metadata on some Pythons; not our user's concern
            import obspy
        except ImportError:
            raise RecordingError(
                path,
                None,
                "binary content read as a waveform file (miniSEED, SAC ...), which needs obspy, not installed: "
                "pip install 'vibkit[seismic]'",
            ) from None
        caught.clear()
        try:
            st = obspy.read(str(path))
        except Exception as exc:  # obspy raises TypeError/ValueError/... for what it cannot read
            detail = "" if "Unknown format" in str(exc) else f" ({type(exc).__name__}: {exc})"
            raise RecordingError(
                path,
                None,
                f"binary content that is neither text, netCDF/HDF5 nor a waveform format obspy reads{detail}",
            ) from None
    return st, [f"obspy warning: {w.message}" for w in caught]


#: SAC ``idep`` codes with a physical unit: code -> (unit as SAC says it, factor to SI, SI unit, quantity)
_SAC_IDEP = {
    6: ("nm", 1e-9, "m", "displacement"),
    7: ("nm/s", 1e-9, "m/s", "velocity"),
    8: ("nm/s^2", 1e-9, "m/s^2", "acceleration"),
    50: ("V", 1.0, "V", "other"),
}


def _calibration(tr):
    """(factor counts -> SI, SI unit, quantity, what) when the format states a physical calibration, else None."""
    s = tr.stats
    fmt = str(s.get("_format", "")).upper()
    calib = float(s.get("calib", 1.0) or 1.0)
    if fmt == "KNET" and calib != 1.0:
        return (
            calib,
            "m/s^2",
            "acceleration",
            (f"K-NET header 'Scale Factor' (counts -> gal), gal -> m/s^2: x {calib:.9g}"),
        )
    if fmt == "KINEMETRICS_EVT" and calib != 1.0:
        return (
            calib,
            "m/s^2",
            "acceleration",
            (
                "Kinemetrics EVT header full scale and sensitivity "
                f"(counts -> m/s^2, as obspy reads them): x {calib:.9g}"
            ),
        )
    if fmt == "SAC":
        idep = int(s.get("sac", {}).get("idep", 5) or 5)
        if idep in _SAC_IDEP:
            unit, f, si, q = _SAC_IDEP[idep]
            return f * calib, si, q, f"SAC header idep={idep} ({unit})" + ("" if f == 1 else f" -> {si}: x {f:g}")
    return None


def read_seismic(
    path, data: bytes, *, channel=None, units=None, sample_rate=None, resample=None, gap_factor=5.0, repair_time=False
):
    """Read a waveform file with obspy into a recording Dataset.

    Parameters are those of :func:`vibkit.io.read_recording`.

    Returns
    -------
    xarray.Dataset

    Raises
    ------
    RecordingError
        Not readable by obspy, no such channel, or channels on different time bases.
    """
    st, history = _load(path)
    if len(st) == 0:
        raise RecordingError(path, None, "holds no traces")
    ids = list(dict.fromkeys(tr.id for tr in st))
    names = {i: safe_name(i.replace(".", "_"), "trace") for i in ids}
    if channel is not None:
        wanted = [channel] if isinstance(channel, str) else list(channel)
        picked = []
        for w in wanted:
            hits = [i for i in ids if w in (i, names[i]) or i.split(".")[-1] == w]
            if not hits:
                raise RecordingError(path, None, f"no trace {w!r}; traces: " + ", ".join(repr(i) for i in ids))
            picked += hits
        ids = list(dict.fromkeys(picked))
    groups = {i: sorted((tr for tr in st if tr.id == i), key=lambda tr: tr.stats.starttime) for i in ids}
    t0 = min(g[0].stats.starttime for g in groups.values())
    rates = {i: float(g[0].stats.sampling_rate) for i, g in groups.items()}
    if len(set(rates.values())) > 1:
        raise RecordingError(
            path,
            None,
            "traces have different sampling rates ("
            + ", ".join(f"{i}: {r:g} Hz" for i, r in rates.items())
            + f"); read one with {spell('channel')}",
        )
    if isinstance(units, dict):
        unknown = [k for k in units if not any(k in (i, names[i], i.split(".")[-1]) for i in ids)]
        if unknown:
            raise ValueError(f"units: no trace {unknown[0]!r} in {path}; traces: " + ", ".join(ids))
    times, channels = None, []
    for i, g in groups.items():
        t = np.concatenate([tr.times() + float(tr.stats.starttime - t0) for tr in g])
        v = np.concatenate([np.asarray(tr.data, dtype=np.float64) for tr in g])
        if times is None:
            times = t
        elif t.shape != times.shape or not np.allclose(t, times, rtol=0, atol=0.01 / rates[i]):
            raise RecordingError(
                path,
                None,
                f"trace {i} does not share the time stamps of {ids[0]}; "
                f"read one trace at a time with {spell('channel')} (e.g. {spell('channel', i.split('.')[-1])})",
            )
        u_text = units if isinstance(units, str) else None
        if isinstance(units, dict):
            for k, u in units.items():
                if k in (i, names[i], i.split(".")[-1]):
                    u_text = u
        attrs = {"trace_id": i, "channel_code": i.split(".")[-1], "original_units": "counts"}
        cal = _calibration(g[0])
        if u_text is None and cal is not None:
            f, si, q, what = cal
            history.append(
                f"trace {i} calibrated by the format: {what}; pass {spell('units')} to read the raw counts "
                "with a scale of your own"
            )
            attrs["calibration"] = what
            ch = Channel(names[i], v * f, si, f"trace {i}", q, attrs)
        elif u_text is None:
            calib = float(g[0].stats.get("calib", 1.0) or 1.0)
            extra = "" if calib == 1.0 else f" (the header's calib {calib:.9g} has no stated unit; not applied)"
            history.append(
                f"trace {i}: a waveform file has no physical units; values kept in counts{extra}; "
                f"pass {spell('units')} to scale them (e.g. 'g/2048')"
            )
            ch = Channel(names[i], v, "counts", f"trace {i}", "other", attrs)
        else:
            unit = parse_unit(u_text)
            if unit is None:
                raise ValueError(
                    f"units for trace {i} of {path}: {u_text!r} is not a unit vibkit knows; expected e.g. "
                    "'m/s^2', 'g', 'm', 'counts' or a scaled one like 'g/2048'"
                )
            if unit.factor is None:
                history.append(f"trace {i} in {u_text} (given), kept in counts")
                ch = Channel(names[i], v, "counts", f"trace {i}", "other", attrs)
            else:
                history.append(f"trace {i} in {u_text} (given) -> {unit.si} (x {unit.factor:.9g})")
                attrs["original_units"] = u_text
                ch = Channel(names[i], v * unit.factor, unit.si, f"trace {i}", unit.quantity, attrs)
        channels.append(ch)
    keep, notes, times = check_order(times, None, path=path, column="trace times", repair=repair_time)
    history += notes
    times = times[keep]
    for ch in channels:
        ch.values = ch.values[keep]
    if times.size < 2:
        raise RecordingError(path, None, "holds only one sample; expected at least 2")
    diag = diagnose(times, gap_factor=gap_factor)
    fs = float(sample_rate) if sample_rate is not None else rates[ids[0]]
    history.append(f"sample rate {fs:g} Hz " + ("(sample_rate given)" if sample_rate is not None else "(trace header)"))
    segment = None
    if diag.n_segments > 1:
        history.append(
            f"{diag.n_segments} segments split at gaps > {gap_factor:g} sample periods; kept as segments, not bridged"
        )
        segment = diag.segment
    if resample == "linear":
        times, cols, seg = resample_linear(times, {c.name: c.values for c in channels}, diag.segment, fs)
        for ch in channels:
            ch.values = cols[ch.name]
        segment = seg if diag.n_segments > 1 else None
        history.append(f"resampled linearly to {fs:g} Hz, each segment on its own")
    first = groups[ids[0]][0].stats
    meta = metadata_attrs(
        [
            ("start_time", str(t0)),
            ("network", first.network),
            ("station", first.station),
            ("location", first.location),
            ("channel", first.channel),
            ("format", str(first.get("_format", ""))),
            ("segment_count", diag.n_segments),
            ("time_jitter_rms_percent", 100 * diag.jitter_rms),
        ]
    )
    return build_recording(
        time=times,
        channels=channels,
        segment=segment,
        path=path,
        data_bytes=data,
        reader="vibkit.io.seismic",
        sample_rate_hz=fs,
        history=history,
        metadata=meta,
    )
