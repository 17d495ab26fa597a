"""Everything the report's pages draw, computed once before the first page: :class:`ReportContext`.

:func:`analyse` reads the recording, resolves speed and nominal pitch, estimates the link-pass frequency
and the pitch (:mod:`vibkit.diagnose.pitch`), simulates and compares a scene when one is given
(:mod:`vibkit.diagnose.comparison`), finds spikes (Hampel events on the residual after the link-pass
family) and suspected clipping, and builds the JSON summary.  The page functions only draw.
"""

from __future__ import annotations

import dataclasses
import datetime as _dt
import os
from dataclasses import dataclass, field

import numpy as np

from ...io import RecordingError, read_recording, source_name
from ...io.channels import own_samples, with_component
from ...model.profile_scene import geometry_note, link_count
from ...model.scene import Scene, SceneError, load_scene
from ...runtime.dates import check_date, parse_iso_date
from ...runtime.report_options import ReportOptions, takes_report_options
from ...signal import hampel_events, link_pass_estimate
from ...signal.bursts import uniform_bursts
from ..channels import estimate_channels
from ..comparison import compare
from ..kept_simulation import simulate_kept
from ..knock import ride_knock, step_rollers_of
from ..links import TooFewLoops, find_worn_links, profile_scene_file
from ..pitch import pick_channel
from ..ride import _AXIS_RE, ride_quality_from_recording, ride_quality_from_simulation
from ..ride_simulation import with_ride_outputs
from ..rounding import fmt_band
from ..segment import cut_recording
from ..settings import resolve_settings, scene_is_unit
from .common import report_date

__all__ = ["ReportContext", "analyse"]


@dataclass
class ReportContext:
    """What :func:`analyse` found, and the options the pages print.

    Attributes
    ----------
    recording : str
        The recording's path as given.
    rec : xarray.Dataset
        The recording as :func:`vibkit.read_recording` read it.
    channel, units : str
    scene : Scene or None
    speed, speed_sigma : float or None
        The run's one chain speed and its sigma [m/s] (``run_speed``); sigma None: not stated.
    run_speed : ResolvedSpeed
        That speed with its sources (:func:`vibkit.diagnose.speed.resolve_speed`): the option, else the
        escalator profile's, else the recording's, else the scene's.  Every page and the comparison use it.
    profile : Profile or None
        The escalator profile (the unit that page 1 names).
    nominal_pitch : float or None
        Resolved nominal pitch (the option, else the profile's, else the scene's) [m].
    limits : tuple of float
        Elongation limits [%].
    band : (float, float) or None
        Link-pass search band as given [Hz].
    duration : float or None
        Simulated time as given [s].
    hampel_half_window_s, hampel_false_alarm_rate : float
    bursts : list
        Uniform bursts of the channel (:func:`vibkit.signal.bursts.uniform_bursts`).
    pitch : PitchEstimate or None
        None without a speed or without a detected link-pass.
    f0 : float
        Link-pass frequency [Hz]; without a detection the search band's geometric centre (unmarked).
    found : bool
        A link-pass was detected.
    notes : list of str
        Decisions shown on the verdict page.
    result : simulation result or None
    comparison : Comparison or None
    events : list of (time_s, value, HampelEvent)
    rms, p2p : float
    clip_n : int
    clipped : bool
    date : datetime.datetime
        The report's date (now, or ``SOURCE_DATE_EPOCH``).
    summary : dict
    measurement_date : datetime.datetime or None
        When the recording was made: the ``date`` option, else the file's start time, else None.
    measurement_date_source : str
        Where it came from.
        The verdict table as a JSON-ready dict.
    """

    recording: str
    rec: object
    channel: str
    units: str
    scene: object
    speed: float | None
    speed_sigma: float | None
    nominal_pitch: float | None
    limits: tuple
    band: tuple | None
    duration: float | None
    hampel_half_window_s: float
    hampel_false_alarm_rate: float
    bursts: list
    pitch: object
    f0: float
    found: bool
    notes: list
    result: object
    comparison: object
    events: list
    rms: float
    p2p: float
    clip_n: int
    clipped: bool
    date: _dt.datetime
    summary: dict = field(default_factory=dict)
    measurement_date: _dt.datetime | None = None
    measurement_date_source: str = ""
    ride: list = field(default_factory=list)  # ("recording" | "simulation", RideQuality), one page each
    run_speed: object = None
    profile: object = None
    links: object = None  # LinksResult: the link map, when a tensioner recording covers two loops of the scene's chain
    links_note: str = ""  # why the links were not scanned (page 1 says it), empty when they were
    links_per_step: int = 3  # the step pass is the link pass over it (order spectrum, hypotheses)
    ride_absent: list = field(default_factory=list)  # why a ride page (recording, simulation) is not drawn
    comparison_absent: str = ""  # why there is no comparison with a simulation (page 1 says it)
    spikes_expected: float = float("nan")  # Hampel events that chance alone gives on these samples

    @property
    def unit_kind(self) -> str:
        """``"moving walk"`` where the profile describes one (``geometry.length``), else ``"escalator"``."""
        return getattr(self.profile, "kind", None) or "escalator"

    @property
    def unit_text(self) -> str:
        """The unit measured, as page 1 names it: the profile's identity, else how to name it."""
        p = self.profile
        if p is None:
            return "unit not named: --escalator FILE (an escalator profile)"
        parts = [str(getattr(p, "unit", "") or "")]
        for key in ("site", "description"):
            v = str(getattr(p, key, "") or "")
            if v:
                parts.append(v)
        return ", ".join(x for x in parts if x)

    @property
    def date_fixed(self) -> bool:
        """The report's date comes from ``SOURCE_DATE_EPOCH``."""
        return bool(os.environ.get("SOURCE_DATE_EPOCH"))

    @property
    def measurement_date_text(self) -> str:
        if self.measurement_date is None:
            return "not stated in the file (give --date)"
        d = self.measurement_date
        zone = "" if "time zone not stated" in self.measurement_date_source else " UTC"
        text = (
            d.strftime("%Y-%m-%d") if (d.hour, d.minute, d.second) == (0, 0, 0) else d.strftime(f"%Y-%m-%d %H:%M{zone}")
        )
        return f"{text} ({self.measurement_date_source})"

    @property
    def harmonic_count(self) -> int:
        """Harmonics marked on the spectrum and order-spectrum pages."""
        return len(self.pitch.harmonics) if self.pitch else (5 if self.found else 0)

    @property
    def fmax_hz(self) -> float:
        """Upper frequency of the spectrum and spectrogram pages [Hz]."""
        return min((max(self.harmonic_count, 5) + 2) * self.f0, min(b.fs for b in self.bursts) / 2)


def _family_fit(x, fs, band):
    """The fitted link-pass harmonic family (with offset) at every sample of ``x`` [x]."""
    try:
        e = link_pass_estimate(x, fs, band=band)
    except ValueError:
        return np.full(x.size, np.median(x))
    t = np.arange(x.size) / fs
    fit = np.full(x.size, float(getattr(e.estimate, "offset", 0.0) or 0.0))
    for h in e.harmonics:
        fit += h.amplitude * np.cos(2 * np.pi * h.frequency_hz * t + h.phase_rad)
    return fit


def measurement_date(rec, date=None):
    """(datetime or None, source) of a recording: ``date`` (ISO 8601 text or a datetime), else the
    file's ``start_time`` / ``start_utc`` metadata, else (None, "")."""
    if date is not None:
        d, source = date, "given"
    else:
        d = rec.attrs.get("start_time") or rec.attrs.get("start_utc")
        source = "the file's start time"
        if not d:
            return None, ""
    if source == "given":  # the validator every command shares (ISO 8601, 1970-2100, not in the future)
        d = check_date(d, "--date") if isinstance(d, _dt.datetime) else parse_iso_date(d, "--date")
    if not isinstance(d, _dt.datetime):
        text = str(d).strip().replace("Z", "+00:00")
        try:
            d = _dt.datetime.fromisoformat(text)
        except ValueError:
            return None, ""
    if d.tzinfo is None:  # a logger's local time without its zone: kept as written, not called UTC
        d = d.replace(tzinfo=_dt.timezone.utc)
        if source != "given":
            source += ", its time zone not stated"
    return d.astimezone(_dt.timezone.utc), source


@takes_report_options
def analyse(recording, **options) -> ReportContext:
    """Everything :func:`vibkit.diagnose.report.write_report` draws (the same options, no output).

    Parameters
    ----------
    recording : str or os.PathLike
        Recording file (anything :func:`vibkit.read_recording` reads).
    **options
    """
    o = ReportOptions.of("analyse", options)
    scene, channel, profile, segment, duration = o.scene, o.channel, o.profile, o.segment, o.duration
    opts = dict(o.read_options or {})
    if o.sample_rate is not None:
        opts["sample_rate"] = o.sample_rate
    try:  # every channel: the report's ride-quality page wants the three axes
        rec = read_recording(recording, **opts)
    except RecordingError:
        if channel is None:
            raise
        rec = read_recording(recording, channel=channel, **opts)  # e.g. traces on different time bases
    rec = with_component(rec, channel)
    whole = rec  # the ride's weighting filters run over the whole record, its segment the one asked for
    rec = cut_recording(rec, segment)  # every other page: the segment asked for, in the file's own time
    measured, measured_source = measurement_date(rec, o.date)
    ch = pick_channel(rec, channel)
    sc = None
    if scene is not None:
        sc = scene if isinstance(scene, Scene) else load_scene(scene)
    notes = []
    # the run's settings as every command resolves them (vibkit.diagnose.settings): the speed, nominal pitch, the
    # unit's own sprocket, band and links where a profile names the unit (a scene given beside it may be another's),
    # the sensor of each channel
    settings = resolve_settings(
        rec,
        speed=o.speed,
        speed_sigma=o.speed_sigma,
        nominal_pitch=o.nominal_pitch,
        band=o.band,
        limits=o.limits_percent,
        segment=segment,
        profile=profile,
        scene=sc,
        frequency_only_band=True,
    )
    run = settings.speed  # (a link count filled in from the profile's geometry: the summary says so)
    speed, speed_sigma = run.value, run.sigma
    if speed is not None and run.source != "given":
        notes.append(f"speed {speed:g} m/s from {run.source}; every page uses it")
    nominal_pitch, band, limits = settings.nominal_pitch, settings.band, settings.limits
    if profile is None and sc is None:
        notes.append(
            f"sprocket teeth not known: {settings.teeth} assumed (the study's sprocket) for the shaft-frequency "
            "reading; give --escalator PROFILE (drive.teeth)"
        )
    if profile is not None and speed is not None and settings.band_source not in ("given", ""):
        notes.append(f"search band {fmt_band(band)} from the profile (0.8-1.25 x speed / nominal pitch)")
    # the per-channel decision of `spectrum` and `pitch` (vibkit.diagnose.channels.estimate_channels): every
    # vibration channel (or the one asked for) estimated, channels that disagree refused, the numbers
    # from the channel with the most evidence; a worn link's once-a-loop pattern is not read as a wander by the
    # parts check where the chain's links are known
    if speed is not None:
        kw = dict(
            speed=speed,
            speed_sigma=speed_sigma,
            band=band,
            nominal_pitch=nominal_pitch,
            limits_percent=limits,
            teeth=settings.teeth,
        )
    else:  # frequency only: the same burst-combined estimator, with a unit "speed"
        kw = dict(speed=1.0, band=band, frequency_only=True)
        notes.append("no speed known: link-pass frequency only, no pitch (give --speed)")
    decided = estimate_channels(
        rec,
        channel=channel,
        n_links=settings.n_links,
        links_per_step=settings.links_per_step,
        sensors=settings.sensors_by_channel,
        **kw,
    )
    found = decided.best is not None
    est = decided.best if found else next((e for e in decided.estimates if e.channel == ch), decided.estimates[0])
    ch = est.channel
    units = str(rec[ch].attrs.get("units", "1"))
    bursts = uniform_bursts(own_samples(rec, ch), ch)
    f0 = est.fundamental_hz
    pitch = est if speed is not None else None
    if found and len(decided.estimates) > 1:
        notes.append(f"channel {ch}: {decided.reason}")
    if not found:
        notes.insert(0, f"{decided.status.upper()}: {decided.reason}; no frequency, pitch or elongation can be given")
        # the pages below mark harmonics of f0: show the search band's centre, unmarked
        band_used = est.band_hz
        f0 = float(np.sqrt(band_used[0] * band_used[1]))
        pitch = None
    comp = None
    result = None
    comparison_absent = "no scene given (--scene SCENE, or a scene of the unit: vibkit scene PROFILE)"
    if sc is not None:
        # with the step's roller motion: the ride figure is then the one `vibkit ride SCENE` gives; the run kept on
        # disk where this scene was simulated before (vibkit.diagnose.kept_simulation)
        result = simulate_kept(with_ride_outputs(sc), duration=duration, progress=o.progress)
        comparison_absent = "" if found else "no link pass found in the recording to compare with the simulation's"
        if found:  # no comparison of a link pass the recording does not carry
            try:
                # the recording's speed only: at the scene's own speed assumed, its pitch is the scene's by
                # construction and not judged (as `vibkit compare` says it)
                assumed = speed is not None and run.from_scene
                comp = compare(
                    rec,
                    result,
                    channel=ch,
                    speed=None if assumed else speed,
                    speed_sigma=None if assumed else speed_sigma,
                    profile=profile,
                )
            except ValueError as exc:  # e.g. a channel in a unit the simulation has no variable in
                notes.append(f"no comparison with the simulation: {' '.join(str(exc).split())}")
                comparison_absent = f"the simulation could not be compared: {' '.join(str(exc).split())}"
    ride_absent = []
    ride = _ride(whole, result if scene_is_unit(sc, profile) else None, sc, notes, segment, speed, ride_absent)
    ride = [(kind, _with_knock(rq, sc if kind == "simulation" else None, profile)) for kind, rq in ride]
    if result is not None and not scene_is_unit(sc, profile):
        why = f"scene {sc.name!r} is not " + (
            f"unit {profile.unit}'s" if profile is not None else "a named unit's (--escalator FILE)"
        )
        notes.append(f"no ride page of the simulation: {why}")
        ride_absent.append(f"simulation: {why}")
    elif result is None:
        ride_absent.append("simulation: no scene simulated")
    # statistics
    x_all = np.concatenate([b.x for b in bursts])
    rms = float(np.sqrt(np.mean((x_all - x_all.mean()) ** 2)))
    p2p = float(np.ptp(x_all))
    # spikes: Hampel events on the residual after the fitted link-pass family is removed (a strong
    # periodic signal would otherwise inflate the local scatter and hide them)
    events = []
    tested = 0  # samples the spike detector judged
    search = pitch.band_hz if pitch is not None else (band or (0.9 * f0, 1.1 * f0))
    for b in bursts:
        hw = max(3, int(round(o.hampel_half_window_s * b.fs)))
        if b.x.size <= 2 * hw + 1:
            continue
        resid = b.x - _family_fit(b.x, b.fs, search)
        tested += b.x.size
        for e in hampel_events(
            resid, b.fs, half_window=hw, false_alarm_rate=o.hampel_false_alarm_rate, t0=b.t0, max_gap=hw // 4
        ):
            events.append((e.time_s, float(b.x[e.index]), e))
    # what chance alone gives: the detector's false-alarm rate is per sample on Gaussian noise
    spikes_expected = o.hampel_false_alarm_rate * tested
    clip_n = held_extremes(x_all)
    clipped = clip_n > 4 and not _quantisation_explains_extremes(x_all, rec[ch].attrs.get("quantum"))
    date = report_date()
    summary = {
        "file": os.path.basename(source_name(recording)),
        "sha256": rec.attrs.get("sha256", ""),
        "channel": ch,
        "units": units,
        "link_pass_hz": f0 if found else None,
        "status": decided.status,
        "reason": decided.reason,
        "measurement_date": measured.isoformat() if measured else None,
        "report_date": date.isoformat(),
        "rms": rms,
        "peak_to_peak": p2p,
        "spikes": len(events),
        "spikes_expected_by_chance": spikes_expected,
        "clipped": clipped,
    }
    if pitch is not None:
        summary.update(
            {
                k: v
                for k, v in pitch.as_dict().items()
                if k
                in (
                    "fundamental_sigma_hz",
                    "pitch_m",
                    "pitch_sigma_m",
                    "elongation_percent",
                    "elongation_sigma_percent",
                    "verdict",
                    "speed_m_s",
                    "speed_sigma_m_s",
                )
            }
        )
    if comp is not None:
        summary.update(score=comp.score, pitch_consistent=comp.pitch_consistent)
    links, links_note = _links(rec, ch, units, sc, speed, notes, profile, o.marker_s)
    chain_links = _chain_links(profile, sc)
    if profile is not None and (assumed := geometry_note(profile)):  # n_links alone: an escalator of 30 deg
        notes.insert(0, assumed)
    if chain_links is not None:
        summary["n_links"], summary["n_links_from"] = chain_links
        if profile is not None and profile.n_links is None:
            notes.insert(
                0,
                f"the chain's {chain_links[0]} links are vibkit's count, not the drawings' ({chain_links[1]}): "
                "give chain.n_links from the drawings (every link number depends on it)",
            )
    if links is not None:
        summary["flagged_links"] = [f["link"] for f in links.flagged]
        summary["link_numbers_from"] = (
            f"the link marked at {links.marker_s:g} s"
            if links.marker_s is not None
            else "the link at the sensor at the start"
        )
        summary["marker_s"] = links.marker_s
        summary["flagged_links_detail"] = [
            {k: f.get(k) for k in ("link", "alternatives", "excess_pitch_mm", "sigma_mm", "loops")}
            for f in links.flagged
        ]
    return ReportContext(
        links=links,
        links_note=links_note,
        ride_absent=ride_absent,
        comparison_absent=comparison_absent,
        spikes_expected=spikes_expected,
        links_per_step=settings.links_per_step,
        recording=recording,
        rec=rec,
        channel=ch,
        units=units,
        scene=sc,
        speed=speed,
        speed_sigma=speed_sigma,
        nominal_pitch=nominal_pitch,
        limits=limits,
        band=band,
        duration=duration,
        hampel_half_window_s=o.hampel_half_window_s,
        hampel_false_alarm_rate=o.hampel_false_alarm_rate,
        bursts=bursts,
        pitch=pitch,
        f0=f0,
        found=found,
        notes=notes,
        result=result,
        comparison=comp,
        events=events,
        rms=rms,
        p2p=p2p,
        clip_n=clip_n,
        clipped=clipped,
        date=date,
        summary=summary,
        measurement_date=measured,
        measurement_date_source=measured_source,
        ride=ride,
        run_speed=run,
        profile=profile,
    )


def _links(rec, ch, units, sc, speed, notes, profile=None, marker_s=None):
    """The link map of a tensioner recording over two loops of the scene's chain: ``(LinksResult, "")``, else
    ``(None, why not)`` for page 1.  A scene built from the escalator profile (in memory) is scanned with the
    profile's scene file, as ``vibkit links --escalator`` does."""
    if sc is None and profile is not None:
        try:  # the profile's own scene: its chain and the worn link's signature
            sc = profile.scene("forward")
        except ValueError as exc:
            return None, f"not scanned: the profile gives no scene ({' '.join(str(exc).split())})"
    if sc is None:
        return None, "not scanned: no scene or escalator profile (its chain and the worn link's signature)"
    if not speed:
        return None, "not scanned: no chain speed"
    if units != "m":
        return None, f"not scanned: channel {ch} is not a tensioner displacement (the links are read from one)"
    scene_file = sc.source
    if sc.analysis != "forward":
        # the worn link's signature is simulated from a forward scene: without one, each link's own cycle is
        # tested, as `vibkit links` does without --scene (the chain's links are still the scene's)
        article = "an" if sc.analysis[:1] in "aeiou" else "a"
        notes.append(
            f"link map: without the worn link's signature (the scene is {article} {sc.analysis} scene, the "
            "signature is simulated from a forward one): each link's own cycle tested"
        )
        scene_file = None
    elif profile is not None and str(scene_file).endswith("(scene built from the profile)"):
        scene_file = profile_scene_file(profile)
    elif scene_file == "<string>" or not os.path.isfile(str(scene_file)):
        notes.append(
            "link map: without the worn link's signature (the scene is not a file, the signature is simulated "
            "from one): each link's own cycle tested"
        )
        scene_file = None
    try:
        res = find_worn_links(
            rec,
            speed=speed,
            n_links=sc.chain.n_rollers,
            channel=ch,
            scene=scene_file,
            marker_s=marker_s,
            nominal_pitch=None if profile is None else profile.nominal_pitch,
            profile=profile,
        )
        return res, ""
    except TooFewLoops as exc:  # under two loops: no page (vibkit links says how long to record)
        return None, f"not scanned: {' '.join(str(exc).split())}"
    except ValueError as exc:
        if "marker_s" in str(exc):  # the marker given lies outside the recording: the user's to mend, not a note
            raise
        notes.append(f"link map: {exc}")
        return None, f"not scanned: {' '.join(str(exc).split())}"


def _chain_links(profile, sc):
    """``(links, where the count came from)`` of the unit's chain: the profile's (given or derived from its
    rise), else the scene's; None where neither says."""
    if profile is not None:
        try:
            n, src = link_count(profile)
        except SceneError:
            return None
        return n, ("chain.n_links of the profile" if src == "chain.n_links" else "derived: " + src.split(": ", 1)[-1])
    if sc is not None:
        return int(sc.chain.n_rollers), f"chain.n_rollers of scene {sc.name}"
    return None


def held_extremes(x):
    """Samples held at the record's extreme values: those equal to its maximum or minimum (to 1e-9 of it) in runs
    of two or more consecutive samples, as a clipped sensor's flat tops are.  A simulation can reach the same
    extreme at separate instants (a value read from a table recurs exactly): those are not counted."""
    x = np.asarray(x, dtype=float)
    n = 0
    for v in (float(np.max(x)), float(np.min(x))):
        at = np.isclose(x, v, rtol=0, atol=1e-9 * max(abs(v), 1e-30))
        held = at & (np.r_[False, at[:-1]] | np.r_[at[1:], False])  # a neighbour is at it too
        n += int(np.count_nonzero(held))
    return n


def _quantisation_explains_extremes(x, q):
    """Whether the samples at the extreme values of a quantised channel are its resolution, not clipping.

    A signal quantised in steps ``q`` sits at its extreme levels for as long as it moves less than a
    step there (a sine at 0.1 m/s^2 resolution holds its crest level about 1.4 times as long as the
    level next to it); a clipped one piles up there: the extreme level then holds over 3 times the
    samples of the level next to it.
    """
    if not q:
        return False
    lo, hi = float(np.min(x)), float(np.max(x))
    tol = 0.25 * float(q)

    def count(v):
        return int(np.sum(np.abs(x - v) < tol))

    return count(hi) <= 3 * max(count(hi - q), 1) and count(lo) <= 3 * max(count(lo + q), 1)


def _with_knock(rq, scene, profile):
    """``rq`` with the knock test of its step's rollers (:func:`vibkit.diagnose.knock.ride_knock`) among its
    notes: the rollers of the scene (a simulation) or of the profile (a recording)."""
    rollers = step_rollers_of(scene=scene) if scene is not None else step_rollers_of(profile=profile)
    _, note = ride_knock(rq, rollers)
    return dataclasses.replace(rq, notes=[*rq.notes, f"roller knock: {note}"])


def _ride(rec, result, sc, notes, segment=None, speed=None, absent=None):
    """Ride qualities of the recording (over ``segment`` [s] when given) and the simulation; a one-line note
    where one that could be expected (a recording with x, y, z channels, a scene that names its step) cannot
    be assessed; ``absent`` collects why a page (recording, simulation) is not drawn."""
    absent = [] if absent is None else absent
    out = []
    axes = {m.group(1) for nm in rec.data_vars if (m := _AXIS_RE.search(str(nm).lower()))}
    try:
        rq = ride_quality_from_recording(rec, segment=segment)
        out.append(("recording", rq if speed is None else dataclasses.replace(rq, speed_m_s=speed)))  # one speed
    except ValueError as exc:
        if len(axes) >= 2:
            notes.append(
                f"no ride-quality page for the recording ({', '.join(sorted(axes))} axes): "
                f"{' '.join(str(exc).split())} (--segment START:END)"
            )
            absent.append(f"recording: {' '.join(str(exc).split())} (--segment START:END)")
        else:
            absent.append("recording: it has no x, y, z acceleration channels of a step")
    if result is not None:  # only the unit's own scene (scene_is_unit)
        try:
            out.append(("simulation", ride_quality_from_simulation(result)))
        except ValueError as exc:
            if sc.outputs.get("step_accelerometer") is not None:
                notes.append(f"no ride-quality page for the simulation: {' '.join(str(exc).split())}")
            absent.append(f"simulation: {' '.join(str(exc).split())}")
    return out
