"""Compare a field recording with a simulation, harmonic by harmonic, in the order domain.

The two are not time-synchronous and their speeds differ, so each signal is referred to its own
link-pass fundamental (:func:`vibkit.signal.compare_spectra`).  A recording made of bursts is
compared burst by burst against the whole simulation and the per-harmonic results are combined by
inverse-variance weighting.  The pitch each signal implies (speed / fundamental) tells whether the
recording's chain is the scene's chain.

Agreement score (documented rule, the same as :data:`vibkit.signal.compare.SCORE_RULE`): the mean
over harmonics detected in either signal of
``exp(-((ratio - 1) / freq_tol)^2 / 2 - (diff_db / amp_tol_db)^2 / 2)``, a harmonic detected in
one signal only scoring 0; 1 is perfect agreement, 0 none.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import scipy.stats

from ..io import read_recording
from ..model.profile import Profile
from ..model.scene import Scene
from ..scenes import find
from ..signal import compare_spectra, order_spectrum, resample_to_angle
from ..signal.bursts import uniform_bursts
from .channels import counted_part, estimate_channels
from .comparison_figure import plot_comparison
from .html import result_table_html
from .pitch import DEFAULT_PITCH_RANGE_M, pick_channel
from .rounding import fmt_interval, fmt_pm
from .settings import resolve_settings
from .speed import speed_from_recording

if TYPE_CHECKING:  # for the annotations only
    import xarray as xr

__all__ = [
    "Comparison",
    "NothingToCompare",
    "compare",
    "matching_variable",
    "as_result",
    "amplitude_diff_text",
    "counted_speed_note",
]


class NothingToCompare(ValueError):
    """The recording carries no link pass to compare (on the channel asked for, or on any vibration channel)."""


# simulation variables that a sensor of each unit can be compared with, best first
_BY_UNITS = {
    "m": ("tensioner_displacement", "delta"),
    "m/s^2": ("accel_step", "delta_ddot"),
    "m/s": ("chain_speed", "delta_dot"),
}


def as_result(result, *, duration=None, progress=False):
    """A simulation result from a Dataset, a :class:`vibkit.model.scene.Scene`, a scene ``.toml`` (or a shipped
    scene's name) or a result file.

    A scene is simulated (``duration`` [s] overrides its length); a result file is read with
    :func:`vibkit.read_recording`.
    """
    import xarray as xr

    if isinstance(result, xr.Dataset):
        return result
    if isinstance(result, (str, os.PathLike)) and find(result) is not None:
        result = find(result)  # a shipped scene by its name ("leon", "sim/leon.toml" outside a clone)
    if isinstance(result, Scene) or (isinstance(result, (str, os.PathLike)) and str(result).endswith(".toml")):
        # the model (numba and its kernels) loaded only here: a report that compares a kept run loads neither
        from .fresh_simulation import simulate_fresh

        return simulate_fresh(result, duration=duration, progress=progress)
    if isinstance(result, (str, os.PathLike)):
        return read_recording(result)
    raise ValueError(
        f"result must be a Dataset, a Scene or a path (.toml scene or result file), got {type(result).__name__}"
    )


def matching_variable(result, recording, channel) -> str:
    """The simulation variable to compare with the recording's ``channel``.

    The same name if the result has it, else the first of the variables that sensors of the
    channel's units see (m: tensioner_displacement, delta; m/s^2: accel_step, delta_ddot; m/s:
    chain_speed, delta_dot).

    Raises
    ------
    ValueError
        No variable of the result matches; the message lists the result's variables.
    """
    if "time" not in result.dims:
        what = result.attrs.get("analysis", "")
        raise ValueError(
            f"the simulation{f' ({what})' if what else ''} has no time axis: a kinematics scene gives the chain's "
            "configurations along its advance, not signals in time; compare a recording with an inverse or a "
            "forward scene"
        )
    one_d = [str(v) for v in result.data_vars if result[v].dims == ("time",)]
    if channel in one_d:
        return channel
    units = str(recording[channel].attrs.get("units", ""))
    for name in _BY_UNITS.get(units, ()):
        if name in one_d:
            return name
    raise ValueError(
        f"the simulation has no variable to compare with channel {channel!r} [{units}] "
        f"(its time variables: {', '.join(one_d) or 'none'}); add one of "
        f"{', '.join(_BY_UNITS.get(units, ('a variable in the same units',)))} to the scene's "
        "outputs.variables"
    )


@dataclass(frozen=True)
class Comparison:
    """Result of :func:`compare`.

    Attributes
    ----------
    channel, variable : str
        Recording channel and simulation variable compared.
    units : str
    harmonics : list of dict
        Per harmonic: ``order``, ``frequency_sim_hz``, ``frequency_meas_hz``, ``frequency_ratio``
        (recording / simulation), ``frequency_ratio_sigma``, ``frequency_ratio_ci``,
        ``amplitude_sim``, ``amplitude_meas`` [units], ``amplitude_diff_db``,
        ``amplitude_diff_db_ci`` [dB], ``detected_sim``, ``detected_meas``, ``frequency_mismatch``.
    fundamental_sim_hz, fundamental_meas_hz : float
        [Hz]
    log_spectral_distance_db : float
        [dB]
    score : float
        In [0, 1]; see ``rule``.
    rule : str
    speed_sim_m_s, speed_meas_m_s : float
        [m/s]; the simulation's is its mean ``chain_speed`` when stored (else its nominal speed);
        the recording's is the ``speed`` given, else its stated ``chain_speed_m_s``, else the scene's
        nominal speed.
    speed_meas_sigma_m_s : float or None
        The recording's speed's standard deviation as stated (None: not stated).
    link_pass_sim_hz, link_pass_meas_hz : float
        The link passes the pitches are read from [Hz]: a simulation's counted one (else its spectrum's
        fundamental) and the recording's as ``vibkit pitch`` reads it (the shared decision's estimate).
    pitch_sim_m, pitch_meas_m : float
        Pitch implied by each signal, speed / link pass. [m]
    pitch_ratio, pitch_ratio_sigma : float
        ``pitch_meas_m / pitch_sim_m`` and its standard deviation (the frequencies' and the stated
        speed uncertainty's).
    pitch_consistent : bool or None
        ``|pitch_ratio - 1| <= pitch_tolerance + z sigma`` (z of the confidence level).
    pitch_tolerance : float
        Relative pitch difference accepted as the same chain (speed knowledge).
    confidence : float
    orders, order_amplitude_sim, order_amplitude_meas : ndarray
        Order spectra on a common order axis (recording averaged over bursts). [units]
    signals : dict
        ``sim`` (fs [Hz], x) and ``meas`` (list of (t0 [s], fs [Hz], x)) for plots.
    notes : list of str
    """

    channel: str
    variable: str
    units: str
    harmonics: list = field(repr=False)
    fundamental_sim_hz: float
    fundamental_meas_hz: float
    log_spectral_distance_db: float
    score: float
    rule: str
    speed_sim_m_s: float
    speed_meas_m_s: float
    pitch_sim_m: float
    pitch_meas_m: float
    pitch_ratio: float
    pitch_ratio_sigma: float
    pitch_consistent: bool | None
    pitch_tolerance: float
    confidence: float
    orders: np.ndarray = field(repr=False)
    order_amplitude_sim: np.ndarray = field(repr=False)
    order_amplitude_meas: np.ndarray = field(repr=False)
    signals: dict = field(repr=False, default_factory=dict)
    notes: list = field(default_factory=list)
    speed_meas_sigma_m_s: float | None = None
    link_pass_sim_hz: float = float("nan")
    link_pass_meas_hz: float = float("nan")

    def plot(self, fig=None):
        """The comparison drawn (:func:`~vibkit.diagnose.comparison_figure.plot_comparison`): order spectra overlaid,
        amplitude spectra and spectrograms side by side; a Figure."""
        return plot_comparison(self, fig)

    def _repr_html_(self) -> str:
        """The notebook's view: the score, the link pass and the pitch on both sides."""
        rows: list[tuple[str, object]] = [
            ("channel / variable", f"{self.channel} / {self.variable}"),
            ("fundamental, recording", f"{self.fundamental_meas_hz:.5g} Hz"),
            ("fundamental, simulation", f"{self.fundamental_sim_hz:.5g} Hz"),
            ("log-spectral distance", f"{self.log_spectral_distance_db:.3g} dB"),
            ("pitch ratio", fmt_pm(self.pitch_ratio, self.pitch_ratio_sigma)),
            ("score", f"{self.score:.3g} ({self.rule})"),
        ]
        return result_table_html(f"Simulation against recording: score {self.score:.3g}", rows)

    def as_dict(self) -> dict:
        """JSON-ready summary (no arrays except none)."""
        return {
            "channel": self.channel,
            "variable": self.variable,
            "units": self.units,
            "fundamental_sim_hz": self.fundamental_sim_hz,
            "fundamental_meas_hz": self.fundamental_meas_hz,
            "link_pass_sim_hz": self.link_pass_sim_hz,
            "link_pass_meas_hz": self.link_pass_meas_hz,
            "speed_sim_m_s": self.speed_sim_m_s,
            "speed_meas_m_s": self.speed_meas_m_s,
            "speed_meas_sigma_m_s": self.speed_meas_sigma_m_s,
            "pitch_sim_m": self.pitch_sim_m,
            "pitch_meas_m": self.pitch_meas_m,
            "pitch_ratio": self.pitch_ratio,
            "pitch_ratio_sigma": self.pitch_ratio_sigma,
            "pitch_consistent": self.pitch_consistent,
            "pitch_tolerance": self.pitch_tolerance,
            "log_spectral_distance_db": self.log_spectral_distance_db,
            "score": self.score,
            "score_rule": self.rule,
            "confidence": self.confidence,
            "harmonics": [dict(h) for h in self.harmonics],
            "notes": list(self.notes),
        }


def _combine(values, sigmas):
    v = np.asarray(values, float)
    s = np.asarray(sigmas, float)
    if v.size == 1:
        return float(v[0]), float(s[0])
    if np.all(s > 0):
        w = 1 / s**2
        return float(np.sum(w * v) / np.sum(w)), float(1 / np.sqrt(np.sum(w)))
    return float(np.mean(v)), float(np.std(v) / math.sqrt(v.size))


def _widen_by_order_scatter(rows, z, notes):
    """Every harmonic of a link-pass family shares one frequency ratio (f_k = k v / p in the recording and
    in the simulation alike): where the orders' ratios scatter more than their sigmas say (Birge ratio
    B = sqrt(chi^2 / dof) > 1 over the orders detected in both), the frequency estimates carry errors the
    noise does not account for (leakage, a speed that drifts within a burst), and every ratio's sigma and
    interval is widened by B (the Particle Data Group's scale factor). Returns B (1 where nothing is widened)."""
    both = [r for r in rows if r["detected_sim"] and r["detected_meas"] and r["frequency_ratio_sigma"] > 0]
    if len(both) < 3:
        return 1.0
    v = np.array([r["frequency_ratio"] for r in both])
    w = 1.0 / np.array([r["frequency_ratio_sigma"] for r in both]) ** 2
    mean = float(np.sum(w * v) / np.sum(w))
    birge = math.sqrt(float(np.sum(w * (v - mean) ** 2)) / (v.size - 1))
    if not birge > 1.0:
        return 1.0
    _widen(rows, birge, z)
    notes.append(
        f"the orders' frequency ratios ({v.min():.6f}-{v.max():.6f}) scatter {birge:.2g} times their sigmas, where one "
        f"chain gives them one ratio: every ratio's sigma (and the pitch ratio's) widened {birge:.2g} times"
    )
    return birge


def _widen_by_parts(rows, dec, z, notes):
    """The recording's own frequency sigma as :func:`vibkit.diagnose.pitch.estimate_pitch` states it: where its
    parts check widened it (the record's parts scatter beyond their sigmas), it is added in quadrature to order
    1's relative ratio sigma and every ratio's sigma widened by the same factor, so that the comparison claims no
    more precision than ``vibkit pitch`` on the same record."""
    parts = dec.parts or {}
    before = parts.get("sigma_before_hz")
    if not rows or not parts.get("widened") or not before or not dec.fundamental_sigma_hz > before:
        return
    own = rows[0]["frequency_ratio_sigma"] / rows[0]["frequency_ratio"]
    if not own > 0:
        return
    factor = math.hypot(own, float(dec.fundamental_sigma_hz) / float(dec.fundamental_hz)) / own
    _widen(rows, factor, z)
    notes.append(
        f"the recording's frequency sigma as vibkit pitch states it, widened by its parts' scatter ({before:.2g} to "
        f"{dec.fundamental_sigma_hz:.2g} Hz), added to order 1's ratio sigma: every ratio's sigma (and the pitch "
        f"ratio's) widened {factor:.2g} times"
    )


def _widen(rows, factor, z):
    """Every row's frequency-ratio sigma times ``factor``, its interval and mismatch flag with it."""
    for r in rows:
        r["frequency_ratio_sigma"] *= factor
        rs = r["frequency_ratio_sigma"]
        r["frequency_ratio_ci"] = [r["frequency_ratio"] - z * rs, r["frequency_ratio"] + z * rs]
        r["frequency_mismatch"] = bool(
            r["detected_sim"]
            and r["detected_meas"]
            and not r["frequency_ratio_ci"][0] <= 1.0 <= r["frequency_ratio_ci"][1]
        )


def _order_amplitude(x, fs, f0, spc):
    phase = 2.0 * np.pi * f0 * np.arange(x.size) / fs
    return order_spectrum(resample_to_angle(x, fs, phase, samples_per_cycle=spc))


def _max_in_bins(o, a, grid, step):
    idx = np.clip(np.round((o - grid[0]) / step).astype(int), -1, grid.size)
    out = np.interp(grid, o, a)
    ok = (idx >= 0) & (idx < grid.size)
    np.maximum.at(out, idx[ok], a[ok])
    return out


def amplitude_diff_text(h) -> str:
    """A harmonic's amplitude difference (recording over simulation) with its interval; an order that one side
    does not carry has no interval: what is read at its frequency is the noise, and the line is under it."""
    if h["detected_meas"] and h["detected_sim"]:
        return fmt_interval(h["amplitude_diff_db"], *h["amplitude_diff_db_ci"])
    if not h["detected_meas"] and h["detected_sim"]:
        return f"not detected (< {h['amplitude_diff_db']:.0f} dB)"
    if h["detected_meas"]:
        return "not in the simulation"
    return "not detected in either"


def counted_speed_note(v_sim, set_point) -> str:
    """The note on a simulation whose counted chain speed ``v_sim`` [m/s] is not its set speed (a drive that
    droops), "" where they agree; a down escalator's set speed is negative (the steps travel down): its
    magnitude is the speed, and both are printed to the same five digits."""
    sp = abs(float(set_point))
    if not sp or abs(v_sim - sp) <= 1e-6 * sp:
        return ""
    down = ", the steps travelling down" if float(set_point) < 0 else ""
    return f"simulated chain speed {v_sim:.5g} m/s (its links counted; set {sp:.5g} m/s{down})"


def compare(
    recording: xr.Dataset | str | os.PathLike[str],
    result: xr.Dataset | Scene | str | os.PathLike[str],
    *,
    channel: str | None = None,
    variable: str | None = None,
    n_harmonics: int = 5,
    band: tuple[float, float] | None = None,
    confidence: float = 0.95,
    freq_tol: float = 0.01,
    amp_tol_db: float = 3.0,
    pitch_tolerance: float = 0.005,
    duration: float | None = None,
    progress: bool = False,
    speed: float | None = None,
    speed_sigma: float | None = None,
    profile: Profile | None = None,
) -> Comparison:
    """Compare a recording with a simulation in the order domain.

    Parameters
    ----------
    recording : xarray.Dataset or path
        A recording (:func:`vibkit.read_recording`), continuous or in bursts.
    result : xarray.Dataset, Scene or path
        A simulation result, a scene (simulated here) or a result file.
    channel : str, optional
        Recording channel. Default: as ``vibkit pitch`` and the report choose (every vibration channel
        estimated, the one with the smallest sigma; a simulation's tensioner sensor).
    variable : str, optional
        Simulation variable (default: see :func:`matching_variable`).
    n_harmonics : int
        Harmonics of the link-pass compared.
    band : (float, float), optional
        Link-pass search band for both signals. [Hz]  Default: both speeds over 80-200 mm pitches.
    confidence : float
        Level of the intervals.
    freq_tol, amp_tol_db : float
        Scales of the score: relative frequency and amplitude [dB] differences that cost e^-1/2.
    pitch_tolerance : float
        Relative pitch difference still counted as the same chain (what the speed is known to).
    duration : float, optional
        Simulated time when ``result`` is a scene. [s]
    speed : float, optional
        The recording's chain (step) speed, measured [m/s]: its order domain and implied pitch use it.
        Default: the recording's stated ``chain_speed_m_s``, else the scene's nominal speed (with a note).
    speed_sigma : float, optional
        Its standard deviation [m/s]; it widens ``pitch_ratio_sigma``. None: not stated (the ratio's
        sigma is then the frequencies' part only, and a note says so).
    profile : vibkit.model.profile.Profile, optional
        The unit's escalator profile: the recording's link pass is decided with its sprocket's teeth, links per
        step, number of links and sensors, as ``vibkit pitch`` decides it (:func:`vibkit.diagnose.settings.resolve_settings`).

    Returns
    -------
    Comparison

    Raises
    ------
    NothingToCompare
        The recording carries no link pass (a ValueError).
    ValueError
        No matching variable, a signal too short for the band, bad options.

    Examples
    --------
    >>> res = vibkit.simulate("sim/leon.toml", duration=4.0)      # doctest: +SKIP
    >>> vibkit.compare(res, res).score                            # doctest: +SKIP
    1.0
    """
    return _compare(
        recording,
        result,
        channel=channel,
        variable=variable,
        n_harmonics=n_harmonics,
        band=band,
        confidence=confidence,
        freq_tol=freq_tol,
        amp_tol_db=amp_tol_db,
        pitch_tolerance=pitch_tolerance,
        duration=duration,
        progress=progress,
        speed=speed,
        speed_sigma=speed_sigma,
        profile=profile,
    )


def _compare(
    recording,
    result,
    *,
    channel,
    variable,
    n_harmonics,
    band,
    confidence,
    freq_tol,
    amp_tol_db,
    pitch_tolerance,
    duration,
    progress,
    speed,
    speed_sigma,
    profile,
):
    # the body of compare(): its parameters are rebound (a path becomes a Dataset), which the public
    # signature's annotations would not allow
    if not 0 < float(confidence) < 1:
        raise ValueError(f"confidence must lie in (0, 1), got {confidence!r}")
    if not float(pitch_tolerance) >= 0:
        raise ValueError(f"pitch_tolerance must be >= 0 (relative), got {pitch_tolerance!r}")
    if isinstance(recording, (str, os.PathLike)):
        recording = read_recording(recording)
    # the chain's numbers and each channel's sensor as every command resolves them (vibkit.diagnose.settings); the
    # band and the speed of the comparison are its own (both sides' speeds), decided below
    settings = resolve_settings(recording, speed=speed, speed_sigma=speed_sigma, profile=profile)
    result = as_result(result, duration=duration, progress=progress)
    # a simulation from rest, on either side, read where it counted its speed: after its start-up
    recording, cut_rec = counted_part(recording)
    result, cut_sim = counted_part(result)
    if channel is not None:
        channel = pick_channel(recording, channel)
    notes = [f"{side}: {cut}" for side, cut in (("recording", cut_rec), ("simulation", cut_sim)) if cut]
    v_nom = float(result.attrs.get("chain_speed_m_s", 0.0) or 0.0)
    v_sim = v_nom
    set_point = result.attrs.get("speed_set_point_m_s")
    if set_point is not None:
        # the result states the speed its chain ran at (its links counted), and the set speed beside it
        note = counted_speed_note(v_sim, float(set_point))
        if note:
            notes.append(note)
    elif "chain_speed" in result.data_vars and result["chain_speed"].dims == ("time",):
        # a result of vibkit 0.4.8 or older states the set speed: a controlled drive droops below it
        v_sim = float(np.abs(result["chain_speed"].values[result.sizes["time"] // 4 :]).mean())
        notes.append(f"simulated chain speed {v_sim:.5g} m/s (mean after the first quarter; set {v_nom:g} m/s)")
    if speed is not None:
        v_meas = float(speed)
        if not (math.isfinite(v_meas) and v_meas > 0):
            raise ValueError(f"speed must be a positive number of m/s, got {speed!r}")
    else:
        v_meas = float(speed_from_recording(recording)[0] or 0.0)
    speed_known = v_meas > 0
    if speed_sigma is not None and not (math.isfinite(float(speed_sigma)) and float(speed_sigma) >= 0):
        raise ValueError(f"speed_sigma must be >= 0 m/s, got {speed_sigma!r}")
    if not v_sim > 0:
        v_sim = v_meas
    if not v_meas > 0:
        v_meas = v_nom if v_nom > 0 else v_sim
        notes.append(
            f"the recording states no speed: the simulation's {v_meas:.4g} m/s assumed for its band and its link "
            "pass's pitch, which is not judged (give --speed)"
        )
    if band is None:
        if not v_sim > 0:
            raise ValueError("neither the result nor the recording states a chain speed; give band=(low, high) [Hz]")
        lo = min(v_sim, v_meas) / DEFAULT_PITCH_RANGE_M[1]
        hi = max(v_sim, v_meas) / DEFAULT_PITCH_RANGE_M[0]
        band = (lo, hi)
    # the shared decision first (that of `pitch` and `report`: every vibration channel, or the one asked for): no
    # comparison of a link pass that the recording does not carry
    decided = estimate_channels(
        recording,
        channel=channel,
        speed=v_meas if v_meas > 0 else 1.0,
        band=band,
        n_harmonics=n_harmonics,
        frequency_only=not v_meas > 0,
        teeth=settings.teeth,
        links_per_step=settings.links_per_step,
        n_links=settings.n_links,
        sensors=settings.sensors_by_channel,
    )
    if decided.best is None:
        raise NothingToCompare(
            f"{'channel ' + repr(channel) + ': ' if channel else ''}{decided.status}: {decided.reason}; "
            "nothing to compare"
        )
    dec = decided.best
    if channel is None:
        channel = dec.channel
        if len(decided.estimates) > 1:
            notes.append(f"channel {channel}: {decided.reason}")
    if variable is None:
        variable = matching_variable(result, recording, channel)
    elif variable not in result.data_vars or result[variable].dims != ("time",):
        raise ValueError(f"variable {variable!r} is not a time variable of the simulation result")
    sim = uniform_bursts(result, variable)
    if len(sim) != 1:
        raise ValueError(f"the simulation's {variable!r} must be continuous (one segment)")
    sim = sim[0]
    meas = uniform_bursts(recording, channel)
    runs = []
    for b in meas:
        try:
            runs.append(
                (
                    b,
                    compare_spectra(
                        sim.x,
                        sim.fs,
                        b.x,
                        b.fs,
                        band=band,
                        n_harmonics=n_harmonics,
                        confidence=confidence,
                        freq_tol=freq_tol,
                        amp_tol_db=amp_tol_db,
                    ),
                )
            )
        except ValueError as exc:
            notes.append(f"burst {b.segment} skipped: {exc}")
    if not runs:
        raise ValueError(f"no burst of channel {channel!r} could be compared ({'; '.join(notes)})")
    if len(runs) > 1:
        notes.append(
            f"{len(runs)} bursts compared one by one with the simulation and combined (inverse-variance weights)"
        )
    k = min(len(c.harmonics) for _, c in runs)
    z = float(scipy.stats.norm.ppf(1.0 - (1.0 - float(confidence)) / (2.0 * k)))
    rows, scores = [], []
    for i in range(k):
        hs = [c.harmonics[i] for _, c in runs]
        r_sig = [(h.frequency_ratio_ci[1] - h.frequency_ratio_ci[0]) / (2 * z) for h in hs]
        d_sig = [(h.amplitude_diff_db_ci[1] - h.amplitude_diff_db_ci[0]) / (2 * z) for h in hs]
        ratio, rs = _combine([h.frequency_ratio for h in hs], r_sig)
        diff, ds = _combine([h.amplitude_diff_db for h in hs], d_sig)
        f_meas, _ = _combine([h.frequency_meas_hz for h in hs], r_sig)
        a_meas, _ = _combine([h.amplitude_meas for h in hs], d_sig)
        det_s = bool(hs[0].detected_sim)
        det_m = bool(sum(h.detected_meas for h in hs) * 2 >= len(hs))
        ci = (ratio - z * rs, ratio + z * rs)
        mismatch = bool(det_s and det_m and not ci[0] <= 1.0 <= ci[1])
        rows.append(
            {
                "order": i + 1,
                "frequency_sim_hz": hs[0].frequency_sim_hz,
                "frequency_meas_hz": f_meas,
                "frequency_ratio": ratio,
                "frequency_ratio_sigma": rs,
                "frequency_ratio_ci": list(ci),
                "amplitude_sim": hs[0].amplitude_sim,
                "amplitude_meas": a_meas,
                "amplitude_diff_db": diff,
                "amplitude_diff_db_ci": [diff - z * ds, diff + z * ds],
                "detected_sim": det_s,
                "detected_meas": det_m,
                "frequency_mismatch": mismatch,
            }
        )
        if det_s or det_m:
            scores.append(
                math.exp(-0.5 * ((ratio - 1) / freq_tol) ** 2 - 0.5 * (diff / amp_tol_db) ** 2)
                if det_s and det_m
                else 0.0
            )
    _widen_by_parts(rows, dec, z, notes)
    scatter = _widen_by_order_scatter(rows, z, notes)
    score = float(np.mean(scores)) if scores else 0.0
    c0 = runs[0][1]
    # order spectra on a common axis; each fine spectrum is reduced by its maximum within every
    # coarse bin, so peaks survive whatever the record lengths
    spc = int(2 ** np.ceil(np.log2(2 * (k + 1) + 2)))
    spec_s = _order_amplitude(sim.x, sim.fs, c0.fundamental_sim_hz, spc)
    spec_m = [_order_amplitude(b.x, b.fs, c.fundamental_meas_hz, spc) for b, c in runs]
    step = max(o[1] - o[0] for o, _ in [spec_s] + spec_m)
    orders = np.arange(0.5, k + 0.5 + step / 2, step)
    a_sim = _max_in_bins(*spec_s, orders, step)
    a_meas = np.mean([_max_in_bins(o, a, orders, step) for o, a in spec_m], axis=0)
    floor = 1e-12 * max(a_sim.max(), a_meas.max(), 1e-300)
    lsd = float(np.sqrt(np.mean((20 * np.log10((a_meas + floor) / (a_sim + floor))) ** 2)))
    f_sim = float(c0.fundamental_sim_hz)
    f_meas = float(np.mean([c.fundamental_meas_hz for _, c in runs]))
    f_meas = rows[0]["frequency_meas_hz"] if rows else f_meas
    # pitch implied by each: v / f; ratio from the order-1 frequency ratio and the speeds
    fr, fr_sig = rows[0]["frequency_ratio"], rows[0]["frequency_ratio_sigma"]
    p_sim = v_sim / f_sim if v_sim > 0 else float("nan")
    p_meas = v_meas / f_meas if v_meas > 0 else float("nan")
    p_ratio = (v_meas / v_sim) / fr if v_sim > 0 else float("nan")
    rel_f = fr_sig / fr
    lp_meas, lp_sim = f_meas, f_sim
    f_counted = float(result.attrs.get("link_pass_frequency_hz", 0.0) or 0.0)
    if set_point is not None and v_sim > 0 and f_counted > 0:
        # the simulation states its chain's pitch: its counted speed over its counted link pass. Its spectrum's
        # fundamental is the link pass over the whole run, start-up and heads included, which differs from the
        # count by a few hundredths of a per cent: read against it, a model's own chain read 0.05 % off
        p_sim, lp_sim = v_sim / f_counted, f_counted
        # the recording's link pass as `vibkit pitch` reads it (the shared decision: the mean phase where the
        # frequency wanders, which the spectrum's fit weights unevenly over the record; a coasting simulation
        # compared with itself read 4e-4 off at 71 sigma), and its sigma; the simulation's pitch is exact
        # (its parts' scatter is in that sigma already; the orders' scatter widens it as it widens every ratio)
        if math.isfinite(dec.fundamental_hz) and dec.fundamental_hz > 0 and math.isfinite(dec.fundamental_sigma_hz):
            lp_meas, rel_f = dec.fundamental_hz, scatter * dec.fundamental_sigma_hz / dec.fundamental_hz
        p_meas = v_meas / lp_meas if v_meas > 0 else float("nan")
        p_ratio = p_meas / p_sim
    rel_v = float(speed_sigma) / v_meas if (speed_sigma is not None and v_meas > 0) else 0.0
    p_sig = p_ratio * math.hypot(rel_f, rel_v) if v_sim > 0 else float("nan")
    if speed_sigma is None and speed is not None:
        notes.append("speed uncertainty not stated: the pitch ratio's sigma is the frequencies' part only")
    z1 = float(scipy.stats.norm.ppf(0.5 + float(confidence) / 2))
    consistent = bool(v_sim > 0 and abs(p_ratio - 1) <= float(pitch_tolerance) + z1 * p_sig)
    if not speed_known:
        consistent = None  # a pitch at an assumed speed is the link passes' ratio: no verdict on the pitch
    elif v_sim > 0:
        verdict = "consistent" if consistent else "NOT consistent"
        notes.append(
            f"pitch implied by the recording {1000 * p_meas:.2f} mm vs the simulation {1000 * p_sim:.2f} mm "
            f"(pitch ratio {fmt_pm(p_ratio, p_sig)}): {verdict} within {100 * pitch_tolerance:g} % + {z1:.2f} sigma"
        )
    return Comparison(
        channel=channel,
        variable=variable,
        units=str(recording[channel].attrs.get("units", "1")),
        harmonics=rows,
        fundamental_sim_hz=f_sim,
        fundamental_meas_hz=float(f_meas),
        log_spectral_distance_db=lsd,
        score=score,
        rule=c0.rule,
        speed_sim_m_s=v_sim,
        speed_meas_m_s=v_meas,
        pitch_sim_m=p_sim,
        pitch_meas_m=p_meas,
        link_pass_sim_hz=float(lp_sim),
        link_pass_meas_hz=float(lp_meas),
        pitch_ratio=float(p_ratio),
        pitch_ratio_sigma=float(p_sig),
        pitch_consistent=consistent,
        pitch_tolerance=float(pitch_tolerance),
        confidence=float(confidence),
        orders=orders,
        order_amplitude_sim=a_sim,
        order_amplitude_meas=a_meas,
        signals={"sim": (sim.fs, sim.x), "meas": [(b.t0, b.fs, b.x) for b, _ in runs]},
        notes=notes,
        speed_meas_sigma_m_s=None if speed_sigma is None else float(speed_sigma),
    )
