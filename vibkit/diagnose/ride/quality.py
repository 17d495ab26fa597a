"""Ride quality of a step-riding accelerometer, as escalator ride-quality meters report it.

One result type, :class:`RideQuality`, from three entry points that share one path
(:func:`ride_quality`, arrays in):

* :func:`ride_quality_from_recording`: a recording (any file :func:`vibkit.read_recording` reads)
  with x, y, z step acceleration channels (x along the travel, y lateral, z vertical);
* :func:`ride_quality_from_simulation`: a simulation Dataset with the acceleration of a step
  roller (``roller_acceleration``: x horizontal, z vertical, as a sensor on the step tread sees them,
  gravity added) or only ``accel_step`` (along the guide tangent);
* :func:`vibkit.diagnose.ride.simulation.simulate_ride`: a scene (TOML) simulated with the step roller's
  motion added to its outputs.

For each axis: the ISO 2631-1 weighted signal (Wd for x and y, Wk for z, as ISO 18738 takes them) and
its max peak-to-peak, A95, r.m.s. and peak over the ride segment; and the same on the 10 Hz
low-passed (unweighted) signal.  Definitions: :mod:`vibkit.signal.ride`,
:mod:`vibkit.signal.weighting`.
"""

from __future__ import annotations

import dataclasses
import functools
import os
import re

import numpy as np

from ...io import read_recording, source_name
from ...runtime.constants import STANDARD_GRAVITY
from ...signal.bursts import uniform_bursts
from ...signal.ride import (
    PeakToPeak,
    RideSegment,
    detect_ride_segment,
    incline_from_vertical_speed,
    level_run_from_velocity,
    level_walk_segment,
    lowpass_10hz,
    peak_to_peak,
)
from ...signal.weighting import WEIGHTINGS, frequency_weighting, get_weighting
from ..rides import ride_in_walk
from ..segment import parse_segment, segment_of_recording
from .result import AxisRide, RideQuality

__all__ = [
    "AxisRide",
    "RideQuality",
    "DEFAULT_WEIGHTINGS",
    "ride_quality",
    "ride_quality_from_recording",
    "parse_weightings",
    "ride_quality_from_simulation",
    "parse_channels",
    "parse_segment",
]

#: ISO 2631-1 / ISO 18738: horizontal axes Wd, vertical Wk (an axis along the guide tangent: Wd)
DEFAULT_WEIGHTINGS = {"x": "Wd", "y": "Wd", "z": "Wk", "tangential": "Wd"}
#: a simulated roller's acceleration plus this is what an accelerometer on it reads (the conversion
#: constant of g units, not the model's gravity of 9.81 m/s^2) [m/s^2]
G = STANDARD_GRAVITY
#: weighted signal discarded at the start of a record while the 0.4 Hz high-pass settles [s]
SETTLE_S = 2.0


def parse_channels(text) -> dict:
    """``"ax,ay,az"`` (x, y, z in order; ``-`` skips one) or ``"z=acc,x=ax"`` -> {axis: channel}."""
    out = {}
    items = [s.strip() for s in str(text).split(",")]
    if any("=" in s for s in items):
        for s in items:
            if "=" not in s:
                raise ValueError(f"channels {text!r}: mix of AXIS=NAME and plain names; use one form")
            k, v = (p.strip() for p in s.split("=", 1))
            if k.lower() not in ("x", "y", "z") or not v:
                raise ValueError(f"channels {text!r}: {s!r} must be x=NAME, y=NAME or z=NAME")
            out[k.lower()] = v
        return out
    if not 1 <= len(items) <= 3:
        raise ValueError(f"channels {text!r}: expected up to three names for x,y,z (use - to skip one)")
    for k, v in zip("xyz", items):
        if v and v != "-":
            out[k] = v
    if not out:
        raise ValueError(f"channels {text!r}: no channel named")
    return out


def parse_weightings(text) -> dict | None:
    """``--weighting`` text -> {axis: weighting name}, one to one, or None for the defaults.

    One name weights every axis (``Wk``); three names weight x, y, z in that order (``Wd,Wd,Wk``);
    ``AXIS=NAME`` pairs name their axes (``x=Wd,z=Wk``; x, y, z or tangential, each at most once).
    Any other count, a repeated axis, a mix of the forms or an unknown name is a ValueError naming
    the text.
    """
    if text is None or not str(text).strip():
        return None
    items = [s.strip() for s in str(text).split(",")]
    if not all(items):
        raise ValueError(f"--weighting {text!r}: an empty entry (expected Wk, Wd,Wd,Wk or x=Wd,y=Wd,z=Wk)")

    def name(v):
        try:
            return get_weighting(v).name
        except ValueError:
            raise ValueError(
                f"--weighting {text!r}: unknown weighting {v!r} (ISO 2631-1: {', '.join(WEIGHTINGS)})"
            ) from None

    pairs = ["=" in s for s in items]
    if any(pairs) and not all(pairs):
        raise ValueError(f"--weighting {text!r}: mix of AXIS=NAME and plain names; use one form")
    if all(pairs):
        out = {}
        for s in items:
            k, v = (p.strip() for p in s.split("=", 1))
            k = k.lower()
            if k not in DEFAULT_WEIGHTINGS:
                raise ValueError(f"--weighting {text!r}: axis {k!r} must be x, y, z or tangential")
            if k in out:
                raise ValueError(f"--weighting {text!r}: axis {k} is given twice")
            out[k] = name(v)
        return out
    if len(items) == 1:
        return {k: name(items[0]) for k in DEFAULT_WEIGHTINGS}
    if len(items) != 3:
        raise ValueError(
            f"--weighting {text!r}: {len(items)} weightings for the three axes x, y, z; give one for "
            f"every axis, three in the order x,y,z, or AXIS=NAME pairs"
        )
    return dict(zip(("x", "y", "z"), (name(v) for v in items)))


def _in_vibkit_words(exc, source) -> str:
    """An analysis error as one line that names ``source`` (once), scipy's filter wording replaced."""
    text = " ".join(str(exc).split()) or type(exc).__name__
    if "Wn" in text or "critical frequenc" in text:
        text = (
            "the sample rate is too low for the ISO 2631-1 weighting filters (they reach 100 Hz; record at "
            "250 Hz or more)"
        )
    if text.startswith("Parameter "):
        text = text[len("Parameter ") :]
    if source and str(source) not in text:
        text = f"{source}: {text}"
    return text


def _naming(source_of):
    """Decorator: ValueErrors (and scipy's) of a ride function re-raised in one line naming the file."""

    def wrap(func):
        @functools.wraps(func)
        def inner(*args, **kwargs):
            try:
                return func(*args, **kwargs)
            except ValueError as exc:
                src = source_of(*args, **kwargs)
                text = _in_vibkit_words(exc, src)
                if text == str(exc):
                    raise
                raise ValueError(text) from None

        return inner

    return wrap


def _recording_source(recording, *args, **kwargs):
    if isinstance(recording, (str, os.PathLike)):
        return source_name(recording)
    return getattr(recording, "attrs", {}).get("source_file", "")


#: fewest peak-to-peak values whose maximum and A95 a ride page states without a note (one every half-cycle of
#: the ride's vibration: a few seconds of it)
MIN_PK_PK_VALUES = 20


def _metrics(x, fs, i0, i1, notes, label):
    """Peak-to-peak summary over the segment; NaN (with a note) for a signal without two half-cycles."""
    try:
        pp = peak_to_peak(x[i0:i1], fs)
    except ValueError:
        notes.append(f"{label}: fewer than two complete half-cycles in the segment (a constant channel?): no values")
        nan = float("nan")
        return PeakToPeak(
            max=nan, a95=nan, rms=float(np.sqrt(np.mean(x[i0:i1] ** 2))), peak=nan, n_values=0, time_of_max_s=nan
        )
    if pp.n_values < MIN_PK_PK_VALUES:
        notes.append(
            f"{label}: only {pp.n_values} peak-to-peak values in the segment: its maximum and A95 are not a ride's "
            f"statistics (a ride gives hundreds; {MIN_PK_PK_VALUES} at least to read them)"
        )
    return pp


def ride_quality(
    signals: dict,
    fs,
    *,
    segment=None,
    weightings=None,
    source="",
    kind="recording",
    channel_names=None,
    speed=None,
    detect=None,
    notes=None,
) -> RideQuality:
    """Ride quality from acceleration arrays.

    Parameters
    ----------
    signals : dict
        Axis name (``"x"``, ``"y"``, ``"z"``, ``"tangential"``) -> acceleration samples. [m/s^2]
    fs : float
        Sample rate. [Hz]
    segment : (float, float) or RideSegment, optional
        Ride segment [s]; default: found by :func:`vibkit.signal.ride.detect_ride_segment` from the
        ``z`` (vertical speed) and ``x``/``tangential`` (gravity component) signals.
    weightings : dict, optional
        Axis -> weighting name (default :data:`DEFAULT_WEIGHTINGS`).
    source, kind : str
    channel_names : dict, optional
        Axis -> channel name (for the report).
    speed : array_like or float, optional
        Speed channel (or a number) [m/s]: its mean over the segment is reported.
    detect : callable, optional
        ``detect(fs) -> RideSegment`` overriding the default detection.
    notes : list of str, optional

    Returns
    -------
    RideQuality

    Raises
    ------
    ValueError
        No signal, unequal lengths, a segment outside the record or too short, no incline found.
    """
    if not signals:
        raise ValueError("ride_quality needs at least one acceleration axis")
    w = dict(DEFAULT_WEIGHTINGS)
    w.update(weightings or {})
    notes = list(notes or [])
    arrs = {k: np.asarray(v, dtype=float) for k, v in signals.items()}
    n = {a.size for a in arrs.values()}
    if len(n) != 1:
        raise ValueError(f"acceleration axes have different lengths {sorted(n)}")
    n = n.pop()
    dur = n / fs
    if segment is None:
        if detect is not None:
            seg = detect(fs)
        else:
            seg = detect_ride_segment(fs, vertical=arrs.get("z"), along=arrs.get("x", arrs.get("tangential")))
    elif isinstance(segment, RideSegment):
        seg = segment
    else:
        a, b = segment
        if not (0 <= a < b):
            raise ValueError(f"segment {a:g}:{b:g} s: expected 0 <= START < END")
        if a >= dur:
            raise ValueError(f"segment {a:g}:{b:g} s starts after the end of the record ({dur:.4g} s)")
        if b > dur * (1 + 1e-9) + 1 / fs:
            notes.append(f"segment end {b:g} s is past the end of the record; cut to {dur:.4g} s")
            b = dur
        seg = RideSegment(start_s=float(a), end_s=float(b), method="given")
    i0, i1 = int(round(seg.start_s * fs)), int(round(seg.end_s * fs))
    if seg.start_s < SETTLE_S:
        notes.append(
            f"the segment starts {seg.start_s:.3g} s into the record: the weighting's 0.4 Hz high-pass "
            f"is still settling there ("
            + (
                f"the simulated step reaches the incline within {SETTLE_S:g} s of the start: give a --segment "
                "that starts later, or place the step lower on its loop (the scene's [run] start)"
                if kind == "simulation"
                else f"record at least {SETTLE_S:g} s before the ride"
            )
            + ")"
        )
    if i1 - i0 < max(8, int(fs / 2)):
        raise ValueError(f"ride segment {seg.start_s:.4g}-{seg.end_s:.4g} s is too short (need at least 0.5 s)")
    axes = []
    weighted = {}
    for ax, x in arrs.items():
        name = w.get(ax, "Wd")
        wt = get_weighting(name).name
        x0 = x - np.mean(x[: max(1, min(n, int(fs)))])  # start the filters near rest (gravity off)
        y = frequency_weighting(x0, fs, wt)
        lp = lowpass_10hz(x0, fs)
        weighted[ax] = y
        axes.append(
            AxisRide(
                axis=ax,
                channel=(channel_names or {}).get(ax, ax),
                weighting=wt,
                weighted=_metrics(y, fs, i0, i1, notes, f"axis {ax} weighted"),
                lowpass=_metrics(lp, fs, i0, i1, notes, f"axis {ax} 10 Hz"),
            )
        )
    sp = None
    if speed is not None:
        s = np.asarray(speed, dtype=float)
        sp = float(s) if s.ndim == 0 else float(np.nanmean(np.abs(s[i0:i1])))
    return RideQuality(
        source=str(source),
        kind=kind,
        fs=float(fs),
        segment=seg,
        axes=tuple(axes),
        speed_m_s=sp,
        time=np.arange(n) / fs,
        weighted=weighted,
        notes=notes,
    )


_AXIS_RE = re.compile(r"([xyz])$")


def _auto_channels(rec, names):
    found = {}
    for nm in names:
        m = _AXIS_RE.search(nm.lower())
        if m:
            found.setdefault(m.group(1), []).append(nm)
    if found and all(len(v) == 1 for v in found.values()):
        return {k: v[0] for k, v in sorted(found.items())}
    # a phone's folder: acc_x and gyro_x both end in x; ride quality is the accelerometer's
    acc = {k: [nm for nm in v if rec[nm].attrs.get("quantity") == "acceleration"] for k, v in found.items()}
    if acc and all(len(v) == 1 for v in acc.values()):
        return {k: v[0] for k, v in sorted(acc.items())}
    raise ValueError(
        f"cannot tell the x, y, z channels of {rec.attrs.get('source_file', 'the recording')!r} from "
        f"their names ({', '.join(names)}); say which with --channels x,y,z "
        f"(e.g. --channels {names[0]},-,- or --channels z={names[0]})"
    )


@_naming(_recording_source)
def ride_quality_from_recording(
    recording,
    *,
    channels=None,
    segment=None,
    weightings=None,
    sample_rate=None,
    speed_channel=None,
    read_options=None,
    level_walk=False,
) -> RideQuality:
    """Ride quality of a recording of a step-riding accelerometer.

    Parameters
    ----------
    recording : str, os.PathLike or xarray.Dataset
        A file :func:`vibkit.read_recording` reads, or its result.  A vibkit simulation result
        (``vibkit simulate -o result.nc``) goes to :func:`ride_quality_from_simulation` unless
        ``channels`` are given.
    channels : dict or str, optional
        Axis -> channel (``{"x": "ax", "z": "az"}``) or the ``--channels`` text (:func:`parse_channels`);
        default: channels whose names end in x, y, z.
    segment : (float, float), optional
        Ride segment [s] in the file's own time (its time column's), inside the recording; default: detected.
    weightings : dict, optional
        Axis -> weighting (default x, y: Wd; z: Wk).
    sample_rate : float, optional
        For files without a time column. [Hz]
    speed_channel : str, optional
        A speed channel [m/s] (default: a channel in m/s named like ``speed``).
    read_options : dict, optional
        More :func:`vibkit.read_recording` arguments (``time_unit``, ``units``, ``repair_time`` ...).
    level_walk : bool
        The sensor rode a level moving walk (no incline to find): the whole record is the ride, unless ``segment``.

    Returns
    -------
    RideQuality

    Raises
    ------
    ValueError
        A channel that is not in the recording or not an acceleration in m/s^2; a recording in bursts
        whose longest burst is too short; the errors of :func:`ride_quality`.
    """
    opts = dict(read_options or {})
    if sample_rate is not None:
        opts["sample_rate"] = sample_rate
    rec = recording if not isinstance(recording, (str, os.PathLike)) else read_recording(recording, **opts)
    src = _recording_source(recording)  # a path as named, else the dataset's source_file (rec is the dataset)
    if (
        channels is None
        and rec.attrs.get("analysis") in ("forward", "inverse")
        and ("roller_acceleration" in rec or "accel_step" in rec)
    ):
        # a vibkit result file: the simulation path (its step roller, or accel_step)
        return ride_quality_from_simulation(rec, segment=segment, weightings=weightings, source=src)
    # a segment given in the file's own time lies inside the recording (never cut to fit), checked first
    given = None if segment is None or isinstance(segment, RideSegment) else segment_of_recording(rec, segment)
    names = [str(v) for v in rec.data_vars if v != "segment" and rec[v].dims == ("time",)]
    if not names:
        raise ValueError(f"{src}: the recording has no channel along time")
    chans = parse_channels(channels) if isinstance(channels, str) else dict(channels or {})
    if not chans:
        chans = _auto_channels(rec, names)
    lower = {n.lower(): n for n in names}
    for ax, ch in list(chans.items()):
        if ch.lower() not in lower:
            raise ValueError(
                f"{src}: channel {ch!r} (axis {ax}) is not in the recording (channels: {', '.join(names)})"
            )
        ch = chans[ax] = lower[ch.lower()]
        units = str(rec[ch].attrs.get("units", ""))
        if units not in ("m/s^2", "m s-2", "m/s2"):
            raise ValueError(
                f"{src}: channel {ch!r} is in {units or 'unknown units'!r}, not an acceleration in m/s^2 "
                "(the reader converts g; give units to the reader for raw counts)"
            )
    notes = []
    bursts = {ax: uniform_bursts(rec, ch) for ax, ch in chans.items()}
    first = next(iter(bursts.values()))
    if not first:
        raise ValueError(f"{src}: no burst of uniformly sampled data long enough to assess")
    k = int(np.argmax([b.x.size for b in first]))
    if len(first) > 1:
        notes.append(
            f"the recording has {len(first)} bursts; the longest ({first[k].x.size / first[k].fs:.3g} s "
            f"from t = {first[k].t0:.4g} s) is assessed, times from its start"
        )
    fs = first[k].fs
    if given is not None:  # in the file's own time: from the assessed burst's start
        segment = (given[0] - float(first[k].t0), given[1] - float(first[k].t0))
    sig = {ax: b[k].x for ax, b in bursts.items()}
    if any(b[k].resampled for b in bursts.values()):
        notes.append("irregular time stamps: resampled linearly to a uniform grid (weighting above ~fs/4 is softened)")
    speed = None
    sp_names = (
        [speed_channel]
        if speed_channel
        else [n for n in names if "speed" in n.lower() and str(rec[n].attrs.get("units", "")) == "m/s"]
    )
    if sp_names and sp_names[0]:
        if sp_names[0].lower() not in lower:
            raise ValueError(f"{src}: speed channel {speed_channel!r} is not in the recording")
        sb = uniform_bursts(rec, lower[sp_names[0].lower()])
        speed = sb[k].x if len(sb) > k and sb[k].x.size == sig[next(iter(sig))].size else None
    if speed is None and float(rec.attrs.get("chain_speed_m_s", 0) or 0) > 0:
        speed = float(rec.attrs["chain_speed_m_s"])
    if segment is None and level_walk:
        segment = level_walk_segment(sig[next(iter(sig))].size / fs)
    if segment is None:
        segment = ride_in_walk(rec, [chans.get(a) for a in "xyz"], first[k].t0, notes, src)
    return ride_quality(
        sig,
        fs,
        segment=segment,
        weightings=weightings,
        source=src,
        kind="recording",
        channel_names=chans,
        speed=speed,
        notes=notes,
    )


def _step_roller(ds):
    step = ds.attrs.get("step_accelerometer")
    if "roller" not in ds.coords or "roller_acceleration" not in ds:
        return None
    rollers = [int(r) for r in ds["roller"].values]
    k = int(ds.attrs.get("links_per_step", 3))  # the middle roller of step s is k (s - 1) + 2 (1-based)
    if step is not None and k * (int(step) - 1) + 2 in rollers:
        return k * (int(step) - 1) + 2
    return rollers[0]


#: a simulated run from rest is a ride once its step runs at this share of the chain's (counted) speed
START_UP_SHARE = 0.98


def _start_up(speed, chain_speed):
    """The first sample at which a step that starts at rest (below half the chain's speed) reaches
    :data:`START_UP_SHARE` of ``chain_speed``; 0 when it does not start at rest or never gets there."""
    if not chain_speed > 0 or speed.size == 0 or speed[0] >= 0.5 * chain_speed:
        return 0
    up = np.flatnonzero(speed >= START_UP_SHARE * chain_speed)
    return int(up[0]) if up.size else 0


def ride_quality_from_simulation(ds, *, segment=None, weightings=None, source=None) -> RideQuality:
    """Ride quality of a simulated step: the same path as a recording.

    Parameters
    ----------
    ds : xarray.Dataset
        A forward or inverse result (``vibkit.simulate``) with ``roller_acceleration`` of a roller of
        the step (preferred: axes x horizontal and z vertical, gravity added as an accelerometer on
        the step tread measures it; the segment from the roller's vertical speed when
        ``roller_velocity`` is there) or with ``accel_step`` (one axis along the guide tangent; the
        whole record is the segment unless given).
    segment : (float, float), optional
        [s] from the first output time.
    weightings : dict, optional
    source : str, optional

    Returns
    -------
    RideQuality

    Raises
    ------
    ValueError
        The Dataset has neither output, is not along time, or is not uniformly sampled.
    """
    if "time" not in ds.dims:
        raise ValueError("ride quality needs a result along time (an inverse or forward analysis)")
    t = np.asarray(ds["time"].values, dtype=float)
    dt = np.diff(t)
    if t.size < 16 or not np.allclose(dt, dt.mean(), rtol=1e-6):
        raise ValueError("the simulation's output times are not uniformly spaced (or too few)")
    fs = 1.0 / float(dt.mean())
    src = source or str(ds.attrs.get("scene_source", ds.attrs.get("scene_name", "simulation")))
    roller = _step_roller(ds)
    notes = []
    detect = None
    speed = ds.attrs.get("chain_speed_m_s") or None
    if roller is not None:
        acc = ds["roller_acceleration"].sel(roller=roller)
        sig = {"x": acc.sel(axis="x").values, "z": acc.sel(axis="z").values + G}
        names = {"x": f"roller_acceleration[{roller}, x]", "z": f"roller_acceleration[{roller}, z] + g"}
        notes.append(
            f"simulated step: roller {roller} (middle roller of step {ds.attrs.get('step_accelerometer', '?')}); "
            "no lateral axis in a planar model"
        )
        if "roller_velocity" in ds and segment is None:
            vz = ds["roller_velocity"].sel(roller=roller, axis="z").values
            vel = ds["roller_velocity"].sel(roller=roller).values
            speed = np.hypot(vel[:, 0], vel[:, 1])
            cut = _start_up(speed, float(ds.attrs.get("chain_speed_m_s") or 0.0))
            down = float(ds.attrs.get("speed_set_point_m_s") or 0.0) < 0.0  # the steps travel down the incline

            def detect(fs_):
                if ds.attrs.get("incline_deg") == 0.0:  # a level moving walk: the ride is its top run, no climb
                    return level_run_from_velocity(vel[cut:, 0], vz[cut:], fs_, backward=down, t0=cut / fs_)
                if not cut:
                    return incline_from_vertical_speed(vz, fs_, down=down)
                # a run from rest: the drive's start-up is no ride; the incline is looked for after it
                seg = incline_from_vertical_speed(vz[cut:], fs_, down=down)
                note = seg.note or ""
                if seg.start_s == 0.0:  # on the incline when the start-up ends: a longer run does not help
                    note = note.replace(
                        "the incline reaches an end of the simulated time (simulate longer: --duration)",
                        "the step is on the incline when the start-up ends (start it lower on its loop: the scene's "
                        "[run] start)",
                    )
                return dataclasses.replace(
                    seg,
                    start_s=seg.start_s + cut / fs_,
                    end_s=seg.end_s + cut / fs_,
                    note=(note + "; " if note else "")
                    + f"the start-up from rest left out (the step at {START_UP_SHARE:.0%} of the chain's speed at "
                    f"{cut / fs_:.1f} s)",
                )

    elif "accel_step" in ds:
        sig = {"tangential": ds["accel_step"].values}
        names = {"tangential": "accel_step"}
        notes.append("only accel_step (along the guide tangent, no gravity): one axis; add roller outputs for x and z")
        if segment is None:

            def detect(fs_):  # not "given": nobody gave it
                return RideSegment(
                    start_s=0.0,
                    end_s=float(t[-1] - t[0]),
                    method="whole simulated time",
                    note="no incline detection without the step's vertical motion",
                )
    else:
        raise ValueError(
            "the simulation has neither 'roller_acceleration' nor 'accel_step' among its outputs "
            "(use vibkit.diagnose.ride.simulate_ride, which adds them)"
        )
    return ride_quality(
        sig,
        fs,
        segment=segment,
        weightings=weightings,
        source=src,
        kind="simulation",
        channel_names=names,
        speed=speed,
        detect=detect,
        notes=notes,
    )
