"""A roller that knocks once a turn: a flat (or out-of-round) roller under the step a sensor rides.

A roller worn flat pivots over the flat's edges once a turn and the leading edge strikes its track
(:mod:`vibkit.model.flat_roller`): the step's vertical acceleration carries a train of knocks at the
roller's turn, f_r = v / (2 pi r) on a straight track (2.27 Hz for a 35 mm roller at 0.5 m/s), not
locked to the link pass (v / p). A knock is a velocity reversal 2 v sin(beta) with the pivot's pull
toward the track on either side of it, so its spectrum rises as f^2 up to about the inverse of the
pivot's duration: the evidence is in the high harmonics (tens of Hz), which a step sensor sampled at
200 Hz or more records.

:func:`roller_knock` tests the vertical acceleration of a straight stretch of the ride for a harmonic
family with its fundamental within :data:`RADIUS_TOLERANCE` of the roller's turn, summing the harmonics
up to :data:`KNOCK_TOP_HZ` (:func:`vibkit.signal.detect.detect_link_pass`, with its stated false-alarm
probability). A step's vertical acceleration carries the chain's own lines whatever its rollers: every
harmonic of the step pass v / (p links_per_step), whose multiples hold the link pass's. They are fitted
and removed first (:func:`without_chain_lines`) and their bins left out of every sum. No bin counts
more than :data:`LINE_CLIP` noise means in a sum, and a family is a knock only where at least
:data:`MIN_KNOCK_ORDERS` of its harmonics above :data:`KNOCK_ORDERS_FROM_HZ` stand out alone: a few
strong lines of something else (mains hum, a machine) or a gait's low harmonics are not a knock. Each of
these only removes detections, so the false-alarm probability stays at most the test's. A family found
gives the radius that turns at its frequency, v / (2 pi f).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model.profile_scene import roller_radius_of
from ..signal.detect import detect_link_pass
from ..signal.estimate import harmonic_ls

__all__ = [
    "KNOCK_TOP_HZ",
    "RADIUS_TOLERANCE",
    "RollerKnock",
    "ride_knock",
    "roller_knock",
    "step_rollers_of",
    "without_chain_lines",
]

#: harmonics are summed up to this frequency (and 0.45 fs) [Hz]: a knock's spectrum rises up to the
#: inverse of the pivot's duration (10 ms for a 5 mm flat on a 35 mm roller at 0.5 m/s)
KNOCK_TOP_HZ = 100.0
#: the turn is searched this far (relative) around v / (2 pi r): a worn tyre, the speed's uncertainty,
#: a trailer roller of another size
RADIUS_TOLERANCE = 0.06
#: a family found within this (relative) of the search band's edge peaks outside it: no roller's turn
EDGE = 1e-3
#: half-width of the chain's lines left out of the sums [bins]
CHAIN_LINE_BINS = 1.0
#: no bin counts more than this in a sum (noise: mean 1): a knock is many harmonics, a few strong lines of
#: something else (mains hum, a motor) cannot make one
LINE_CLIP = 8.0
#: a knock is a few milliseconds long: a family is one only where at least MIN_KNOCK_ORDERS of its
#: harmonics above KNOCK_ORDERS_FROM_HZ stand out alone (a gait's or a hum's do not)
MIN_KNOCK_ORDERS = 5
KNOCK_ORDERS_FROM_HZ = 20.0
#: the fewest turns of the roller the test is run on (split in halves of at least three)
MIN_TURNS = 8
#: the ride's straight part: its segment without this fraction at either end (the transition curves,
#: where the roller's turn runs faster or slower than on the straight)
TRIM = 0.15


@dataclass(frozen=True)
class RollerKnock:
    """Result of :func:`roller_knock`.

    Attributes
    ----------
    detected : bool
        A roller of the step knocks once a turn (at false-alarm probability ``p_fa``).
    reason : str
        One sentence: why.
    frequency_hz : float
        The knock's rate (NaN when none). [Hz]
    radius_m : float
        The rolling radius that turns at that rate at the speed, v / (2 pi f) (NaN when none). [m]
    band_hz : (float, float)
        Where the turn was searched. [Hz]
    p_value, p_fa : float
    n_harmonics : int
        Harmonics summed (those not on the chain's lines count).
    """

    detected: bool
    reason: str
    frequency_hz: float
    radius_m: float
    band_hz: tuple
    p_value: float
    p_fa: float
    n_harmonics: int

    def as_dict(self) -> dict:
        return {
            "detected": self.detected,
            "reason": self.reason,
            "frequency_hz": self.frequency_hz if self.detected else None,
            "radius_m": self.radius_m if self.detected else None,
            "band_hz": list(self.band_hz),
            "p_value": self.p_value,
            "p_fa": self.p_fa,
            "n_harmonics": self.n_harmonics,
        }


#: the chain's step pass is searched this far (relative) around speed / (pitch links_per_step)
CHAIN_SPREAD = 0.01


def without_chain_lines(x, fs, f_step, f_top):
    """``x`` less a least-squares fit of every harmonic of the chain's step pass up to ``f_top``: the
    link pass and its harmonics (every links_per_step-th) and the step pass's own, their common frequency
    found within :data:`CHAIN_SPREAD` of ``f_step`` (:func:`vibkit.signal.harmonic_ls`, started from the
    harmonics' bins of a zero-padded periodogram). A clean simulation's link-pass lines stand so far over
    its floor that their leakage alone would make families anywhere; what is left is the rest of the
    step's motion."""
    x = np.asarray(x, dtype=float)
    n_h = min(int(f_top // (f_step * (1 - CHAIN_SPREAD))) + 1, int(0.49 * fs // (f_step * (1 + CHAIN_SPREAD))))
    orders = np.arange(1, n_h + 1)
    pad = 16 * x.size
    spec = np.abs(np.fft.rfft((x - x.mean()) * np.hanning(x.size), pad)) ** 2

    def coarse(f):
        k = np.rint(orders * f * pad / fs).astype(int)
        return float(spec[k[k < spec.size]].sum())

    f = max(f_step * (1.0 + CHAIN_SPREAD * np.linspace(-1.0, 1.0, 401)), key=coarse)
    # a few harmonics first (a wide capture range), then all of them from there
    for k in (min(10, n_h), n_h):
        est = harmonic_ls(x, fs, f_guess=f, n_harmonics=k)
        f = est.frequency_hz
    arg = 2.0 * np.pi * f * np.arange(x.size) / fs
    model = est.offset + sum(a * np.cos((h + 1) * arg + p) for h, (a, p) in enumerate(zip(est.amplitudes, est.phases)))
    return x - model


def roller_knock(x, fs, *, speed, roller_radius, link_pitch, links_per_step=3, p_fa=1e-3):
    """Does a roller under the step knock once a turn?

    Parameters
    ----------
    x : array_like
        Vertical acceleration of a step over a straight stretch of track (the incline of the ride). [m/s^2]
    fs : float
        Sampling frequency. [Hz]
    speed : float
        Chain speed. [m/s]
    roller_radius : float
        The rollers' radius (the profile's ``roller_radius``). [m]
    link_pitch : float
        The chain's link pitch. [m]
    links_per_step : int
        Links per step (the step pass is the link pass over it).
    p_fa : float
        False-alarm probability of the test.

    Returns
    -------
    RollerKnock

    Raises
    ------
    ValueError
        Bad arguments, a sampling too slow for the knock's harmonics, or a stretch too short to test.
    """
    speed, r, p = float(speed), float(roller_radius), float(link_pitch)
    if not (speed > 0 and r > 0 and p > 0):
        raise ValueError(f"speed, roller_radius and link_pitch must be positive, got {speed!r}, {r!r}, {p!r}")
    f_turn = speed / (2.0 * math.pi * r)
    band = (f_turn / (1.0 + RADIUS_TOLERANCE), f_turn / (1.0 - RADIUS_TOLERANCE))
    f_top = min(KNOCK_TOP_HZ, 0.45 * float(fs))
    n_h = int(f_top // band[1])
    if n_h < 8:
        raise ValueError(
            f"a roller's knock shows in its harmonics up to {KNOCK_TOP_HZ:g} Hz; sampled at {fs:g} Hz the record "
            f"holds {n_h} of the {f_turn:.3g} Hz turn: record at 200 Hz or more"
        )
    step_pass = speed / (p * int(links_per_step))
    x = without_chain_lines(np.asarray(x, dtype=float), fs, step_pass, f_top)
    det = detect_link_pass(
        x,
        fs,
        band=band,
        n_harmonics=n_h,
        p_fa=p_fa,
        f_top=f_top,
        exclude=(step_pass, CHAIN_LINE_BINS),
        family_checks=False,
        clip=LINE_CLIP,
    )
    where = f"{band[0]:.3g}-{band[1]:.3g} Hz (the turn of a {1e3 * r:.3g} mm roller at {speed:.3g} m/s +- {100 * RADIUS_TOLERANCE:g} %)"
    high = [o for o in det.significant_orders if o * det.frequency_hz >= KNOCK_ORDERS_FROM_HZ]
    if det.detected and len(high) < MIN_KNOCK_ORDERS:
        reason = (
            f"no knock at {where}: a harmonic family at {det.frequency_hz:.4g} Hz passes the test (p = "
            f"{det.p_value:.2g}), but only {len(high)} of its harmonics above {KNOCK_ORDERS_FROM_HZ:g} Hz stand out "
            f"alone (orders {', '.join(map(str, det.significant_orders[:8])) or 'none'}); a knock, a few "
            f"milliseconds long, shows in {MIN_KNOCK_ORDERS} or more: a few lines of something else (hum, a "
            "machine) or a gait"
        )
        return RollerKnock(False, reason, float("nan"), float("nan"), band, det.p_value, p_fa, det.n_harmonics)
    if det.detected and not band[0] * (1 + EDGE) < det.frequency_hz < band[1] * (1 - EDGE):
        reason = (
            f"no knock at {where}: the strongest harmonic family (p = {det.p_value:.2g}) lies at the band's edge, "
            f"{det.frequency_hz:.4g} Hz: its peak is outside the turns a roller of this radius makes (the step's "
            "own lines, not a roller's knock)"
        )
        return RollerKnock(False, reason, float("nan"), float("nan"), band, det.p_value, p_fa, det.n_harmonics)
    if det.detected:
        f = float(det.frequency_hz)
        radius = speed / (2.0 * math.pi * f)
        reason = (
            f"a roller knocks once a turn: a harmonic family at {f:.4g} Hz, the turn of a {1e3 * radius:.3g} mm "
            f"roller at {speed:.3g} m/s (p = {det.p_value:.2g}, false-alarm probability {p_fa:g}): a flat or "
            "out-of-round roller under this step"
        )
        return RollerKnock(True, reason, f, radius, band, det.p_value, p_fa, det.n_harmonics)
    reason = f"no knock at {where}: {det.reason.split(': ', 1)[-1]}"
    return RollerKnock(False, reason, float("nan"), float("nan"), band, det.p_value, p_fa, det.n_harmonics)


def step_rollers_of(scene=None, profile=None):
    """``(radius [m], link pitch [m], links per step, where)`` of the step a sensor rides: a scene's
    (the middle roller of its ``step_accelerometer`` step) or an escalator profile's (its
    ``roller_radius``, else the reference 35 mm scaled with the pitch, as its scene is built); None
    without either."""
    if scene is not None:  # as the model places a step (EscalatorModel.step_rollers), without building the model
        c = scene.chain
        step = scene.outputs.get("step_accelerometer") or 1
        roller = (c.links_per_step * (int(step) - 1) + 1) % c.n_rollers
        return (
            float(c.radii()[roller]),
            float(c.link_pitch),
            int(c.links_per_step),
            f"roller {roller + 1} of the scene",
        )
    if profile is not None:
        radius, where = roller_radius_of(profile)
        return radius, float(profile.nominal_pitch), int(profile.links_per_step), f"the profile ({where})"
    return None


def ride_knock(rq, rollers, *, p_fa=1e-3):
    """The knock test (:func:`roller_knock`) on a ride's vertical axis: the ISO-weighted z of
    :class:`vibkit.diagnose.ride.RideQuality` ``rq`` (a linear filter: every harmonic's signal-to-noise
    ratio is the unweighted one's) over its segment without :data:`TRIM` at either end. ``rollers``:
    :func:`step_rollers_of`. Returns ``(RollerKnock or None, note)``: None, and why, where the ride
    cannot be tested."""
    if rollers is None:
        return None, "not checked: the rollers' radius is unknown (--escalator FILE)"
    if "z" not in rq.weighted:
        return None, "not checked: no vertical axis"
    if not rq.speed_m_s:
        return None, "not checked: no chain speed (--speed)"
    radius, pitch, per_step, _ = rollers
    seg = rq.segment
    a = seg.start_s + TRIM * seg.duration_s
    b = seg.end_s - TRIM * seg.duration_s
    turns = (b - a) * rq.speed_m_s / (2.0 * math.pi * radius)
    if turns < MIN_TURNS:
        return None, (
            f"not checked: the straight part of the ride ({a:.2f}-{b:.2f} s) "
            f"holds {turns:.1f} turns of a {1e3 * radius:.3g} mm roller, the test needs {MIN_TURNS}"
        )
    z = rq.weighted["z"][int(round(a * rq.fs)) : int(round(b * rq.fs))]
    try:
        res = roller_knock(
            z, rq.fs, speed=rq.speed_m_s, roller_radius=radius, link_pitch=pitch, links_per_step=per_step, p_fa=p_fa
        )
    except ValueError as exc:
        return None, f"not checked: {exc}"
    return res, f"{res.reason} (over {a:.2f}-{b:.2f} s of the ride)"
