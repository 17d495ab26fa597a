"""What a ride's climb says: the barometer's vertical speed and rise over a ride, a lift's climb near a still span,
and, without a barometer, a lift car's start or stop in the acceleration of a person standing still.

:mod:`vibkit.diagnose.rides` asks these of each still span whose line passes its test: a line with a lift's climb or
a car's start in or beside it is refused, a flat one is flagged (a level moving walk, or a lift at a floor).
"""

from __future__ import annotations

import math

import numpy as np

from ..signal.stillness import gravity_removed

__all__ = [
    "CAR_ACCELERATION",
    "ESCALATOR_VZ_MAX",
    "LEVEL_VZ",
    "LIFT_MARGIN_S",
    "altitude",
    "car_acceleration",
    "climbs_as_an_escalator",
    "fastest_climb",
    "vertical_speed",
]

#: air density times gravity near sea level [Pa/m]: the barometric pressure gradient
RHO_G = 1.2 * 9.81
#: |vertical speed| under which a ride is called level [m/s]
LEVEL_VZ = 0.05
#: the fastest an escalator climbs [m/s]: EN 115-1's 0.75 m/s on 35 deg is 0.43 m/s vertical (the eight ADVIO rides'
#: 4 s slopes: at most 0.29; walking stairs: 0.30; ADVIO's lift: 0.89)
ESCALATOR_VZ_MAX = 0.45
#: the barometer's slopes are read over windows of this length [s], stepped by a second
SLOPE_WINDOW_S = 4.0
#: how far before and after a still span a lift's climb is looked for [s]: a lift's doors open and close and its
#: passengers step in and out in about that (ADVIO's lift: 7-10 s at a floor between climbs of about 8 s)
LIFT_MARGIN_S = 8.0
#: a lift's car starting or stopping, where no barometer says so [m/s^2]: the acceleration's magnitude held this far
#: off gravity for :data:`CAR_HOLD_S` within a still span (low-passed at :data:`CAR_LOWPASS_HZ`).  Measured
#: 2026-12-08 on phones held still: ADVIO's rides 0.01-0.17 (advio-08's missed up ride 0.32), its lifts 0.49-0.78
#: (advio-07, -14, -18), two phyphox/Science Journal lifts 0.83-0.85.  Lifts accelerate at 0.5-1.2 m/s^2 for
#: comfort; a hydraulic lift's gentler start can stay under it
CAR_ACCELERATION = 0.4
CAR_HOLD_S = 1.0
CAR_LOWPASS_HZ = 0.5


def altitude(ds):
    """(time [s], altitude [m], source) of the recording's barometer, or None without one."""
    t = np.asarray(ds["time"].values, dtype=float)
    if "altitude" in ds.data_vars:
        return t, np.asarray(ds["altitude"].values, dtype=float), "barometer (phone's relative altitude)"
    if "pressure" in ds.data_vars:
        return t, -np.asarray(ds["pressure"].values, dtype=float) / RHO_G, "barometer (pressure)"
    return None


def slope(tt, z):
    a = tt - tt.mean()
    return float(np.dot(a, z - z.mean()) / np.dot(a, a))


def vertical_speed(ds, t0, t1):
    """(vertical speed [m/s], its sigma, rise [m], its sigma, source) over t0..t1 from the barometer, or Nones.

    The speed is the least-squares slope; its sigma the larger of the formal one and the scatter of the slopes of
    the span's 4 s parts (over the square root of their number): a barometer's noise is not white (air moves, the
    phone's altitude is smoothed), and on the eight ADVIO rides its 4 s slopes scatter by 0.01-0.03 m/s where the
    formal sigma is under 0.005.  The rise is the speed times the span, its sigma with the span's bounds known to a
    second (stepping on and off)."""
    alt = altitude(ds)
    if alt is None:
        return None, None, None, None, None
    t, zz, source = alt
    sel = (t >= t0) & (t <= t1) & np.isfinite(zz)
    rate = float(ds["altitude" if "altitude" in ds.data_vars else "pressure"].attrs.get("native_rate_hz", 1.0))
    tt, z = t[sel], zz[sel]
    if tt.size < 3 or tt[-1] - tt[0] < 3:
        return None, None, None, None, None
    vz = slope(tt, z)
    resid = z - z.mean() - vz * (tt - tt.mean())
    n_eff = max((tt[-1] - tt[0]) * min(rate, 1.0 / np.median(np.diff(tt))), 3.0)  # independent readings
    s = float(np.std(resid, ddof=2))
    sigma = s / math.sqrt(np.sum((tt - tt.mean()) ** 2) * n_eff / tt.size) if s > 0 else 0.0
    k = int((tt[-1] - tt[0]) // SLOPE_WINDOW_S)
    if k >= 2:
        edges = np.linspace(tt[0], tt[-1], k + 1)
        parts = [
            slope(tt[m], z[m]) for m in ((tt >= a) & (tt <= b) for a, b in zip(edges[:-1], edges[1:])) if m.sum() > 2
        ]
        if len(parts) >= 2:
            sigma = max(sigma, float(np.std(parts, ddof=1)) / math.sqrt(len(parts)))
    sigma = max(sigma, 0.005)
    rise = vz * (t1 - t0)
    return vz, sigma, rise, math.hypot(sigma * (t1 - t0), vz * 1.0), source


#: the least steady climb [m/s] that tells a ride from standing in a lift at a floor: the eight ADVIO rides climb
#: 0.12-0.29 m/s, a lift standing at a floor climbs nothing (its still spans read under 0.05 m/s)
ESCALATOR_VZ_MIN = 0.1


def climbs_as_an_escalator(ds, t0, t1, fast_at):
    """Whether the still span t0..t1 itself climbs as an escalator does (a steady 0.1-0.45 m/s, four sigmas from
    standing) while the fast climb near it (its 4 s window about ``fast_at``) lies wholly outside it: a pressure wave
    (a train, a door) beside a real ride, not a lift, whose car stands at a floor while its line is on."""
    if fast_at is None or t0 - SLOPE_WINDOW_S / 2 < fast_at < t1 + SLOPE_WINDOW_S / 2:
        return False
    vz, vz_s, *_ = vertical_speed(ds, t0, t1)
    return vz is not None and ESCALATOR_VZ_MIN <= abs(vz) <= ESCALATOR_VZ_MAX and abs(vz) > 4 * vz_s


def car_acceleration(acc, fs):
    """The acceleration a lift's car gives a person standing still in it [m/s^2]: the largest magnitude held for
    :data:`CAR_HOLD_S` by the three axes' low-passed vector less its median (gravity, where the phone keeps it:
    a vertical acceleration adds to ``|g|``; a turn of the phone in the hand does not change it)."""
    from scipy import ndimage, signal

    hold = max(int(round(CAR_HOLD_S * fs)), 1)
    sos = signal.butter(2, min(CAR_LOWPASS_HZ, 0.4 * fs), fs=fs, output="sos")
    if acc.shape[1] <= max(3 * 2 * sos.shape[0] * 3, hold):
        return 0.0
    if gravity_removed(acc, fs):
        off = np.sqrt(np.sum(signal.sosfiltfilt(sos, acc - np.median(acc, axis=1, keepdims=True), axis=1) ** 2, axis=0))
    else:
        mag = np.sqrt(np.sum(acc**2, axis=0))
        off = np.abs(signal.sosfiltfilt(sos, mag - np.median(mag)))
    return float(np.max(ndimage.minimum_filter1d(off, hold)))


def fastest_climb(ds, t0, t1):
    """(the barometer's largest |vertical speed| [m/s] over 4 s windows stepped by a second within t0..t1, the time
    [s] of that window's middle), or (None, None) without a barometer."""
    alt = altitude(ds)
    if alt is None:
        return None, None
    t, zz, _ = alt
    sel = (t >= t0) & (t <= t1) & np.isfinite(zz)
    tt, z = t[sel][::5], zz[sel][::5]  # the barometer reads at about 1 Hz: 20 Hz of its interpolation is plenty
    best, at = 0.0, None
    if tt.size < 3:
        return None, None
    for a in np.arange(tt[0], tt[-1] - SLOPE_WINDOW_S + 1e-9, 1.0):  # whole windows only, within the record
        m = (tt >= a) & (tt <= a + SLOPE_WINDOW_S)
        if m.sum() > 2:
            v = abs(slope(tt[m], z[m]))
            if v > best:
                best, at = v, a + SLOPE_WINDOW_S / 2
    return (best, at) if at is not None else (None, None)
