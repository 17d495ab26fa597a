"""Which link is worn: the link map of a tensioner recording and its decision.

The signal layer numbers every link-pass cycle by its link (:mod:`vibkit.signal.linkmap`) and tests
the per-link map (:mod:`vibkit.signal.linkscan`); this module gives it what only the model knows: the *signature* of one worn link
on the escalator, that is how one link of excess pitch changes the per-link map of the sensor.  On
the tensioner it is not one odd cycle but a pattern over the links that follow the worn one (its
wrap on the sprocket and on the lower head change the tensioner's mean by microns for ``Z / 2``
link passes each), so the scan fits that pattern at every link and flags the links it finds.

:func:`worn_link_signature` simulates the scene twice at the recording's speed (healthy, and with
link 1 ``excess`` longer, exact closure), one loop of settling cut off, and processes both runs
exactly as a recording; :func:`find_worn_links` reads the recording's channel, tracks its link-pass
phase, builds the map and scans it.

Link numbers count, in the order the links pass, from the link at the sensor when the recording
starts (or the link marked at ``marker_s``), a link being at the sensor while it goes over the top of
the lower head (:func:`link_number_of`).  In the signature's run, roller 1 is at the top of the lower
head at ``t = 0`` (the scene's start) and links pass in decreasing model number, so the run's own
numbering is known and its worn link is row 0 of the signature.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass, field

import numpy as np

from ..analyses.simulation import simulate
from ..model.scene import load_scene
from ..signal import find_fundamental
from ..signal.linkmap import (
    MIN_LOOPS,
    TooFewLoops,
    canonical_phase,
    link_map,
    link_pass_phase,
    record_time_for_loops,
)
from ..signal.linkscan import count_drift, scan_links
from .channels import vibration_channels
from .decision import ELONGATION_WINDOW_PERCENT
from .sensors import is_tensioner_channel  # noqa: F401 (re-exported: its home is vibkit.diagnose.sensors)

__all__ = [
    "DEFAULT_FALSE_ALARM",
    "LinksResult",
    "find_worn_links",
    "link_number_of",
    "link_offset",
    "links_channel",
    "profile_scene_file",
    "signature_error",
    "worn_link_signature",
    "TooFewLoops",
]

DEFAULT_FALSE_ALARM = 1e-2
#: tracking bandwidth of the link-pass phase, as a fraction of the link-pass frequency
BANDWIDTH_FRACTION = 1.0 / 40.0
SAMPLES_PER_CYCLE = 16
#: a recording with fewer samples a link-pass cycle reads a worn link's excess low: a note says so
FEW_SAMPLES_PER_CYCLE = 10
#: excess pitch below which a link fitted by the signature is not flagged [m]: the simulated healthy chain of
#: the study's escalator, without noise, fits at most 0.0004 mm at any link, and 0.012 mm with a 1 % speed
#: wander (the tracked phase's error at the record's ends); with 1 um of noise over three loops the links that
#: pass the statistical threshold by chance read about 0.03 mm
MIN_EXCESS_M = 0.05e-3
#: loops (after one of settling) that the signature's runs average over
SIGNATURE_LOOPS = 2
#: excess pitch of the simulated worn link whose signature is fitted first [m]
SIGNATURE_EXCESS_M = 1e-3
#: a first fit above this many times ``SIGNATURE_EXCESS_M`` is fitted again with the signature of a link that long:
#: on a 90-link profile scene a 2 mm link fits as 1.69 mm with the 1 mm signature and as 2.05 mm with the 1.7 mm one
REFIT_ABOVE = 1.25
#: without a scene, more links flagged than this is a pattern, not worn links: a worn link moves the tensioner
#: over about half the sprocket's teeth of link passes, twice a loop (on the sprocket and on the lower head),
#: so each link's own cycle test flags dozens of neighbours; no number is then given
MAX_OWN_CYCLE_FLAGS = 3
#: the sensors the model gives a signature for: sensor -> the simulation's output
SENSORS = {"tensioner": "delta"}
#: units of a step accelerometer's channel (refused: see ``STEP_REFUSAL``)
ACCELERATION_UNITS = ("m/s^2", "m/s2", "m s-2", "mm/s^2", "g")
#: why a step accelerometer gives no link number (measured on the no-load scene, 0.5 m/s, exact closure:
#: benchmarks/bench_links_step.py)
STEP_REFUSAL = (
    "a step accelerometer gives no link number: the step rides the chain, so its signal is its own trip round "
    "the loop (0.015 m/s^2 r.m.s. on the study's escalator), which a 1 mm worn link changes by 0.004 m/s^2 at two "
    "places a loop; on the simulator those places move with the link's excess as much as with its number (about 13 links "
    "a millimetre), so a step cannot tell which link is worn from how much (the user guide's links page says "
    "more); record the tensioner's displacement, which sees every link at the same place (a step's accelerometer "
    "does show a flat roller under that step: vibkit ride)"
)


@dataclass(frozen=True)
class LinksResult:
    """Result of :func:`find_worn_links`.

    Attributes
    ----------
    file, channel, sensor : str
    speed_m_s, link_pass_hz : float
    n_links, loops : int
    flagged : list of dict
        Per flagged link: ``link`` (1-based), ``excess_pitch_mm`` and ``sigma_mm`` (the noise's part; with a
        scene, ``signature_relative_error`` is the worn-link signature's own error, relative), ``t`` (its
        statistic), ``loops`` (1-based loops whose own fit shows it); with a scene, ``alternatives``:
        the links where the signature fits nearly as well (the recording does not tell them from ``link``;
        empty when it does).
    threshold, false_alarm, dof : float
    statistic : ndarray (n_links,)
        Absolute t of every link before any flagged link's change is taken out (the map the report draws).
    residual_statistic : ndarray (n_links,) or None
        With a scene: the same once the flagged links' change is taken out (what decides that no other link is
        flagged).
    excess_mm : ndarray (n_links,)
        Fitted excess pitch at every link. [mm]
    method : str
    marker_s : float or None
    notes : list of str
    """

    file: str
    channel: str
    sensor: str
    speed_m_s: float
    link_pass_hz: float
    n_links: int
    loops: int
    flagged: list
    threshold: float
    false_alarm: float
    dof: float
    statistic: np.ndarray
    excess_mm: np.ndarray
    method: str
    marker_s: float | None = None
    notes: list = field(default_factory=list)
    #: "ok" (the links were scanned), or "inconclusive" (deviations no link number can be given for)
    status: str = "ok"
    reason: str = ""
    residual_statistic: np.ndarray | None = None

    def as_dict(self):
        return {
            "file": self.file,
            "channel": self.channel,
            "sensor": self.sensor,
            "speed_m_s": self.speed_m_s,
            "link_pass_hz": self.link_pass_hz,
            "n_links": self.n_links,
            "loops": self.loops,
            "false_alarm": self.false_alarm,
            "threshold": self.threshold,
            "dof": self.dof,
            "method": self.method,
            "marker_s": self.marker_s,
            "status": self.status,
            "reason": self.reason,
            "flagged": self.flagged,
            "notes": self.notes,
        }


def link_phase(x, fs, f_lp):
    """The link-pass phase of ``x`` near ``f_lp`` [Hz], by demodulation. [rad]"""
    return link_pass_phase(x, fs, f_lp, bandwidth_hz=f_lp * BANDWIDTH_FRACTION)


def link_number_of(model_link, links_passed, n_links):
    """Number (1-based, in passing order from the link at the sensor) of the scene's link
    ``model_link`` after ``links_passed`` links have passed since the scene's start.

    A link is at the sensor while it goes over the top of the lower head, from the arrival there of one of
    its rollers to the other's.  At the scene's start roller 1 is at the top and rollers arrive in
    decreasing number (2, 1, n, n - 1 ...): while ``j`` to ``j + 1`` links have passed, the link from roller
    ``(-j - 1) mod n + 1`` to the next is at the sensor (link n, from roller n to roller 1, at first)."""
    at_sensor = (-1 - int(math.floor(links_passed))) % n_links  # 0-based model link at the sensor
    return (at_sensor - (model_link - 1)) % n_links + 1


def _scene_with(scene, *, speed, worn=None):
    chain = scene.chain if worn is None else dataclasses.replace(scene.chain, worn_links=(worn,))
    effects = dict(scene.effects)
    if "motor" in effects:
        effects["motor"] = dataclasses.replace(effects["motor"], speed=float(speed))
    outputs = dict(scene.outputs, variables=tuple(sorted(set(SENSORS.values()) | {"sprocket_angle"})))
    # both runs on the closure walked run by run (exact, and what a worn chain takes): the difference is the
    # worn link's, not the closures'
    return dataclasses.replace(scene, chain=chain, effects=effects, outputs=outputs).with_solver(closure="runs")


@functools.lru_cache(maxsize=32)
def _run_map_cached(scene_path, sensor, speed, fs, samples_per_cycle, excess, loops):
    """One run's mean per-link shape (link 1 ``excess`` [m] longer; 0: healthy) and the row of its link 1."""
    scene = load_scene(scene_path)
    if scene.analysis != "forward" or scene.run.start != 0.0:
        raise ValueError(
            f"{scene_path}: the worn link's signature needs a forward scene that starts with roller 1 at the top "
            "of the lower head ([run] start = 0), so that its links can be numbered"
        )
    n = scene.chain.n_rollers
    pitch = scene.chain.link_pitch
    f_lp = speed / pitch
    settle = n / f_lp + 5.0  # one loop and the start-up
    duration = settle + (loops * n + 3) / f_lp
    worn = None if excess == 0.0 else (1, pitch + excess)
    ds = simulate(_scene_with(scene, speed=speed, worn=worn), duration=duration, progress=False)
    t = ds.time.values
    keep = t >= settle
    tx = np.arange(t[keep][0], t[-1], 1.0 / fs)
    x = np.interp(tx, t, ds[SENSORS[sensor]].values)
    ph = link_phase(x, fs, f_lp)
    # links passed since the start, on the sprocket; a roller is at the sensor where it is a whole number: where
    # that falls in the signal's cycle (its fundamental's peak is 0) is the offset that numbers the links of the
    # map, and of a recording of this escalator, by the link at the sensor rather than by the signal's cycle
    passed = scene.sprocket.teeth * np.abs(np.interp(tx, t, ds.sprocket_angle.values) - ds.sprocket_angle.values[0])
    passed /= 2 * np.pi
    cyc = canonical_phase(x, ph) / (2 * np.pi)
    lag = 2 * np.pi * (cyc - passed)
    offset = float(np.angle(np.mean(np.exp(1j * lag))) / (2 * np.pi)) % 1.0
    lmap = link_map(x, fs, ph, n, samples_per_cycle=samples_per_cycle, link_offset=offset)
    # the map's first link as the map counts it (between the link boundaries the offset places in the signal),
    # in links passed on the sprocket: at a start on a boundary the sprocket's count alone may differ by one
    # (5 s at 4.8 Hz is 24 links: every number of a 120-link scene came out one too high)
    whole = round(float(np.mean(cyc - offset - passed)))  # the phase's whole cycles before the sprocket's count
    first = math.floor(cyc[0] - offset) - whole + 0.5
    return lmap.mean_shape, link_number_of(1, first, n) - 1, n, offset


def _cache_key(scene_path, sensor, speed, fs, samples_per_cycle):
    """The cached runs' key: the same scene, speed and rate (rounded) are one run, whoever asks."""
    return (str(scene_path), sensor, round(float(speed), 9), round(float(fs), 6), int(samples_per_cycle))


def _signature_cached(scene_path, sensor, speed, fs, samples_per_cycle, excess, loops):
    healthy, _, n, _ = _run_map_cached(scene_path, sensor, speed, fs, samples_per_cycle, 0.0, loops)
    worn, row, _, _ = _run_map_cached(scene_path, sensor, speed, fs, samples_per_cycle, excess, loops)
    return np.roll(worn - healthy, -row, axis=0), n


def link_offset(scene_path, *, sensor="tensioner", speed, fs, samples_per_cycle=SAMPLES_PER_CYCLE):
    """Where a roller reaches the sensor in the signal's link-pass cycle of the scene's healthy chain, as a fraction of
    a cycle after the fundamental's peak (:func:`vibkit.signal.linkmap.link_map`'s ``link_offset``): with it a
    recording of this escalator numbers its links from the link at the sensor when it starts (or the marked link),
    as the signature numbers them, wherever the recording starts within a link's passage."""
    return _run_map_cached(*_cache_key(scene_path, sensor, speed, fs, samples_per_cycle), 0.0, SIGNATURE_LOOPS)[3]


def worn_link_signature(scene_path, *, sensor="tensioner", speed, fs, samples_per_cycle=SAMPLES_PER_CYCLE, excess=1e-3):
    """The change of the per-link map that one link ``excess`` [m] longer makes, row 0 that link.

    Parameters
    ----------
    scene_path : str or Path
        A forward scene of the escalator (its chain, sprocket, guide and motor).
    sensor : {"tensioner"}
    speed : float
        Chain speed of the recording (the scene's motor runs at it). [m/s]
    fs : float
        The recording's sample rate (the runs are sampled at it). [Hz]
    samples_per_cycle : int, optional
    excess : float, optional
        Excess pitch of the simulated worn link. [m]

    Returns
    -------
    signature : ndarray (n_links, samples_per_cycle)
    n_links : int
    """
    if sensor not in SENSORS:
        raise ValueError(f"sensor {sensor!r}: the model gives a worn link's signature for {', '.join(SENSORS)} only")
    return _signature_cached(
        *_cache_key(scene_path, sensor, speed, fs, samples_per_cycle), float(excess), SIGNATURE_LOOPS
    )


def signature_error(scene_path, *, sensor="tensioner", speed, fs, samples_per_cycle=SAMPLES_PER_CYCLE, excess=1e-3):
    """The signature's relative error, as the model shows it: ``|S(e / 2) / (e / 2) - S(e) / e| / |S(e) / e|``,
    ``S(e)`` the signature of a link ``e`` longer (each without the mean over its links, as the scan fits it).
    A linear, reproducible signature gives 0; the study's 159-link scene at 0.5 m/s gives 0.15 at 1 mm."""
    key = _cache_key(scene_path, sensor, speed, fs, samples_per_cycle)
    full, _ = _signature_cached(*key, float(excess), SIGNATURE_LOOPS)
    half, _ = _signature_cached(*key, float(excess) / 2.0, SIGNATURE_LOOPS)
    full = (full - full.mean(axis=0)) / float(excess)
    half = (half - half.mean(axis=0)) / (float(excess) / 2.0)
    return float(np.sqrt(np.sum((half - full) ** 2) / np.sum(full * full)))


def links_channel(recording, channel=None):
    """The channel :func:`find_worn_links` reads: ``channel``, else the first in a length unit (a tensioner
    displacement), else the first vibration channel."""
    chans = vibration_channels(recording)
    if channel is not None:
        return str(channel)
    for c in chans:
        if str(recording[c].attrs.get("units", "")) in ("m", "mm", "um"):
            return c
    if not chans:
        raise ValueError("the recording has no vibration channel")
    return chans[0]


#: the pitches a link map accepts, in % from the nominal: the elongations a chain can have
#: (:data:`vibkit.diagnose.decision.ELONGATION_WINDOW_PERCENT`) widened by the 5 % by which an escalator's speed
#: may differ from its rated one (EN 115-1)
PITCH_WINDOW_PERCENT = (ELONGATION_WINDOW_PERCENT[0] - 5.0, ELONGATION_WINDOW_PERCENT[1] + 5.0)


def _check_healthy(scene):
    """Refuse a scene with worn links: the signature is one worn link's change of the escalator's chain without it."""
    worn = load_scene(scene).chain.worn_links
    if worn:
        raise ValueError(
            f"the scene {scene} has worn links ({', '.join(str(k) for k, _ in worn)}): the worn link's signature is "
            "simulated from the escalator's chain without them; give its scene without worn_links (a worn scene "
            "halves the excess read and moves the link found)"
        )


def _check_pitch(ch, f_lp, speed, nominal):
    """Refuse a link pass whose pitch (speed / frequency) no chain of this nominal pitch has."""
    el = 100.0 * (speed / f_lp / nominal - 1.0)
    lo, hi = PITCH_WINDOW_PERCENT
    if not lo <= el <= hi:
        raise ValueError(
            f"channel {ch}: the link pass found, {f_lp:.4g} Hz, gives a link pitch of {1e3 * speed / f_lp:.1f} mm at "
            f"{speed:g} m/s, {el:+.0f} % from the nominal {1e3 * nominal:g} mm (a chain is {lo:+g} to {hi:+g} %, "
            "speed tolerance included): check the speed (in m/s, not km/h) and the nominal pitch; no link map"
        )


def find_worn_links(
    recording,
    *,
    speed,
    n_links,
    channel=None,
    scene=None,
    marker_s=None,
    false_alarm=DEFAULT_FALSE_ALARM,
    band=None,
    min_excess=MIN_EXCESS_M,
    file="<recording>",
    nominal_pitch=None,
):
    """The links of a chain whose pitch departs from the others', from a tensioner recording.

    Parameters
    ----------
    recording : xarray.Dataset
        As :func:`vibkit.read_recording` gives (dimension ``time``).
    speed : float
        Chain speed. [m/s]
    n_links : int
        Links in the chain.
    channel : str, optional
        Default: the first channel in a length unit (a tensioner displacement).
    scene : str or Path, optional
        The escalator's forward scene, for the worn link's signature. Without one, each link's own
        cycle is tested (its mean level and duration): a deviation is found and numbered but the
        tensioner spreads it over the links that follow, and no excess pitch is given.
    marker_s : float, optional
        Time at which a marked link passed the sensor: it is link 1. [s]
    false_alarm : float, optional
        Probability that a chain without a deviating link gets any flag.
    band : (float, float), optional
        Search band of the link-pass frequency (default speed / 200 mm to speed / 80 mm). [Hz]
    min_excess : float, optional
        With a scene: a link passing the threshold is flagged only when its excess pitch is at least
        this. [m]
    file : str
        The recording's name, for messages.
    nominal_pitch : float, optional
        The chain's nominal pitch [m]: the link pass found must then give a pitch within the elongations a
        chain can have, widened by the escalator standard's 5 % speed tolerance (``PITCH_WINDOW_PERCENT``),
        or the map is refused (a speed in km/h, a harmonic taken for the link pass).

    Returns
    -------
    LinksResult

    Raises
    ------
    TooFewLoops
        The recording covers fewer than two loops (the message says how long to record).
    ValueError
        A bad channel, no link pass found; an acceleration channel (a step accelerometer: its signal is its own trip
        round the loop, which only a model could subtract, ``STEP_REFUSAL``).
    """
    ch = links_channel(recording, channel)
    if ch not in recording.data_vars:
        raise ValueError(f"no channel {ch!r} (channels: {', '.join(map(str, recording.data_vars))})")
    if is_step_channel(recording, ch):
        raise ValueError(f"channel {ch} (units {recording[ch].attrs['units']}): {STEP_REFUSAL}")
    n = int(n_links)
    if n < 2:
        raise ValueError(f"--links {n_links!r}: a chain has at least 2 links")
    speed = float(speed)
    da = recording[ch]
    t = np.asarray(recording.time.values, dtype=float)
    if np.issubdtype(recording.time.dtype, np.datetime64):
        t = (recording.time.values - recording.time.values[0]) / np.timedelta64(1, "s")
    fs = (t.size - 1) / (t[-1] - t[0])
    x = np.asarray(da.values, dtype=float)
    x = np.interp(np.arange(t[0], t[-1], 1.0 / fs), t, x)  # uniform samples
    ok = np.isfinite(x)
    if not ok.all():
        raise ValueError(f"channel {ch}: {np.count_nonzero(~ok)} missing samples; the link map needs a whole recording")
    _check_rate(file, fs, speed, band)
    band = band or (speed / 0.2, speed / 0.08)
    fund = find_fundamental(x, fs, band=band)
    f_lp = fund.frequency_hz
    if nominal_pitch is not None:
        _check_pitch(ch, f_lp, speed, float(nominal_pitch))
    span = (x.size - 1) / fs
    if span * f_lp < MIN_LOOPS * n:
        need = record_time_for_loops(n, f_lp)
        raise TooFewLoops(
            f"channel {ch}: {span:.1f} s at about {f_lp:.3g} Hz link pass covers {span * f_lp / n:.2f} loops of "
            f"the chain's {n} links; a link map needs {MIN_LOOPS} loops: record at least {math.ceil(need):.0f} s "
            f"({MIN_LOOPS} x {n} / {f_lp:.3g} Hz plus one link)"
        )
    notes = []
    sensor = "tensioner" if str(da.attrs.get("units", "")) in ("m", "mm", "um") else "other"
    if scene is not None:
        if sensor != "tensioner":
            units = str(da.attrs.get("units", "") or "unknown")
            hint = (
                "; if it is one, give its unit (--units mm)"
                if units.lower() in ("unknown", "", "1", "counts", "none")
                else ""
            )
            raise ValueError(
                f"channel {ch} (units {units!r}) is not a tensioner displacement: the worn link's signature is "
                "known for the tensioner only (a step sensor rides the loop, and its own path dominates its "
                f"per-link pattern){hint}"
            )
    if fs / f_lp < FEW_SAMPLES_PER_CYCLE:
        notes.append(
            f"{fs / f_lp:.1f} samples per link-pass cycle: a worn link's sharp part falls between them and its excess "
            "is read low (a stranger's 1 mm link read 0.75 +- 0.10 mm at 5.6 samples a cycle, 0.99 +- 0.01 at 11); "
            f"record at {5 * math.ceil(12 * f_lp / 5)} Hz or more"
        )
    # with a scene the links are counted between the instants a roller reaches the sensor, not between the
    # signal's cycle boundaries: numbers as the signature gives them wherever the recording starts
    offset = 0.0 if scene is None else link_offset(scene, sensor="tensioner", speed=speed, fs=fs)
    lmap = link_map(
        x, fs, link_phase(x, fs, f_lp), n, samples_per_cycle=SAMPLES_PER_CYCLE, marker_s=marker_s, link_offset=offset
    )
    if scene is not None:
        _check_healthy(scene)
        sig, n_scene = worn_link_signature(scene, sensor="tensioner", speed=speed, fs=fs)
        if n_scene != n:
            raise ValueError(f"--links {n}: the scene {scene} has {n_scene} links")
        fit = functools.partial(_signature_scan, lmap, scene, speed, fs, units_scale(da), false_alarm)
        scan, err = fit(SIGNATURE_EXCESS_M)
        used = SIGNATURE_EXCESS_M
        top = max(scan.flagged, key=lambda f: f.t, default=None)
        if top is not None and abs(top.amplitude) > REFIT_ABOVE * SIGNATURE_EXCESS_M:
            # the signature is not linear in the excess above about 1 mm: fit again with the signature of a link
            # as long as the first fit found (to 0.1 mm), and keep that fit when it explains more of the map
            again = round(1e3 * abs(top.amplitude), 1) * 1e-3
            scan2, err2 = fit(again)
            top2 = max(scan2.flagged, key=lambda f: f.t, default=None)
            if top2 is not None and top2.t > top.t:
                scan, err, used = scan2, err2, again
        flagged = [
            {
                "link": f.link,
                "alternatives": list(f.alternatives),
                "excess_pitch_mm": 1e3 * f.amplitude,
                "sigma_mm": 1e3 * f.sigma,
                # the sigma is the noise's part; the signature's own (model) error, relative, beside it
                "signature_relative_error": err,
                "t": f.t,
                "loops": list(f.loops),
            }
            for f in scan.flagged
            if abs(f.amplitude) >= min_excess
        ]
        small = len(scan.flagged) - len(flagged)
        if small:
            notes.append(
                f"{small} link(s) passed the threshold with an excess under {1e3 * min_excess:g} mm "
                "(--min-excess): not flagged"
            )
        if flagged:
            notes.append(
                f"+- is the noise's part only: the signature's shape changes with the excess (relative error {err:.2f}), "
                "which can move the excess read by up to that share of it"
            )
        if any(f["alternatives"] for f in flagged):
            notes.append(
                "a link given as 'A or B': the signature fits at B nearly as well as at A (within what the noise "
                f"and the signature's own error, {100 * err:.0f} %, allow); the recording cannot tell them apart: "
                "mark a link (--marker) and look at both"
            )
        excess = 1e3 * scan.amplitude
        method = (
            f"worn-link signature of the scene ({1e3 * used:g} mm, relative error {err:.2f}), "
            f"excess at least {1e3 * min_excess:g} mm"
        )
        drift = count_drift(scan.peaks, n) if flagged else 0
        if drift:
            # one worn link is at one number every loop; counted with the wrong number of links it moves by the
            # difference from one loop to the next
            reason = (
                f"the deviation peaks at another link in every loop (links {', '.join(map(str, scan.peaks))} in loops "
                f"1-{len(scan.peaks)}): counted as {n} links, a worn link moves by the difference from loop to loop; "
                f"this chain has about {n + drift} links: check --links (or the profile's chain.n_links); no link "
                "number"
            )
            return _result(file, ch, sensor, speed, lmap, n, [], scan, excess, method, marker_s, notes,
                           status="inconclusive", reason=reason)  # fmt: skip
    else:
        scan = scan_links(lmap, false_alarm=false_alarm)
        flagged = [
            {
                "link": f.link,
                "feature": f.feature,
                "excess_pitch_mm": 1e3 * f.amplitude * speed if f.feature == "duration" else None,
                "sigma_mm": 1e3 * f.sigma * speed if f.feature == "duration" else None,
                "t": f.t,
                "loops": list(f.loops),
            }
            for f in scan.flagged
        ]
        excess = np.full(n, np.nan)
        method = "each link's own cycle (level and duration)"
        if scan.unsteady:
            notes.append(
                f"link(s) {', '.join(map(str, scan.unsteady))} deviated in some loops only (their own loop-to-loop "
                "scatter is far beyond the other links'): a transient such as the start-up, not a worn link, which "
                "is the same every loop; not flagged"
            )
        notes.append(
            "without --scene each link's own cycle is tested: a worn link shows on the tensioner as a pattern "
            "over the links that follow it, so several neighbouring numbers may be flagged"
        )
        if len(flagged) > MAX_OWN_CYCLE_FLAGS:
            reason = (
                f"{len(flagged)} of {n} links deviate beyond the threshold: a pattern over many links (a worn link "
                "moves the tensioner over the links that follow it), not a link number; give the escalator's "
                "scene (--scene or --escalator) so that the worn link's signature is fitted"
            )
            return _result(file, ch, sensor, speed, lmap, n, [], scan, excess, method, marker_s, notes,
                           status="inconclusive", reason=reason)  # fmt: skip
    return _result(file, ch, sensor, speed, lmap, n, flagged, scan, excess, method, marker_s, notes)


def _check_rate(file, fs, speed, band):
    """ValueError in the reader's terms when the recording's Nyquist frequency is under the search band's top
    (the band given, else the speed's: speed / 200-80 mm): most often a time column in the wrong unit."""
    lo, hi = band if band else (speed / 0.2, speed / 0.08)
    if not fs / 2 < hi:
        return
    rate = f"the recording's sample rate {fs:.4g} Hz (Nyquist frequency {fs / 2:.4g} Hz)"
    if band:
        raise ValueError(
            f"{file}: band {lo:.4g}-{hi:.4g} Hz reaches above the Nyquist frequency {fs / 2:.4g} Hz of the "
            f"recording (sample rate {fs:.4g} Hz); lower the band, or check the time column "
            "and its unit (--time-unit)"
        )
    raise ValueError(
        f"{file}: {rate} cannot show a link pass at {speed:g} m/s (speed / 200-80 mm: {lo:.4g}-{hi:.4g} Hz); "
        "check the time column and its unit (--time-unit), or give --sample-rate"
    )


def _signature_scan(lmap, scene, speed, fs, metres_per_unit, false_alarm, excess):
    """The scan of ``lmap`` with the signature of a link ``excess`` [m] longer, and the signature's relative error."""
    sig, _ = worn_link_signature(scene, sensor="tensioner", speed=speed, fs=fs, excess=excess)
    err = signature_error(scene, sensor="tensioner", speed=speed, fs=fs, excess=excess)
    scan = scan_links(lmap, signature=sig / metres_per_unit, scale=excess, false_alarm=false_alarm, signature_error=err)
    return scan, err


def _result(file, ch, sensor, speed, lmap, n, flagged, scan, excess, method, marker_s, notes, **kw):
    return LinksResult(
        file=str(file),
        channel=ch,
        sensor=sensor,
        speed_m_s=speed,
        link_pass_hz=lmap.link_pass_hz,
        n_links=n,
        loops=lmap.loops,
        flagged=flagged,
        threshold=scan.threshold,
        false_alarm=scan.false_alarm,
        dof=scan.dof,
        statistic=scan.statistic,
        residual_statistic=getattr(scan, "residual", None),
        excess_mm=excess,
        method=method,
        marker_s=marker_s,
        notes=notes,
        **kw,
    )


def is_step_channel(recording, channel):
    """Whether ``channel`` is an acceleration (a step accelerometer): refused, see ``STEP_REFUSAL``."""
    return str(recording[channel].attrs.get("units", "")) in ACCELERATION_UNITS


def profile_scene_file(profile):
    """An escalator profile's forward scene as a file (the signature is simulated from a scene file and cached by
    its path, speed and rate): written once per profile text into the user's temporary folder."""
    import hashlib
    import os
    import tempfile
    from pathlib import Path

    text = profile.scene_text("forward")
    digest = hashlib.sha256(text.encode()).hexdigest()[:16]
    path = Path(tempfile.gettempdir()) / f"vibkit-links-{digest}.toml"
    if not path.exists():
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, path)
    return str(path)


def units_scale(da):
    """Metres per unit of a length channel (the signature is in metres)."""
    return {"m": 1.0, "mm": 1e-3, "um": 1e-6}.get(str(da.attrs.get("units", "m")), 1.0)
