"""Escalator rides in a phone recording of a walk: where the person stood on a moving chain, and what the
ride says of it.

A ride leaves three marks in a phone's record: the walking band of ``|a|`` falls to the standing level
(:mod:`vibkit.signal.stillness`); a steady narrow line, the chain's link pass, appears on the
accelerometer's and gyroscope's axes (:func:`vibkit.signal.steadyline.steady_line`); the barometer climbs
or falls steadily (0.2-0.4 m/s of vertical speed on an escalator).  :func:`find_rides` looks for still
spans of at least ``min_ride_s``, trims ``trim_s`` at each end (stepping on and off), and calls a span a
ride only where the line stands over the noise with false-alarm probability under ``p_fa``: standing on a
train, at a counter is still without that line, and says "no ride".  A lift's car may hum steadily near a
chain's link pass; its climb (0.5-0.9 m/s over 4 s in ADVIO's lift, faster than any escalator's 0.43 m/s)
within the still span or 8 s of it refuses the line, said in ``RideSearch.refused``; a ride whose barometer
shows no climb, or without a barometer, is kept and flagged (``Ride.flag``).  Walking up a moving escalator is
not found (the gait hides the line).

What a ride can say without a tachometer: the link-pass frequency with its sigma and, given the chain's
nominal pitch, the chain's *actual* speed (pitch times frequency) and its deviation from the rated speed
(EN 115-1 allows +-5 %).  It cannot tell the chain's elongation: that needs a speed measured to better
than the elongation, which a phone does not give.  The barometer gives the direction and the vertical
speed, and with the speed the incline.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import asdict, dataclass, field

import numpy as np

from ..signal.ride import RideSegment
from ..signal.steadyline import line_level, normalised_spectrum, steady_line
from ..signal.stillness import LEAVE_THRESHOLD, STILL_THRESHOLD, still_spans, walking_level
from .climb import (
    CAR_ACCELERATION,
    CAR_HOLD_S,
    ESCALATOR_VZ_MAX,
    LEVEL_VZ,
    LIFT_MARGIN_S,
    car_acceleration,
    climbs_as_an_escalator,
    fastest_climb,
    vertical_speed,
)

__all__ = [
    "DEFAULT_BAND_HZ",
    "Ride",
    "RideSearch",
    "common_line",
    "common_line_names",
    "find_rides",
    "ride_evidence",
    "ride_in_walk",
    "unconfirmed_line",
    "walking_fraction",
    "WALK_FRACTION",
]

#: where a chain's link pass may be without a profile [Hz]: 0.4-0.9 m/s over 101.6-135 mm pitches
DEFAULT_BAND_HZ = (2.9, 9.0)


@dataclass(frozen=True)
class Ride:
    """One escalator ride found in a recording (times in the file's own seconds).

    ``start_s``/``end_s`` bound the ride: stepping on (walking stopped, or where the line starts when the person
    stood at the landing first) to stepping off (walking started again); ``line_start_s`` and
    ``line_end_s`` the part analysed, where the link pass stands clear of stepping on and off."""

    start_s: float
    end_s: float
    direction: str  # "up", "down", "level" or "unknown"
    link_pass_hz: float | None  # None: two steady lines, and the record cannot tell which is the chain's (``lines_hz``)
    link_pass_sigma_hz: float | None
    level_db: float
    p_value: float
    channel: str  # the channel with the most evidence
    speed_m_s: float | None = None
    speed_sigma_m_s: float | None = None
    speed_deviation_percent: float | None = None
    speed_deviation_sigma_percent: float | None = None
    vertical_speed_m_s: float | None = None
    vertical_speed_sigma_m_s: float | None = None
    rise_m: float | None = None
    rise_source: str | None = None
    incline_deg: float | None = None
    channels_db: dict = field(default_factory=dict)
    line_start_s: float | None = None  # the part of the ride analysed: the line clear of stepping on and off
    line_end_s: float | None = None
    vertical_speed_max_m_s: float | None = None  # the barometer's fastest 4 s slope within the still span or near it
    rise_sigma_m: float | None = None
    incline_sigma_deg: float | None = None
    flag: str | None = None  # what the barometer cannot rule out (a level ride, or no barometer)
    # where the ride holds two steady lines, neither a harmonic of the other: both [Hz] and their levels [dB], the
    # stronger first; the link pass (and the speed from it) is then not told
    lines_hz: tuple = ()
    lines_db: tuple = ()

    @property
    def duration_s(self) -> float:
        return self.end_s - self.start_s

    def to_dict(self) -> dict:
        out = asdict(self)
        out["duration_s"] = self.duration_s
        return out


@dataclass(frozen=True)
class RideSearch:
    """What :func:`find_rides` found: the rides, and the still spans it tested and why each is not a ride."""

    rides: tuple
    band_hz: tuple
    p_fa: float
    still_spans: tuple  # (start_s, end_s, verdict)
    channels: tuple
    notes: tuple = ()
    refused: tuple = ()  # dicts: start_s, end_s, link_pass_hz, level_db, p_value, why (a line that is no ride)


def _interp_finite(tu, t, v):
    """``v`` at ``tu`` from its finite samples only (an app that writes one sensor a row leaves the others empty)."""
    ok = np.isfinite(v)
    if ok.all() or np.count_nonzero(ok) < 2:
        return np.interp(tu, t, v)
    return np.interp(tu, t[ok], v[ok])


def _uniform(ds, names, fs):
    t = np.asarray(ds["time"].values, dtype=float)
    tu = np.arange(t[0], t[-1], 1.0 / fs)
    x = np.stack([_interp_finite(tu, t, np.asarray(ds[n].values, dtype=float)) for n in names])
    # samples farther than five periods from a stamp are a gap: never still, never analysed
    k = np.clip(np.searchsorted(t, tu), 1, t.size - 1)
    near = np.minimum(np.abs(tu - t[k - 1]), np.abs(t[k] - tu)) <= 5.0 / fs
    return tu, x, near


def _by_axis(names):
    """Three channels named by their axes (x, y, z last: an app's AccX, AccY, AccZ beside its magnitude's column),
    else the first three."""
    named = [next((v for v in names if v.lower().endswith(ax)), None) for ax in "xyz"]
    return named if None not in named and len(set(named)) == 3 else list(names[:3])


def _acc_channels(ds):
    acc = [v for v in ds.data_vars if ds[v].attrs.get("quantity") == "acceleration"]
    if len(acc) >= 3:
        return _by_axis(acc), 1.0
    cand = [v for v in ds.data_vars if v != "segment" and ds[v].dims == ("time",)]
    axes = _by_axis(cand)
    if len(axes) >= 3:
        cols = [np.asarray(ds[v].values, dtype=float) for v in axes]
        both = np.all(np.isfinite(cols), axis=0)
        # rows where all three hold a value; sparse rows (one sensor a row): each axis' own median
        mag = (
            float(np.median(np.sqrt(sum(c[both] ** 2 for c in cols))))
            if np.count_nonzero(both) > 10
            else float(np.sqrt(sum(np.nanmedian(c) ** 2 for c in cols)))
        )
        if 7.0 <= mag <= 12.5:
            return axes, 1.0
        if 0.7 <= mag <= 1.3:
            return axes, 9.80665
    raise ValueError(
        f"{ds.attrs.get('source_file', 'the recording')}: no accelerometer's three axes (channels: "
        f"{', '.join(cand) or 'none'}); expected x, y, z of a phone's accelerometer in m/s^2 or g"
    )


def find_rides(
    recording,
    *,
    nominal_pitch=None,
    rated_speed=None,
    band=None,
    p_fa=1e-3,
    min_ride_s=6.0,
    trim_s=1.0,
    still_threshold=STILL_THRESHOLD,
) -> RideSearch:
    """Find the escalator rides in a phone recording of a walk (see the module's notes).

    Parameters
    ----------
    recording : xarray.Dataset
        A recording with an accelerometer's three axes (:func:`vibkit.read_recording` of a phone file or
        folder); a gyroscope's axes and a barometer are used where present.
    nominal_pitch : float, optional
        The chain's nominal link pitch [m]: gives each ride's speed.
    rated_speed : float, optional
        The rated step speed [m/s]: narrows the band to +-10 % around rated speed / pitch (with a
        pitch) and gives each ride's deviation from it.
    band : (float, float), optional
        Where the link pass may be [Hz] (default: from pitch and rated speed, else 2.9-9 Hz).
    p_fa : float
        Bound on the false-alarm probability of each still span's test (default 1e-3).
    min_ride_s : float
        Shortest still span tested [s] (default 6: an 8 s ride less the walking band's 2 s window).
    trim_s : float
        Left out at each end of a still span: stepping on and off [s] (default 1).
    still_threshold : float
        Walking-band r.m.s. under which the person stands still [m/s^2]; a still span ends only where the band
        stays over :data:`~vibkit.signal.stillness.LEAVE_THRESHOLD` (or this, if higher) for a step.

    Returns
    -------
    RideSearch
    """
    if band is None:
        if nominal_pitch is not None and rated_speed is not None:
            f = abs(float(rated_speed)) / float(nominal_pitch)
            band = (0.9 * f, 1.1 * f)
        else:
            band = DEFAULT_BAND_HZ
    band = (float(band[0]), float(band[1]))
    acc, scale = _acc_channels(recording)
    gyro = [v for v in ("gyro_x", "gyro_y", "gyro_z") if v in recording.data_vars]
    names = acc + gyro
    fs = float(recording.attrs.get("sample_rate_hz") or 0.0)
    t_raw = np.asarray(recording["time"].values, dtype=float)
    if not fs > 0:
        fs = 1.0 / float(np.median(np.diff(t_raw)))
    if band[1] >= 0.45 * fs:
        raise ValueError(
            f"{recording.attrs.get('source_file', 'the recording')}: the link pass's band {band[0]:g}-{band[1]:g} Hz "
            f"reaches past 0.45 x the sample rate {fs:.4g} Hz: record at {band[1] / 0.45:.0f} Hz or faster (the app's "
            "fastest rate), or give a narrower --band"
        )
    tu, x, near = _uniform(recording, names, fs)
    x[:3] *= scale
    level = walking_level(x[:3], fs)
    level[~near] = np.inf
    # hysteresis: still where the walking band falls under the still level, a ride's span left only where walking
    # resumes for a step (a passenger shifting on a step does not end the ride)
    leave = max(LEAVE_THRESHOLD, still_threshold)
    spans = still_spans(level, fs, threshold=still_threshold, leave=leave, min_s=min_ride_s)
    rides, verdicts, notes, refused = [], [], [], []
    for a, b in spans:
        t0, t1 = float(tu[a]), float(tu[b - 1])
        i0, i1 = a + int(round(trim_s * fs)), b - int(round(trim_s * fs))
        if (i1 - i0) / fs * band[0] < 6:
            verdicts.append((t0, t1, "too short to resolve the band's lowest frequency"))
            continue
        line, j0, j1, why = _line_in(x[:, i0:i1], fs, band, p_fa)
        if line is None:
            verdicts.append((t0, t1, f"no ride: {why}"))
            continue
        if j1 - j0 < i1 - i0:
            notes.append(
                f"still {t0:.1f}-{t1:.1f} s: the line only {tu[i0 + j0]:.1f}-{tu[i0 + j1 - 1]:.1f} s (standing off the "
                "escalator before or after)"
            )
        # a ride starts where its line does when that is later than the still span (a person standing at the landing
        # before stepping on: the line's first window less the second trimmed), and ends where walking resumes (people
        # walk off an escalator; the line of a step flattening into the landing fades before they do)
        start = t0 if j0 == 0 else max(t0, float(tu[i0 + j0]) - trim_s)
        span = x[:, i0:i1]  # the still span less stepping on and off: where another line is looked for
        span_i0, span_i1 = i0, i1
        i0, i1 = i0 + j0, i0 + j1
        # a lift: its car may hum steadily near a chain's link pass, and a person stands still in it; its climb (about
        # 1 m/s, faster than any escalator's) falls within the still span or just before or after it
        fast, at = fastest_climb(recording, t0 - LIFT_MARGIN_S, t1 + LIFT_MARGIN_S)
        # without a barometer, the car's start or stop: the still span's acceleration off gravity
        car = car_acceleration(x[:3, span_i0:span_i1], fs) if fast is None else None
        why = None
        if fast is not None and fast > ESCALATOR_VZ_MAX and not climbs_as_an_escalator(recording, start, t1, at):
            why = (
                f"a lift, not an escalator: the barometer's vertical speed reaches {fast:.2f} m/s (over 4 s about "
                f"{at:.0f} s, within {LIFT_MARGIN_S:.0f} s of the still span), faster than any escalator climbs "
                f"({ESCALATOR_VZ_MAX:.2f} m/s; or a pressure wave: a train, a door)"
            )
        elif car is not None and car >= CAR_ACCELERATION:
            why = (
                f"a lift, not an escalator: with no barometer, the acceleration stands {car:.2f} m/s^2 off gravity for "
                f"{CAR_HOLD_S:g} s while the person stands still (a car starting or stopping; a rider standing on an "
                f"escalator stays under {CAR_ACCELERATION:g} m/s^2)"
            )
        if why is not None:
            refused.append(
                {
                    "start_s": start,
                    "end_s": t1,
                    "link_pass_hz": line.frequency_hz,
                    "level_db": line.level_db,
                    "p_value": line.p_value,
                    "vertical_speed_max_m_s": fast,
                    "car_acceleration_m_s2": car,
                    "why": why,
                }
            )
            verdicts.append((t0, t1, f"refused: a steady line at {line.frequency_hz:.3f} Hz, but {why}"))
            continue
        ride = _ride(recording, line, names, start, t1, nominal_pitch, rated_speed)
        other = _other_line(span, fs, band, line.frequency_hz, p_fa)
        untold = {}
        if other is not None:
            pair = sorted([line, other], key=lambda x: -x.level_db)
            untold = dict(
                link_pass_hz=None,
                link_pass_sigma_hz=None,
                speed_m_s=None,
                speed_sigma_m_s=None,
                speed_deviation_percent=None,
                speed_deviation_sigma_percent=None,
                incline_deg=None,
                incline_sigma_deg=None,
                lines_hz=tuple(float(x.frequency_hz) for x in pair),
                lines_db=tuple(float(x.level_db) for x in pair),
            )
            notes.append(
                f"ride {start:.1f}-{t1:.1f} s: two steady lines, {line.frequency_hz:.3f} Hz ({line.level_db:.1f} dB) and "
                f"{other.frequency_hz:.3f} Hz ({other.level_db:.1f} dB, p <= {other.p_value:.2g}), neither a harmonic of "
                "the other: which is the chain's link pass the record cannot tell (another machine's line, a drive "
                "chain), so none is given; give --nominal-pitch and --speed (or --escalator), or --band, to search "
                "near the chain's"
            )
        rides.append(
            dataclasses.replace(
                ride,
                line_start_s=float(tu[i0]),
                line_end_s=float(tu[i1 - 1]),
                vertical_speed_max_m_s=fast,
                **untold,
            )
        )
        verdicts.append((t0, t1, "ride"))
    return RideSearch(tuple(rides), band, p_fa, tuple(verdicts), tuple(names), tuple(notes), tuple(refused))


def _line_in(x, fs, band, p_fa):
    """(the steady line, first and stop sample of the part analysed, why not) of a still span's channels ``x``: a
    line over the whole span first (no steadiness asked), then the part where that line stands (a still span may
    hold standing before stepping on or after stepping off: the ride is where the line is), tested for a steady
    line.  The line is None where either test fails."""
    n = x.shape[1]
    seg = x - x.mean(axis=1, keepdims=True)
    line = steady_line(seg, fs, band=band, p_fa=p_fa, parts=1)
    if not line.detected:
        return None, 0, n, line.reason
    j0, j1 = _where_the_line_is(seg, fs, line.frequency_hz, band, line.level_db)
    if j1 - j0 >= n - int(1.5 * fs):
        j0, j1 = 0, n
    if (j1 - j0) / fs * band[0] < 6:
        return None, j0, j1, "the line lasts too short to resolve the band's lowest frequency"
    part = x[:, j0:j1] - x[:, j0:j1].mean(axis=1, keepdims=True)
    line = steady_line(part, fs, band=band, p_fa=p_fa)
    third = (j1 - j0) // 3
    if not line.detected and line.failed_part in (0, 2) and 2 * third / fs * band[0] >= 6:
        # the first or last third without the line: stepping on or off the escalator (or standing at a landing), too
        # short for the windows above to cut; the two thirds that show it are tested once more
        j0, j1 = (j0 + third, j1) if line.failed_part == 0 else (j0, j1 - third)
        part = x[:, j0:j1] - x[:, j0:j1].mean(axis=1, keepdims=True)
        line = steady_line(part, fs, band=band, p_fa=p_fa)
    return (line, j0, j1, "") if line.detected else (None, j0, j1, line.reason)


#: how near a line (relative) another is taken for the same line or its harmonic: a Hann window's main lobe on a 10 s
#: ride is +-0.2 Hz, 5 % of a 4 Hz line; a passenger moves the line 1-2 %
_SAME_LINE = 0.06


def _other_line(x, fs, band, freq, p_fa):
    """Another steady line in ``band`` of the ride's channels ``x`` than the one at ``freq`` [Hz] and its harmonics and
    half (within :data:`_SAME_LINE` of each), or None: the band's parts left by those are each tested for a steady line
    with ``p_fa`` shared among them (the note's false-alarm bound is the ride's)."""
    near = sorted(k * freq for k in (0.5, 1.0, 2.0, 3.0))
    edges, lo = [], band[0]
    for c in near:
        a, b = c * (1 - _SAME_LINE), c * (1 + _SAME_LINE)
        if b <= lo or a >= band[1]:
            continue
        if a > lo:
            edges.append((lo, min(a, band[1])))
        lo = max(lo, b)
    if lo < band[1]:
        edges.append((lo, band[1]))
    n = x.shape[1]
    edges = [(a, b) for a, b in edges if b - a >= 0.3 and n / fs * a >= 6]  # resolvable parts only
    if not edges:
        return None
    seg = x - x.mean(axis=1, keepdims=True)
    best = None
    for a, b in edges:
        line = steady_line(seg, fs, band=(a, b), p_fa=p_fa / len(edges))
        if line.detected and (best is None or line.p_value < best.p_value):
            best = line
    return best


def _where_the_line_is(seg, fs, freq, band, level_db, on_db=3.0):
    """(first, stop) sample of the stretch of sliding windows that holds the most evidence of the line near ``freq``:
    the run that maximises the sum of ``level - on`` over its windows (levels as power ratios; the whole segment when
    every window stands over ``on``).

    A steady line that stands ``R`` (``level_db``) over the floor in the whole segment of ``T`` seconds stands about
    ``1 + (R - 1) w / T`` in a window of ``w`` seconds, and noise alone about 1.  ``on`` is halfway between the two,
    never over ``on_db`` nor under 1.5 (1.8 dB), so that a window of noise scores negative and one with the line
    positive: the stretch ends where the line is gone for good (standing at a landing, stepping off), while a window
    in which a weak line dips inside the ride is outweighed by its neighbours and does not cut the ride in two."""
    n = seg.shape[1]
    window = max(min(4.0, n / fs / 3), 6.0 / band[0])
    c, lv = line_level(seg, fs, freq, window_s=window, tolerance=0.02)  # a passenger moves the line 1-2 %
    expected = 1.0 + (10.0 ** (level_db / 10.0) - 1.0) * window / (n / fs)
    on = min(max(0.5 * (1.0 + expected), 1.5), 10.0 ** (on_db / 10.0))
    if lv.size == 0 or np.all(10.0 ** (lv / 10.0) >= on):
        return 0, n
    gain = 10.0 ** (lv / 10.0) - on
    best, first, stop = 0.0, 0, 0
    run, run_first = 0.0, 0
    for k, g in enumerate(gain):  # the largest sum over a run of consecutive windows (Kadane)
        if run <= 0.0:
            run, run_first = 0.0, k
        run += g
        if run > best:
            best, first, stop = run, run_first, k + 1
    if best <= 0.0:
        return 0, n
    half = window / 2
    a = max(int((c[first] - half) * fs), 0)
    b = min(int((c[stop - 1] + half) * fs), n)
    return a, b


#: what a ride's flag says where the barometer cannot rule a lift out
_FLAG_LEVEL = (
    "level: the barometer shows no climb while the line is on and no lift's climb within {m:.0f} s of it: a level "
    "moving walk, or a machine standing still (a lift at a floor whose climb the record does not hold)"
)
_FLAG_NO_BAROMETER = (
    "no barometer: a lift standing at a floor cannot be told from an escalator without one (a car's start or stop "
    "within the still span would have refused it)"
)


def _ride(ds, line, names, t0, t1, pitch, rated):
    vz, vz_s, rise, rise_s, source = vertical_speed(ds, t0, t1)
    flag = None
    if vz is None:
        direction, flag = "unknown", _FLAG_NO_BAROMETER
    elif abs(vz) < max(LEVEL_VZ, 2 * vz_s):
        direction, flag = "level", _FLAG_LEVEL.format(m=LIFT_MARGIN_S)
    else:
        direction = "up" if vz > 0 else "down"
    speed = speed_s = dev = dev_s = incline = incline_s = None
    if pitch is not None:
        speed = float(pitch) * line.frequency_hz
        speed_s = float(pitch) * line.sigma_hz
        if rated is not None:
            dev = 100.0 * (speed / abs(float(rated)) - 1.0)
            dev_s = 100.0 * speed_s / abs(float(rated))
        if vz is not None and abs(vz) < speed:
            # asin(v_z / v): d/dv_z = 1 / (v cos), d/dv = -v_z / (v^2 cos)
            th = math.asin(abs(vz) / speed)
            incline = math.degrees(th)
            incline_s = math.degrees(math.hypot(vz_s, abs(vz) * speed_s / speed) / (speed * math.cos(th)))
    return Ride(
        start_s=t0,
        end_s=t1,
        direction=direction,
        link_pass_hz=line.frequency_hz,
        link_pass_sigma_hz=line.sigma_hz,
        level_db=line.level_db,
        p_value=line.p_value,
        channel=names[line.strongest_channel],
        speed_m_s=speed,
        speed_sigma_m_s=speed_s,
        speed_deviation_percent=dev,
        speed_deviation_sigma_percent=dev_s,
        vertical_speed_m_s=vz,
        vertical_speed_sigma_m_s=vz_s,
        rise_m=rise,
        rise_sigma_m=rise_s,
        rise_source=source,
        incline_deg=incline,
        incline_sigma_deg=incline_s,
        flag=flag,
        channels_db=dict(zip(names, line.channel_levels_db)),
    )


def ride_evidence(recording, ride, search):
    """What a ride's page draws: the axes' mean normalised periodogram over the part analysed, and the line's level
    in sliding windows over the still span.

    Returns
    -------
    dict
        ``f`` [Hz] and ``level_db`` (the spectrum), ``track_s`` [s, the file's time] and ``track_db`` (the line's
        level in 4 s windows), ``threshold_db``.
    """
    names = list(search.channels)
    fs = float(recording.attrs.get("sample_rate_hz") or 0.0)
    if not fs > 0:
        fs = 1.0 / float(np.median(np.diff(np.asarray(recording["time"].values, dtype=float))))
    tu, x, _ = _uniform(recording, names, fs)
    a, b = np.searchsorted(tu, [ride.line_start_s, ride.line_end_s])
    seg = x[:, a:b] - x[:, a:b].mean(axis=1, keepdims=True)
    f, t = normalised_spectrum(seg, fs)
    a2, b2 = np.searchsorted(tu, [ride.start_s, ride.end_s])
    span = x[:, a2:b2] - x[:, a2:b2].mean(axis=1, keepdims=True)
    freq = ride.link_pass_hz if ride.link_pass_hz is not None else ride.lines_hz[0]
    c, lv = line_level(span, fs, freq, window_s=4.0)
    return {
        "f": f,
        "level_db": 10 * np.log10(np.maximum(t, 1e-300)),
        "track_s": c + float(tu[a2]),
        "track_db": lv,
    }


def ride_in_walk(recording, axes, t0, notes, source):
    """The ride segment of a phone's recording for its ride quality (times from ``t0`` [s], the assessed burst's
    start), or None where the ride is left to the step's own signals (:func:`~vibkit.signal.detect_ride_segment`).

    A record in which the person walks (the walking band over the still level for a fifth of it or more) is a
    walk with rides, not a step's ride: its incline cannot be read from the gravity component (a phone in the
    hand turns) nor from the integrated vertical acceleration (walking drifts it by metres a second).  The ride
    is then the longest :func:`find_rides` finds (said in ``notes``); a walk without one is refused.

    A phone's export in which nobody walks (a phone laid on a step, or held by someone standing) is a ride where
    its link-pass line is (:func:`find_rides`, the longest): the line says where the chain carried the phone,
    where a phone's integrated vertical acceleration says its own noise and turns (cut out of the eight ADVIO
    walks, the rides' integrated vertical speed read -0.87 to +0.59 m/s where the barometer read 0.22 to 0.26
    m/s).  A phone's recording without a line is refused, naming each still span's verdict.

    Parameters
    ----------
    recording : xarray.Dataset
    axes : list of str or None
        The accelerometer's x, y, z channels (None where the ride-quality axes lack one).
    t0 : float
        Where the assessed burst starts [s].
    notes : list of str
        Appended to.
    source : str
        The recording as the messages name it.
    """
    if None in axes:
        return None
    t = np.asarray(recording["time"].values, dtype=float)
    fs = float(recording.attrs.get("sample_rate_hz") or 0.0) or 1.0 / float(np.median(np.diff(t)))
    if t[-1] - t[0] < 10.0:
        return None
    acc = np.stack([np.asarray(recording[c].values, dtype=float) for c in axes])
    walking = float(np.mean(walking_level(acc, fs) > STILL_THRESHOLD))
    if walking >= 0.2:
        found = find_rides(recording)
        if not found.rides:
            raise ValueError(
                f"{source}: a walk ({100 * walking:.0f} % of it walking) with no escalator ride found in it (`vibkit "
                "rides` says why for each still span): give the ride as --segment START:END"
            )
        what = f"a walk with {len(found.rides)} escalator ride(s) (`vibkit rides`); the longest assessed"
        method = "a ride in a walk"
    elif is_phone_recording(recording):
        found = find_rides(recording)
        if not found.rides:
            why = "; ".join(f"{a:.1f}-{b:.1f} s: {v}" for a, b, v in found.still_spans) or "no still span of 6 s"
            raise ValueError(
                f"{source}: a phone's recording with no escalator ride found in it ({why}); a phone's integrated "
                "acceleration cannot place the incline (the phone turns in the hand, its noise adds up): give the ride "
                "as --segment START:END"
            )
        what = "a phone's ride found by its link-pass line (`vibkit rides`)"
        method = "the link-pass line"
    else:
        return None
    ride = max(found.rides, key=lambda r: r.line_end_s - r.line_start_s)
    notes.append(
        f"{what}, {ride.line_start_s:.1f}-{ride.line_end_s:.1f} s of the recording (--segment to choose another)"
    )
    return RideSegment(
        start_s=max(ride.line_start_s - float(t0), 0.0),
        end_s=ride.line_end_s - float(t0),
        method=method,
        note=(
            f"link pass {ride.link_pass_hz:.3f} Hz"
            if ride.link_pass_hz is not None
            else "two steady lines (" + ", ".join(f"{f:.3f}" for f in ride.lines_hz) + " Hz), the link pass not told"
        )
        + f", direction {ride.direction}",
    )


#: the share of a phone's recording in its walking band over :data:`~vibkit.signal.stillness.STILL_THRESHOLD` from
#: which it is a walk, not a ride (a ride's span, stepping on and off included, holds far less)
WALK_FRACTION = 0.2


def walking_fraction(recording, *, trim_s=1.0):
    """The share of a phone's recording (``trim_s`` left out at each end) in which its walking band stands over
    :data:`~vibkit.signal.stillness.STILL_THRESHOLD`, or None where it has no three accelerometer axes or is too
    short to tell (under 10 s).  Over :data:`WALK_FRACTION` it is a walk: a steady line over the whole of it is the
    gait's or another machine's, not a ride's link pass (a walk's rides: :func:`find_rides`)."""
    try:
        acc, scale = _acc_channels(recording)
    except ValueError:
        return None
    t = np.asarray(recording["time"].values, dtype=float)
    if t.size < 2 or t[-1] - t[0] < 10.0 + 2 * trim_s:
        return None
    fs = float(recording.attrs.get("sample_rate_hz") or 0.0) or 1.0 / float(np.median(np.diff(t)))
    _, x, near = _uniform(recording, acc, fs)
    level = walking_level(x[:3] * scale, fs)
    k = int(round(trim_s * fs))
    level, near = level[k : level.size - k], near[k : near.size - k]
    level = level[near & np.isfinite(level)]
    return float(np.mean(level > STILL_THRESHOLD)) if level.size else None


def common_line(recording, band, *, p_fa=1e-3, trim_s=1.0):
    """One steady line common to a phone's axes in ``band`` [Hz] (:func:`~vibkit.signal.steadyline.steady_line` over
    its accelerometer's and gyroscope's channels, ``trim_s`` left out at each end: stepping on and off), or None
    where the recording has no three accelerometer axes (a tensioner, one channel) or is too short for the band.

    A ride's link pass is often one line without harmonics, which the harmonic-family test of ``vibkit spectrum``
    needs; the axes together show it."""
    names = common_line_names(recording)
    if not names:
        return None
    _, scale = _acc_channels(recording)
    t = np.asarray(recording["time"].values, dtype=float)
    fs = float(recording.attrs.get("sample_rate_hz") or 0.0) or 1.0 / float(np.median(np.diff(t)))
    if band[1] >= 0.45 * fs:
        return None
    tu, x, _ = _uniform(recording, names, fs)
    k = int(round(trim_s * fs))
    x = x[:, k : x.shape[1] - k]
    if x.shape[1] / fs * band[0] < 6:
        return None
    x[:3] *= scale
    line, _, _, _ = _line_in(x, fs, band, p_fa)
    return line if line is not None else steady_line(x - x.mean(axis=1, keepdims=True), fs, band=band, p_fa=p_fa)


def unconfirmed_line(recording, freq, band, *, tolerance=0.01):
    """Why a phone's common line at ``freq`` [Hz] (:func:`common_line` over the whole recording) is no ride's link
    pass, or None where it is one: :func:`find_rides` over the recording in ``band`` must find a ride (a still span
    whose line passes its false-alarm bound and is not a lift's climb) whose line, or one of its two, lies within
    ``tolerance`` of it.  A line over a recording's walking parts, or a lift's, fails that."""
    found = find_rides(recording, band=band)
    for r in found.rides:
        lines = [r.link_pass_hz] if r.link_pass_hz is not None else list(r.lines_hz)
        if any(abs(f / freq - 1.0) <= tolerance for f in lines):
            return None
    if found.rides:
        return (
            "the ride(s) found in it carry other lines ("
            + ", ".join(f"{r.start_s:.1f}-{r.end_s:.1f} s" for r in found.rides)
            + "): give one as --segment START:END"
        )
    spans = "; ".join(f"{a:.1f}-{b:.1f} s: {v}" for a, b, v in found.still_spans) or "no still span to test"
    return "no ride found in it (" + spans + ")"


def common_line_names(recording) -> list:
    """The channels :func:`common_line` combines: the accelerometer's three axes and the gyroscope's (none without
    three accelerometer axes)."""
    try:
        acc, _ = _acc_channels(recording)
    except ValueError:
        return []
    return acc + [v for v in ("gyro_x", "gyro_y", "gyro_z") if v in recording.data_vars]


def is_phone_recording(recording) -> bool:
    """Whether the recording is a phone's export (its channels carry the phone reader's ``sensor``)."""
    return any(recording[v].attrs.get("sensor") in ("accelerometer", "gyroscope") for v in recording.data_vars)
