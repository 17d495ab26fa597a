"""Everything the report's pages draw, computed once before the first page: :class:`ReportContext`.

:func:`analyse` reads the recording, resolves speed and nominal pitch, estimates the link-pass frequency
and the pitch (:mod:`vibkit.diagnose.pitch`), simulates and compares a scene when one is given
(:mod:`vibkit.diagnose.comparison`), finds spikes (Hampel events on the residual after the link-pass
family) and suspected clipping, and builds the JSON summary.  The page functions only draw.
"""

from __future__ import annotations

import datetime as _dt
import os
from dataclasses import dataclass, field

import numpy as np

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
    speed, speed_sigma : float or None, float
        Resolved chain speed (the option, else the recording's, else the scene's) [m/s].
    nominal_pitch : float or None
        Resolved nominal pitch (the option, else the scene's) [m].
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
    speed_sigma: float
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

    @property
    def date_fixed(self) -> bool:
        """The report's date comes from ``SOURCE_DATE_EPOCH``."""
        return bool(os.environ.get("SOURCE_DATE_EPOCH"))

    @property
    def measurement_date_text(self) -> str:
        if self.measurement_date is None:
            return "not stated in the file (give --date)"
        d = self.measurement_date
        text = d.strftime("%Y-%m-%d") if (d.hour, d.minute, d.second) == (0, 0, 0) else d.strftime("%Y-%m-%d %H:%M UTC")
        return f"{text} ({self.measurement_date_source})"

    @property
    def harmonic_count(self) -> int:
        """Harmonics marked on the spectrum and order-spectrum pages."""
        return len(self.pitch.harmonics) if self.pitch else (5 if self.found else 0)

    @property
    def fmax_hz(self) -> float:
        """Upper frequency of the spectrum and spectrogram pages [Hz]."""
        return min((max(self.harmonic_count, 5) + 2) * self.f0, min(b.fs for b in self.bursts) / 2)


def _scene_speed(scene):
    if scene is None:
        return None
    if scene.analysis == "inverse":
        return float(scene.motion.speed)
    if scene.analysis == "forward":
        from ...model.schema import nominal_speed

        return float(nominal_speed(scene.effects, scene.run)) or None
    return None


def _family_fit(x, fs, band):
    """The fitted link-pass harmonic family (with offset) at every sample of ``x`` [x]."""
    from ...signal import link_pass_estimate

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
        from ...runtime.dates import check_date, parse_iso_date

        d = check_date(d, "--date") if isinstance(d, _dt.datetime) else parse_iso_date(d, "--date")
    if not isinstance(d, _dt.datetime):
        text = str(d).strip().replace("Z", "+00:00")
        try:
            d = _dt.datetime.fromisoformat(text)
        except ValueError:
            return None, ""
    if d.tzinfo is None:
        d = d.replace(tzinfo=_dt.timezone.utc)
    return d.astimezone(_dt.timezone.utc), source


def analyse(
    recording,
    *,
    scene=None,
    speed=None,
    speed_sigma=0.0,
    channel=None,
    nominal_pitch=None,
    limits_percent=None,
    sample_rate=None,
    duration=None,
    band=None,
    hampel_half_window_s=0.1,
    hampel_false_alarm_rate=1e-4,
    progress=False,
    read_options=None,
    date=None,
) -> ReportContext:
    """Everything :func:`vibkit.diagnose.report.write_report` draws (same parameters, no output)."""
    from ...io import read_recording
    from ...model.scene import Scene, load_scene
    from ...signal import hampel_events
    from ...signal.bursts import uniform_bursts
    from ..pitch import DEFAULT_LIMITS_PERCENT, estimate_pitch, pick_channel

    limits = tuple(limits_percent) if limits_percent is not None else DEFAULT_LIMITS_PERCENT
    from ...io import RecordingError

    opts = dict(read_options or {})
    if sample_rate is not None:
        opts["sample_rate"] = sample_rate
    try:  # every channel: the report's ride-quality page wants the three axes
        rec = read_recording(recording, **opts)
    except RecordingError:
        if channel is None:
            raise
        rec = read_recording(recording, channel=channel, **opts)  # e.g. traces on different time bases
    measured, measured_source = measurement_date(rec, date)
    ch = pick_channel(rec, channel)
    units = str(rec[ch].attrs.get("units", "1"))
    sc = None
    if scene is not None:
        sc = scene if isinstance(scene, Scene) else load_scene(scene)
    notes = []
    if speed is None:
        from ..channels import speed_from_recording

        speed, source = speed_from_recording(rec)
        if speed is not None:
            notes.append(f"speed {speed:g} m/s from the recording's metadata ({source})")
        elif _scene_speed(sc):
            speed = _scene_speed(sc)
            notes.append(
                f"speed {speed:g} m/s from the scene (the recording states none): the pitch then "
                "assumes the scene's speed"
            )
    if nominal_pitch is None and sc is not None:
        nominal_pitch = sc.chain.link_pitch
    bursts = uniform_bursts(rec, ch)
    pitch = None
    f0 = None
    if speed is not None:
        pitch = estimate_pitch(
            rec,
            speed=speed,
            speed_sigma=speed_sigma,
            channel=ch,
            band=band,
            nominal_pitch=nominal_pitch,
            limits_percent=limits,
            teeth=sc.sprocket.teeth if sc else 28,
        )
        f0 = pitch.fundamental_hz
    else:
        # frequency only: the same burst-combined estimator, with a unit "speed"
        fonly = estimate_pitch(rec, speed=1.0, channel=ch, band=band or (2.5, 6.0), frequency_only=True)
        f0 = fonly.fundamental_hz
        notes.append("no speed known: link-pass frequency only, no pitch (give --speed)")
    decided = pitch if pitch is not None else fonly  # the shared decision (vibkit.diagnose.decision)
    found = decided.has_link_pass
    if not found:
        notes.insert(0, f"{decided.status.upper()}: {decided.reason}; no frequency, pitch or elongation can be given")
        # the pages below mark harmonics of f0: show the search band's centre, unmarked
        band_used = (pitch if pitch is not None else fonly).band_hz
        f0 = float(np.sqrt(band_used[0] * band_used[1]))
        pitch = None
    comp = None
    result = None
    if sc is not None:
        from ...analyses.simulation import simulate
        from ..comparison import compare
        from ..ride import with_ride_outputs

        # with the step's roller motion: the ride figure is then the one `vibkit ride SCENE` gives
        result = simulate(with_ride_outputs(sc), duration=duration, progress=progress)
        if found:  # no comparison of a link pass the recording does not carry
            comp = compare(rec, result, channel=ch)
    ride = _ride(rec, result, sc, notes)
    # statistics
    x_all = np.concatenate([b.x for b in bursts])
    rms = float(np.sqrt(np.mean((x_all - x_all.mean()) ** 2)))
    p2p = float(np.ptp(x_all))
    # spikes: Hampel events on the residual after the fitted link-pass family is removed (a strong
    # periodic signal would otherwise inflate the local scatter and hide them)
    events = []
    search = pitch.band_hz if pitch is not None else (band or (0.9 * f0, 1.1 * f0))
    for b in bursts:
        hw = max(3, int(round(hampel_half_window_s * b.fs)))
        if b.x.size <= 2 * hw + 1:
            continue
        resid = b.x - _family_fit(b.x, b.fs, search)
        for e in hampel_events(
            resid, b.fs, half_window=hw, false_alarm_rate=hampel_false_alarm_rate, t0=b.t0, max_gap=hw // 4
        ):
            events.append((e.time_s, float(b.x[e.index]), e))
    # clipping: samples sitting at the extreme values in runs
    lo, hi = float(np.min(x_all)), float(np.max(x_all))
    clip_n = int(
        np.sum(np.isclose(x_all, hi, rtol=0, atol=1e-9 * max(abs(hi), 1e-30)))
        + np.sum(np.isclose(x_all, lo, rtol=0, atol=1e-9 * max(abs(lo), 1e-30)))
    )
    clipped = clip_n > 4
    date = report_date()
    summary = {
        "file": os.path.basename(os.fspath(recording)),
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
    return ReportContext(
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
        hampel_half_window_s=hampel_half_window_s,
        hampel_false_alarm_rate=hampel_false_alarm_rate,
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
    )


def _ride(rec, result, sc, notes):
    """Ride qualities of the recording and the simulation; a one-line note where one that could be
    expected (a recording with x, y, z channels, a scene that names its step) cannot be assessed."""
    from ..ride import _AXIS_RE, ride_quality_from_recording, ride_quality_from_simulation

    out = []
    axes = {m.group(1) for nm in rec.data_vars if (m := _AXIS_RE.search(str(nm).lower()))}
    try:
        out.append(("recording", ride_quality_from_recording(rec)))
    except ValueError as exc:
        if len(axes) >= 2:
            notes.append(
                f"no ride-quality page for the recording ({', '.join(sorted(axes))} axes): "
                f"{' '.join(str(exc).split())} (vibkit ride FILE --segment START:END)"
            )
    if result is not None:
        try:
            out.append(("simulation", ride_quality_from_simulation(result)))
        except ValueError as exc:
            if sc.outputs.get("step_accelerometer") is not None:
                notes.append(f"no ride-quality page for the simulation: {' '.join(str(exc).split())}")
    return out
