"""Which link is worn: the link map of a tensioner recording and its decision.

The signal layer numbers every link-pass cycle by its link (:mod:`vibkit.signal.linkmap`) and tests
the per-link map (:mod:`vibkit.signal.linkscan`); this module gives it what only the model knows: the *signature* of one worn link
on the escalator, that is how one link of excess pitch changes the per-link map of the sensor.  On
the tensioner it is not one odd cycle but a pattern over the links that follow the worn one (its
wrap on the sprocket and on the lower head change the tensioner's mean by microns for ``Z / 2``
link passes each), so the scan fits that pattern at every link and flags the links it finds.

:func:`worn_link_signature` simulates the scene twice at the recording's speed (healthy, and with
link 1 ``excess`` longer, exact closure), one loop of settling cut off, and processes both runs
exactly as a recording (:mod:`vibkit.diagnose.link_signature`); :func:`find_worn_links` reads the recording's channel, tracks its link-pass
phase, builds the map and scans it.

Link numbers count, in the order the links pass, from the link at the sensor when the recording
starts (or the link marked at ``marker_s``), a link being at the sensor while it goes over the top of
the lower head (:func:`link_number_of`).  In the signature's run, roller 1 is at the top of the lower
head at ``t = 0`` (the scene's start) and links pass in decreasing model number, so the run's own
numbering is known and its worn link is row 0 of the signature.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from ..io.text.units import parse_unit
from ..model.scene import load_scene
from ..signal import find_fundamental
from ..signal.linkmap import (
    MIN_LOOPS,
    TooFewLoops,
    link_map,
    record_time_for_loops,
)
from ..signal.linkscan import count_drift, scan_links
from .channels import vibration_channels
from .decision import ELONGATION_WINDOW_PERCENT
from .link_signature import (
    DIRECTIONS,
    SAMPLES_PER_CYCLE,
    link_number_of,
    link_offset,
    link_phase,
    profile_scene_file,
    scene_direction,
    signature_error,
    worn_link_signature,
)
from .sensors import channel_sensor, is_acceleration_channel, is_tensioner_channel

__all__ = [
    "DEFAULT_FALSE_ALARM",
    "LinksResult",
    "find_worn_links",
    "link_number_of",
    "link_offset",
    "links_channel",
    "scene_direction",
    "profile_scene_file",
    "signature_error",
    "worn_link_signature",
    "TooFewLoops",
]

DEFAULT_FALSE_ALARM = 1e-2
#: a recording with fewer samples a link-pass cycle reads a worn link's excess low: a note says so
FEW_SAMPLES_PER_CYCLE = 10
#: excess pitch below which a link fitted by the signature is not flagged [m]: the simulated healthy chain of
#: the study's escalator, without noise, fits at most 0.0004 mm at any link, and 0.012 mm with a 1 % speed
#: wander (the tracked phase's error at the record's ends); with 1 um of noise over three loops the links that
#: pass the statistical threshold by chance read about 0.03 mm
MIN_EXCESS_M = 0.05e-3
#: excess pitch of the simulated worn link whose signature is fitted first [m]
SIGNATURE_EXCESS_M = 1e-3
#: a first fit above this many times ``SIGNATURE_EXCESS_M`` is fitted again with the signature of a link that long:
#: on a 90-link profile scene a 2 mm link fits as 1.69 mm with the 1 mm signature and as 2.05 mm with the 1.7 mm one
REFIT_ABOVE = 1.25
#: without a scene, more links flagged than this is a pattern, not worn links: a worn link moves the tensioner
#: over about half the sprocket's teeth of link passes, twice a loop (on the sprocket and on the lower head),
#: so each link's own cycle test flags dozens of neighbours; no number is then given
MAX_OWN_CYCLE_FLAGS = 3
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
    direction : str or None
        With a scene: "up" or "down", the way the chain ran as the signature was simulated.
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
    #: with a scene: the way the chain ran ("up" or "down"), as the signature was simulated; None without one
    direction: str | None = None

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
            "direction": self.direction,
            "status": self.status,
            "reason": self.reason,
            "flagged": self.flagged,
            "notes": self.notes,
        }


def links_channel(recording, channel=None, profile=None):
    """The channel :func:`find_worn_links` reads: ``channel``, else the first that is the tensioner's displacement
    (:func:`vibkit.diagnose.sensors.channel_sensor`, with the profile's sensors), else the first vibration channel."""
    chans = vibration_channels(recording)
    if channel is not None:
        return str(channel)
    for c in chans:
        if is_tensioner_channel(recording, c, profile):
            return c
    if not chans:
        along = [str(v) for v in recording.data_vars if recording[v].dims == ("time",) and v != "segment"]
        for v in along:
            vals = np.asarray(recording[v].values, dtype=float) if recording[v].dtype.kind in "biuf" else None
            if vals is not None and vals.size and np.nanmin(vals) == np.nanmax(vals):
                raise ValueError(
                    f"channel {v} is constant ({float(np.nanmin(vals)):g} in every sample): no vibration to map; "
                    "check that the sensor was connected and recording, or give another channel (--channel)"
                )
        names = f" (its columns: {', '.join(along)})" if along else ""
        raise ValueError(
            f"the recording has no vibration channel{names}: give the tensioner's displacement channel (--channel)"
        )
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


def _check_pitch(ch, f_lp, speed, nominal, resolution_hz=0.0):
    """Refuse a link pass whose pitch (speed / frequency) no chain of this nominal pitch has, within the frequency's
    resolution (``1 / span``: a 2 s recording's link pass is known to 0.5 Hz, too coarse to blame the speed)."""
    el = 100.0 * (speed / f_lp / nominal - 1.0)
    lo, hi = PITCH_WINDOW_PERCENT
    el_short = 100.0 * (speed / (f_lp + resolution_hz) / nominal - 1.0)
    el_long = 100.0 * (speed / max(f_lp - resolution_hz, 1e-12) / nominal - 1.0)
    if el_long >= lo and el_short <= hi:
        return
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
    direction=None,
    profile=None,
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
    direction : {"up", "down"}, optional
        With a scene: the way the chain ran while recorded (default: the scene's own, :func:`scene_direction`).
        The signature is simulated running that way; a down-running chain numbered with an up-running signature
        gets a wrong number.
    profile : vibkit.model.profile.Profile, optional
        The escalator's profile: its sensors say which channel is the tensioner's
        (:func:`vibkit.diagnose.sensors.channel_sensor`; without it the channel's quantity says).

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
    ch = links_channel(recording, channel, profile)
    if ch not in recording.data_vars:
        raise ValueError(f"no channel {ch!r} (channels: {', '.join(map(str, recording.data_vars))})")
    sensor = channel_sensor(recording, ch, profile)
    sensor_name = "tensioner" if sensor.is_tensioner else "other"  # the result's word for it
    if is_step_channel(recording, ch, profile):
        raise ValueError(f"channel {ch} (units {recording[ch].attrs['units']}): {STEP_REFUSAL}")
    n = int(n_links)
    if n < 2:
        raise ValueError(f"--links {n_links!r}: a chain has at least 2 links")
    speed = float(speed)
    da = recording[ch]
    t = np.asarray(recording.time.values, dtype=float)
    if np.issubdtype(recording.time.dtype, np.datetime64):
        t = (recording.time.values - recording.time.values[0]) / np.timedelta64(1, "s")
    _check_span(ch, t, n, speed, band, nominal_pitch)
    _check_gaps(file, recording, t, n, speed, band, nominal_pitch)
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
    span = (x.size - 1) / fs
    if span * f_lp < min(MIN_PITCH_CYCLES, MIN_LOOPS * n):
        # the link pass of a few cycles is too coarse to judge the pitch by (2 s: 2.5 Hz found for 3.75): too short,
        # not a wrong speed; the time to record from the nominal pitch when the profile gives it
        _too_few_loops(ch, span, n, f_lp if nominal_pitch is None else speed / float(nominal_pitch))
    if nominal_pitch is not None:
        _check_pitch(ch, f_lp, speed, float(nominal_pitch), resolution_hz=1.0 / span)
    if span * f_lp < MIN_LOOPS * n:
        _too_few_loops(ch, span, n, f_lp)
    notes = []
    if scene is not None:
        if sensor.signature is None:
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
    if scene is not None:
        direction = scene_direction(load_scene(scene)) if direction is None else direction
        if direction not in DIRECTIONS:
            raise ValueError(f"direction {direction!r}: expected one of {', '.join(DIRECTIONS)}")
    offset = 0.0 if scene is None else link_offset(scene, sensor=sensor.kind, speed=speed, fs=fs, direction=direction)
    lmap = link_map(
        x, fs, link_phase(x, fs, f_lp), n, samples_per_cycle=SAMPLES_PER_CYCLE, marker_s=marker_s, link_offset=offset
    )
    if scene is not None:
        _check_healthy(scene)
        sig, n_scene = worn_link_signature(scene, sensor=sensor.kind, speed=speed, fs=fs, direction=direction)
        if n_scene != n:
            raise ValueError(f"--links {n}: the scene {scene} has {n_scene} links")
        fit = functools.partial(
            _signature_scan, lmap, scene, sensor.kind, speed, fs, units_scale(da), false_alarm, direction
        )
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
            return _result(file, ch, sensor_name, speed, lmap, n, [], scan, excess, method, marker_s, notes,
                           status="inconclusive", reason=reason, direction=direction)  # fmt: skip
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
            return _result(file, ch, sensor_name, speed, lmap, n, [], scan, excess, method, marker_s, notes,
                           status="inconclusive", reason=reason, direction=direction)  # fmt: skip
    return _result(file, ch, sensor_name, speed, lmap, n, flagged, scan, excess, method, marker_s, notes,
                   direction=direction)  # fmt: skip


#: link-pass cycles under which the link pass found is too coarse to refuse a pitch by (its resolution, 1 / span,
#: is then over 5 % of it: a third of the pitch window)
MIN_PITCH_CYCLES = 20
#: fewer samples than this are refused before any analysis (a phase needs a few cycles of a few samples each)
MIN_SAMPLES = 16
#: a step between time stamps longer than this many median steps is a gap (as the readers split records at)
GAP_FACTOR = 5.0


def _loop_time(n, speed, band, nominal_pitch):
    """(shortest time one loop can take [s], what it is from): the nominal pitch's link pass, else the top of the
    search band."""
    if nominal_pitch is not None:
        return n * float(
            nominal_pitch
        ) / speed, f"{speed:g} m/s over the nominal {1e3 * float(nominal_pitch):g} mm pitch"
    hi = band[1] if band else speed / 0.08
    return n / hi, f"the link pass at most {hi:.4g} Hz" + ("" if band else f" at {speed:g} m/s (a pitch of 80 mm)")


def _check_span(ch, t, n, speed, band, nominal_pitch):
    """TooFewLoops, before any analysis, for a recording of too few samples to analyse (five samples were refused as
    an unnamed parameter's)."""
    if t.size >= MIN_SAMPLES:
        return
    span = float(t[-1] - t[0]) if t.size > 1 else 0.0
    loop, basis = _loop_time(n, speed, band, nominal_pitch)
    if nominal_pitch is None:
        lo = band[0] if band else speed / 0.2
        need = f"{math.ceil(MIN_LOOPS * loop + loop / n):.0f} to {math.ceil((MIN_LOOPS * n + 1) / lo):.0f} s"
        need += (
            " (the band's link pass)"
            if band
            else ", as the pitch is 80 to 200 mm (the profile's nominal pitch says which)"
        )
    else:
        need = f"{math.ceil(MIN_LOOPS * loop + loop / n):.0f} s ({basis})"
    raise TooFewLoops(
        f"channel {ch} has {t.size} samples over {span:.3g} s: a link map needs {MIN_LOOPS} loops of the chain's "
        f"{n} links; record at least {need}"
    )


def _too_few_loops(ch, span, n, f_lp):
    need = record_time_for_loops(n, f_lp)
    raise TooFewLoops(
        f"channel {ch}: {span:.1f} s at about {f_lp:.3g} Hz link pass covers {span * f_lp / n:.2f} loops of "
        f"the chain's {n} links; a link map needs {MIN_LOOPS} loops: record at least {math.ceil(need):.0f} s "
        f"({MIN_LOOPS} x {n} / {f_lp:.3g} Hz plus one link)"
    )


def _check_gaps(file, recording, t, n, speed, band, nominal_pitch):
    """ValueError naming the gaps (their time spans) in a recording's time stamps: a link map counts every link pass,
    and the links that passed in a gap are not known to one link (the speed there is not recorded), so the record is
    not resampled across it; the message says which segment could be analysed alone."""
    dt = np.diff(t)
    gap = dt > GAP_FACTOR * float(np.median(dt))
    if not gap.any():
        return
    where = np.flatnonzero(gap)
    spans = ", ".join(f"{t[i]:.2f}-{t[i + 1]:.2f} s" for i in where[:3]) + (" ..." if where.size > 3 else "")
    bounds = np.concatenate([[0], where + 1, [t.size]])
    longest = max(range(bounds.size - 1), key=lambda k: t[bounds[k + 1] - 1] - t[bounds[k]])
    a, b = t[bounds[longest]], t[bounds[longest + 1] - 1]
    loop, _ = _loop_time(n, speed, band, nominal_pitch)
    enough = (
        f"it covers at most {(b - a) / loop:.2f} loops, so cut it out and analyse it alone"
        if b - a >= MIN_LOOPS * loop
        else f"it covers at most {(b - a) / loop:.2f} loops, under the {MIN_LOOPS} a link map needs: record again without a break"
    )
    raise ValueError(
        f"{file}: the time stamps have {where.size} gap(s) (no samples {spans}): the links that passed in a gap cannot "
        f"be counted, so no link can be numbered across it; the longest part without a gap is {a:.2f}-{b:.2f} s, "
        f"{enough}"
    )


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


def _signature_scan(lmap, scene, kind, speed, fs, metres_per_unit, false_alarm, direction, excess):
    """The scan of ``lmap`` with the signature of a link ``excess`` [m] longer, and the signature's relative error."""
    sig, _ = worn_link_signature(scene, sensor=kind, speed=speed, fs=fs, excess=excess, direction=direction)
    err = signature_error(scene, sensor=kind, speed=speed, fs=fs, excess=excess, direction=direction)
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


def is_step_channel(recording, channel, profile=None):
    """Whether ``channel`` is an acceleration (a step accelerometer) or a sensor the profile puts on a step:
    refused, see ``STEP_REFUSAL``."""
    return is_acceleration_channel(recording, channel) or channel_sensor(recording, channel, profile).rides_step


def units_scale(da):
    """Metres per unit of a length channel (the signature is in metres): its unit's factor to SI, 1 for any other."""
    unit = parse_unit(str(da.attrs.get("units", "m")))
    return unit.factor if unit is not None and unit.quantity == "displacement" else 1.0
