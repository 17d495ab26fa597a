"""The PDF diagnostic report: the only module of vibkit that draws pages.

:func:`write_report` reads a recording, estimates the link-pass frequency and the link pitch
(:mod:`vibkit.diagnose.pitch`), finds spikes (Hampel events), and, given a scene, simulates it and compares
(:mod:`vibkit.diagnose.comparison`).  It writes one multi-page PDF: cover, verdict table, time signal with
events, spectrum with harmonic markers, spectrogram, order spectrum, simulation against recording,
data quality, parameters.  The same inputs give the same bytes: the PDF dates come from
``SOURCE_DATE_EPOCH`` (or a fixed epoch), and nothing random is drawn.
"""

from __future__ import annotations

import datetime as _dt
import math
import os
import textwrap
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Report", "write_report", "plot_comparison", "plot_ride", "report_date", "atomic_path"]

#: date used in the PDF when SOURCE_DATE_EPOCH is not set (the PDF stays reproducible)
FIXED_EPOCH = 946684800  # 2000-01-01T00:00:00Z
_PAGE = (8.27, 11.69)  # A4 portrait [in]
_WIDE = (11.69, 8.27)  # A4 landscape [in]


@dataclass(frozen=True)
class Report:
    """What :func:`write_report` wrote.

    Attributes
    ----------
    path : str
    pages : list of (str, list of str)
        Page title and every text drawn on it (for tests and indexing).
    pitch : PitchEstimate or None
    comparison : Comparison or None
    summary : dict
        The verdict table as a JSON-ready dict.
    """

    path: str
    pages: list
    pitch: object = None
    comparison: object = None
    summary: dict = field(default_factory=dict)


def report_date() -> _dt.datetime:
    """UTC date of the report: ``SOURCE_DATE_EPOCH`` if set, else a fixed epoch (2000-01-01).

    Raises
    ------
    ValueError
        ``SOURCE_DATE_EPOCH`` is not an integer number of seconds.
    """
    raw = os.environ.get("SOURCE_DATE_EPOCH")
    if raw is None or raw == "":
        sec = FIXED_EPOCH
    else:
        try:
            sec = int(raw)
        except ValueError:
            raise ValueError(f"SOURCE_DATE_EPOCH must be an integer number of seconds, got {raw!r}") from None
    return _dt.datetime.fromtimestamp(sec, tz=_dt.timezone.utc)


class atomic_path:
    """Context manager yielding a temporary path next to ``path``; on success it replaces ``path``.

    A thin wrapper of :func:`vibkit.runtime.safe_output.atomic_output` (regular files only, fsync, rename,
    the temporary file removed on any error or signal).
    """

    def __init__(self, path, suffix="", *, overwrite=True, inputs=()):
        self.path = os.fspath(path)
        self.suffix = suffix
        self._cm = None
        self._kw = {"overwrite": overwrite, "inputs": inputs}

    def __enter__(self):
        from ..runtime.safe_output import atomic_output

        self._cm = atomic_output(self.path, **self._kw)
        self.tmp = self._cm.__enter__()
        return self.tmp

    def __exit__(self, exc_type, exc, tb):
        return self._cm.__exit__(exc_type, exc, tb)


class _pdf_in_memory:
    """Collect a PDF in memory; on success write it to ``path`` atomically (a full disk leaves nothing)."""

    def __init__(self, path, *, overwrite, inputs):
        self.path, self.overwrite, self.inputs = path, overwrite, inputs

    def __enter__(self):
        import io

        self.buf = io.BytesIO()
        return self.buf

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            from ..runtime.safe_output import write_bytes

            write_bytes(self.buf.getbuffer(), self.path, overwrite=self.overwrite, inputs=self.inputs)
        return False


def _texts(fig):
    import matplotlib.text

    out = [t.get_text() for t in fig.findobj(matplotlib.text.Text) if t.get_text() and t.get_visible()]
    for ax in fig.axes:
        for tab in ax.tables:
            out += [c.get_text().get_text() for _, c in sorted(tab.get_celld().items()) if c.get_text().get_text()]
    return out


def _fmt(v, unit="", digits=4):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a"
    return f"{v:.{digits}g} {unit}".strip()


def _scene_speed(scene):
    if scene is None:
        return None
    if scene.analysis == "inverse":
        return float(scene.section("motion")["speed"])
    if scene.analysis == "forward":
        return float(scene.effects.get("motor", {}).get("speed", scene.section("run").get("initial_speed", 0.0))) or None
    return None


def _table(ax, rows, col_widths=(0.42, 0.58), fontsize=9):
    ax.axis("off")
    tab = ax.table(cellText=rows, colWidths=list(col_widths), loc="upper center", cellLoc="left")
    tab.auto_set_font_size(False)
    tab.set_fontsize(fontsize)
    tab.scale(1.0, 1.35)
    return tab


def _page_title(fig, title, subtitle=""):
    fig.suptitle(title, fontsize=14, fontweight="bold", x=0.06, ha="left", y=0.975)
    if subtitle:
        fig.text(0.06, 0.945, subtitle, fontsize=8.5, color="0.3")


def plot_comparison(comp, fig=None):
    """Draw a :class:`vibkit.diagnose.comparison.Comparison` on one figure: order spectra overlaid, amplitude
    spectra side by side with harmonic markers, spectrograms side by side.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    from ..signal import amplitude_spectrum, spectrogram

    if fig is None:
        fig = plt.figure(figsize=_WIDE)
    gs = fig.add_gridspec(3, 2, height_ratios=(1.0, 1.0, 1.1), hspace=0.55, wspace=0.25,
                          left=0.07, right=0.97, top=0.88, bottom=0.07)
    u = comp.units
    ax = fig.add_subplot(gs[0, :])
    ax.semilogy(comp.orders, np.maximum(comp.order_amplitude_sim, 1e-30), label=f"simulation ({comp.variable})")
    ax.semilogy(comp.orders, np.maximum(comp.order_amplitude_meas, 1e-30), label=f"recording ({comp.channel})",
                alpha=0.8)
    top = max(comp.order_amplitude_sim.max(), comp.order_amplitude_meas.max())
    ax.set_ylim(top * 1e-4, top * 3)
    ax.set_xlabel("order of the link-pass frequency [-]")
    ax.set_ylabel(f"amplitude [{u}]")
    ax.set_title(f"Order spectra (each referred to its own link-pass); score {comp.score:.3f}, "
                 f"log-spectral distance {comp.log_spectral_distance_db:.1f} dB", fontsize=10)
    ax.legend(fontsize=8, loc="upper right")
    ax.grid(alpha=0.3)
    fs_s, x_s = comp.signals["sim"]
    meas = comp.signals["meas"]
    longest = max(meas, key=lambda m: m[2].size)
    nh = len(comp.harmonics)
    fmax = min((nh + 1.5) * max(comp.fundamental_sim_hz, comp.fundamental_meas_hz), fs_s / 2, longest[1] / 2)
    specs = (("simulation", fs_s, x_s, comp.fundamental_sim_hz, "C0"),
             ("recording", longest[1], longest[2], comp.fundamental_meas_hz, "C1"))
    for j, (name, fs, x, f0, col) in enumerate(specs):
        a1 = fig.add_subplot(gs[1, j])
        f, a = amplitude_spectrum(x, fs)
        sel = f <= fmax
        a1.semilogy(f[sel], np.maximum(a[sel], 1e-30), color=col, lw=0.9)
        for h in range(1, nh + 1):
            a1.axvline(h * f0, color="0.5", ls=":", lw=0.8)
        a1.set_xlim(0, fmax)
        a1.set_xlabel("frequency [Hz]")
        a1.set_ylabel(f"amplitude [{u}]")
        a1.set_title(f"{name}: link-pass {f0:.4g} Hz (dotted: harmonics)", fontsize=9)
        a1.grid(alpha=0.3)
        a2 = fig.add_subplot(gs[2, j])
        frame = min(2.0, x.size / fs / 2)
        nper = max(16, int(round(frame * fs)))
        fr, tt, s = spectrogram(x, fs, nperseg=nper, noverlap=nper * 3 // 4)
        sel = fr <= fmax
        db = 20 * np.log10(np.maximum(s[sel], 1e-30))
        im = a2.pcolormesh(tt, fr[sel], db, shading="nearest", vmin=db.max() - 60, vmax=db.max(), cmap="viridis",
                           rasterized=True)
        a2.set_xlabel("time from burst start [s]" if name == "recording" and len(meas) > 1 else "time [s]")
        a2.set_ylabel("frequency [Hz]")
        a2.set_title(f"{name} spectrogram ({frame:.2g} s frames)", fontsize=9)
        cb = fig.colorbar(im, ax=a2, pad=0.01)
        cb.set_label(f"dB re 1 {u}", fontsize=8)
    return fig


def plot_ride(rq, fig=None):
    """Draw a :class:`vibkit.diagnose.ride.RideQuality` on one figure: the per-axis table (weighted and 10 Hz
    max pk-pk, A95, r.m.s.) and each axis's weighted acceleration with the ride segment shaded and
    its largest peak-to-peak pair marked.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    if fig is None:
        fig = plt.figure(figsize=_PAGE)
    seg = rq.segment
    n = len(rq.axes)
    tab_ax = fig.add_axes((0.06, 0.76, 0.88, 0.14))
    tab_ax.axis("off")
    head = ["axis", "channel", "weighting", "max pk-pk", "A95", "r.m.s.", "10 Hz max pk-pk", "10 Hz A95"]
    cells = [[a.axis, a.channel[:28], a.weighting, f"{a.weighted.max:.4g}", f"{a.weighted.a95:.4g}",
              f"{a.weighted.rms:.4g}", f"{a.lowpass.max:.4g}", f"{a.lowpass.a95:.4g}"] for a in rq.axes]
    tab = tab_ax.table(cellText=cells, colLabels=head, loc="upper center", cellLoc="center",
                       colWidths=[0.06, 0.27, 0.09, 0.1, 0.1, 0.1, 0.14, 0.12])
    tab.auto_set_font_size(False)
    tab.set_fontsize(8)
    tab.scale(1, 1.3)
    fig.text(0.06, 0.745, f"values in m/s^2 over the ride {seg.start_s:.2f}-{seg.end_s:.2f} s ({seg.method}); "
             "pk-pk: adjacent half-cycle peaks; A95: not exceeded by 95 % of them", fontsize=7.5, color="0.3")
    top, bottom = 0.7, 0.07
    h = (top - bottom) / max(n, 1)
    for j, a in enumerate(rq.axes):
        ax = fig.add_axes((0.1, top - (j + 1) * h + 0.04, 0.85, h - 0.06))
        y = rq.weighted[a.axis]
        ax.plot(rq.time, y, lw=0.5, color="C0")
        ax.axvspan(seg.start_s, seg.end_s, color="C2", alpha=0.12, lw=0)
        tm = seg.start_s + a.weighted.time_of_max_s
        ax.axvline(tm, color="C3", ls=":", lw=1)
        ax.set_ylabel(f"{a.axis}, {a.weighting} [m/s^2]")
        ax.set_title(f"{a.axis}: weighted ({a.weighting}); max pk-pk {a.weighted.max:.3g} m/s^2 (dotted), "
                     f"A95 {a.weighted.a95:.3g} m/s^2", fontsize=8.5)
        ax.grid(alpha=0.3)
        if j == n - 1:
            ax.set_xlabel("time [s] (shaded: ride segment)")
    return fig


def _ride_quality_pages(emit, rec, result):
    """Ride-quality pages of the recording (when it has x, y, z acceleration channels) and of the
    simulation (when it has the step's motion); none when neither can be assessed."""
    import matplotlib.pyplot as plt

    from .ride import ride_quality_from_recording, ride_quality_from_simulation

    done = []
    for what, make in (("recording", lambda: ride_quality_from_recording(rec)),
                       ("simulation", lambda: ride_quality_from_simulation(result) if result is not None else None)):
        try:
            rq = make()
        except ValueError:
            rq = None
        if rq is None:
            continue
        fig = plt.figure(figsize=_PAGE)
        _page_title(fig, f"Ride quality ({what})", f"{os.path.basename(rq.source)}: step vibration, ISO 2631-1 "
                    "weighted (x, y: Wd; z: Wk) and 0.4-10 Hz unweighted")
        plot_ride(rq, fig)
        notes = rq.notes + ([rq.segment.note] if rq.segment.note else [])
        fig.text(0.06, 0.015, "\n".join(textwrap.fill("- " + m, 115) for m in notes[:4]), fontsize=6.5,
                 va="bottom", color="0.3")
        emit(fig, f"ride quality ({what})")
        done.append(rq)
    return done


def _family_fit(x, fs, band):
    """The fitted link-pass harmonic family (with offset) at every sample of ``x`` [x]."""
    from ..signal import link_pass_estimate

    try:
        e = link_pass_estimate(x, fs, band=band)
    except ValueError:
        return np.full(x.size, np.median(x))
    t = np.arange(x.size) / fs
    fit = np.full(x.size, float(getattr(e.estimate, "offset", 0.0) or 0.0))
    for h in e.harmonics:
        fit += h.amplitude * np.cos(2 * np.pi * h.frequency_hz * t + h.phase_rad)
    return fit


def write_report(recording, out_path, *, scene=None, speed=None, speed_sigma=0.0, channel=None,
                 nominal_pitch=None, limits_percent=None, sample_rate=None, duration=None, band=None,
                 hampel_half_window_s=0.1, hampel_false_alarm_rate=1e-4, progress=False, overwrite=True) -> Report:
    """Write the PDF diagnostic report of a recording.

    Parameters
    ----------
    recording : str or os.PathLike
        Recording file (anything :func:`vibkit.read_recording` reads).
    out_path : str or os.PathLike
        PDF to write (atomically); never one of the inputs.
    scene : str, os.PathLike or Scene, optional
        Scene describing the escalator and sensor; simulated and compared with the recording.
    speed : float, optional
        Chain speed [m/s]; default the recording's ``chain_speed_m_s``, else the scene's.
    speed_sigma : float
        Its standard deviation. [m/s]
    channel : str, optional
    nominal_pitch : float, optional
        [m]; default the scene's link pitch.
    limits_percent : (float, float, float), optional
        Elongation limits [%] (default 1.5, 2, 3).
    sample_rate : float, optional
        For files without time. [Hz]
    duration : float, optional
        Simulated time [s] (default the scene's).
    band : (float, float), optional
        Link-pass search band. [Hz]
    hampel_half_window_s : float
        Half window of the spike detector [s] (longer than a spike: a knock lasts tens of ms).
    hampel_false_alarm_rate : float
        Per-sample false-alarm probability of the spike detector on Gaussian noise.
    overwrite : bool
        Replace an existing regular file ``out_path`` (default True; the CLI passes ``--force``).

    Returns
    -------
    Report

    Raises
    ------
    ValueError
        The output is one of the inputs or not a ``.pdf``; bad options; or the errors of
        :func:`vibkit.read_recording` and :func:`vibkit.load_scene`.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.backends.backend_pdf import PdfPages

    from .. import __version__
    from ..io import read_recording
    from .pitch import DEFAULT_LIMITS_PERCENT, estimate_pitch, pick_channel, uniform_bursts
    from ..model.scene import Scene, load_scene
    from ..signal import amplitude_spectrum, hampel_events, order_spectrum, resample_to_angle, spectrogram

    out = os.fspath(out_path)
    if not out.lower().endswith(".pdf"):
        raise ValueError(f"output {out!r} must be a .pdf file")
    inputs = [os.fspath(recording)] + ([os.fspath(scene)] if isinstance(scene, (str, os.PathLike)) else [])
    for p in inputs:
        if os.path.exists(out) and os.path.samefile(out, p):
            raise ValueError(f"output {out!r} is an input file; refusing to overwrite it")
    from ..runtime.safe_output import check_output_path

    check_output_path(out, overwrite=overwrite, inputs=inputs)  # before any work
    limits = tuple(limits_percent) if limits_percent is not None else DEFAULT_LIMITS_PERCENT
    rec = read_recording(recording, sample_rate=sample_rate)
    ch = pick_channel(rec, channel)
    units = str(rec[ch].attrs.get("units", "1"))
    sc = None
    if scene is not None:
        sc = scene if isinstance(scene, Scene) else load_scene(scene)
    notes = []
    if speed is None:
        if float(rec.attrs.get("chain_speed_m_s", 0) or 0) > 0:
            speed = float(rec.attrs["chain_speed_m_s"])
            notes.append(f"speed {speed:g} m/s from the recording's metadata")
        elif _scene_speed(sc):
            speed = _scene_speed(sc)
            notes.append(f"speed {speed:g} m/s from the scene (the recording states none): the pitch then "
                         "assumes the scene's speed")
    if nominal_pitch is None and sc is not None:
        nominal_pitch = sc.chain.link_pitch
    bursts = uniform_bursts(rec, ch)
    pitch = None
    f0 = None
    if speed is not None:
        pitch = estimate_pitch(rec, speed=speed, speed_sigma=speed_sigma, channel=ch, band=band,
                               nominal_pitch=nominal_pitch, limits_percent=limits,
                               teeth=sc.sprocket.teeth if sc else 28)
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
    if sc is not None:
        from .comparison import compare

        result = None
        from ..analyses.simulation import simulate

        result = simulate(sc, duration=duration, progress=progress)
        comp = compare(rec, result, channel=ch)
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
        for e in hampel_events(resid, b.fs, half_window=hw, false_alarm_rate=hampel_false_alarm_rate, t0=b.t0,
                               max_gap=hw // 4):
            events.append((e.time_s, float(b.x[e.index]), e))
    # clipping: samples sitting at the extreme values in runs
    lo, hi = float(np.min(x_all)), float(np.max(x_all))
    clip_n = int(np.sum(np.isclose(x_all, hi, rtol=0, atol=1e-9 * max(abs(hi), 1e-30))) +
                 np.sum(np.isclose(x_all, lo, rtol=0, atol=1e-9 * max(abs(lo), 1e-30))))
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
        "rms": rms,
        "peak_to_peak": p2p,
        "spikes": len(events),
        "clipped": clipped,
    }
    if pitch is not None:
        summary.update({k: v for k, v in pitch.as_dict().items()
                        if k in ("fundamental_sigma_hz", "pitch_m", "pitch_sigma_m", "elongation_percent",
                                 "elongation_sigma_percent", "verdict", "speed_m_s", "speed_sigma_m_s")})
    if comp is not None:
        summary.update(score=comp.score, pitch_consistent=comp.pitch_consistent)

    pages = []
    meta = {"Title": f"vibkit report: {summary['file']}", "Author": f"vibkit {__version__}",
            "Subject": "escalator drive-chain vibration diagnostic", "Creator": f"vibkit {__version__}",
            "CreationDate": date, "ModDate": date}
    with matplotlib.rc_context({"pdf.compression": 6, "font.size": 9, "axes.titlesize": 10,
                                "svg.hashsalt": "vibkit", "path.simplify": True}):
        with _pdf_in_memory(out, overwrite=overwrite, inputs=inputs) as buf, PdfPages(buf, metadata=meta) as pdf:

            def emit(fig, title):
                pages.append((title, _texts(fig)))
                pdf.savefig(fig)
                plt.close(fig)

            # 1 cover
            fig = plt.figure(figsize=_PAGE)
            fig.text(0.08, 0.88, "Escalator drive-chain vibration", fontsize=20, fontweight="bold")
            fig.text(0.08, 0.845, "Diagnostic report", fontsize=15, color="0.25")
            ax = fig.add_axes((0.08, 0.35, 0.84, 0.45))
            sha = str(rec.attrs.get("sha256", ""))
            rows = [["recording", summary["file"]], ["sha256", sha[:32]], ["", sha[32:]],
                    ["reader", str(rec.attrs.get("reader", ""))],
                    ["report date (UTC)", date.strftime("%Y-%m-%d")], ["vibkit version", __version__],
                    ["escalator", (sc.description if sc else "not given (no scene)")[:70]],
                    ["scene", (f"{sc.name} ({sc.analysis}; pitch {1000 * sc.chain.link_pitch:.2f} mm, "
                               f"Z = {sc.sprocket.teeth})") if sc else "none"],
                    ["sensor channel", f"{ch} [{units}], {rec[ch].attrs.get('quantity', 'other')}"],
                    ["provenance", str(rec.attrs.get("provenance", "not stated"))[:70]]]
            _table(ax, rows, (0.25, 0.75), 9)
            fig.text(0.08, 0.08, textwrap.fill(
                "Generated by vibkit. Frequencies from harmonic least squares with Cramer-Rao standard "
                "deviations; pitch = speed / link-pass frequency. Reproducible: the same inputs give the same "
                "file (dates from SOURCE_DATE_EPOCH).", 95), fontsize=8, color="0.35")
            emit(fig, "cover")

            # 2 verdict
            fig = plt.figure(figsize=_PAGE)
            _page_title(fig, "Verdict", f"{summary['file']}, channel {ch}")
            ax = fig.add_axes((0.06, 0.30, 0.88, 0.62))
            rows = [["link-pass frequency", (f"{f0:.5g} Hz" + (f" +- {pitch.fundamental_sigma_hz:.2g} Hz" if pitch else ""))
                     if found else "NO LINK-PASS FOUND (no pitch, no verdict)"]]
            if pitch is not None:
                rows += [["speed", f"{pitch.speed_m_s:.4g} +- {pitch.speed_sigma_m_s:.2g} m/s"],
                         ["link pitch", f"{1000 * pitch.pitch_m:.2f} +- {1000 * pitch.pitch_sigma_m:.2f} mm"]]
                if pitch.nominal_pitch_m is not None:
                    rows += [["nominal pitch", f"{1000 * pitch.nominal_pitch_m:.2f} mm"],
                             ["elongation", f"{pitch.elongation_percent:.2f} +- {pitch.elongation_sigma_percent:.2f} %"],
                             ["limits (watch / plan / replace)", " / ".join(f"{v:g} %" for v in limits)],
                             ["elongation verdict", pitch.verdict.upper()]]
            rows += [["RMS", f"{rms:.4g} {units}"], ["peak to peak", f"{p2p:.4g} {units}"],
                     ["spikes (Hampel events)", f"{len(events)}"],
                     ["clipping", "suspected" if clipped else "none seen"]]
            if comp is not None:
                rows += [["agreement with simulation", f"score {comp.score:.3f} (0 none, 1 perfect)"],
                         ["pitch vs scene", ("consistent" if comp.pitch_consistent else "NOT consistent") +
                          f" (ratio {comp.pitch_ratio:.4f})"]]
            _table(ax, rows, (0.4, 0.6), 9.5)
            msgs = (pitch.warnings + pitch.notes if pitch else []) + notes
            fig.text(0.06, 0.05, "\n".join(textwrap.fill("- " + m, 110) for m in msgs[:7]), fontsize=7.5,
                     va="bottom", color="0.2")
            emit(fig, "verdict")

            # 3 time signal
            fig, ax = plt.subplots(figsize=_WIDE)
            fig.subplots_adjust(left=0.08, right=0.97, top=0.88, bottom=0.1)
            _page_title(fig, "Time signal", f"{len(bursts)} burst(s); red: spikes (Hampel events on the residual "
                        f"after the link-pass family, half window {hampel_half_window_s:g} s, false-alarm rate {hampel_false_alarm_rate:g})")
            for b in bursts:
                t = b.t0 + np.arange(b.x.size) / b.fs
                ax.plot(t, b.x, lw=0.5, color="C0")
            if events:
                ax.plot([e[0] for e in events], [e[1] for e in events], "o", mfc="none", color="C3",
                        ms=8, label=f"{len(events)} spike(s)")
                ax.legend(loc="upper right")
            ax.set_xlabel("time [s]")
            ax.set_ylabel(f"{rec[ch].attrs.get('long_name', ch)} [{units}]")
            ax.grid(alpha=0.3)
            emit(fig, "time signal")

            # 4 spectrum
            fig, ax = plt.subplots(figsize=_WIDE)
            fig.subplots_adjust(left=0.08, right=0.97, top=0.88, bottom=0.1)
            _page_title(fig, "Spectrum", "Hann-windowed amplitude spectrum averaged over bursts; dotted: "
                        "link-pass harmonics")
            nh = len(pitch.harmonics) if pitch else (5 if found else 0)
            fmax = min((max(nh, 5) + 2) * f0, min(b.fs for b in bursts) / 2)
            nfft = 1 << int(np.ceil(np.log2(max(b.x.size for b in bursts))))
            acc = None
            for b in bursts:
                f, a = amplitude_spectrum(b.x, b.fs, nfft=max(nfft, b.x.size))
                a = np.interp(np.linspace(0, fmax, 2000), f, a)
                acc = a if acc is None else acc + a
            fgrid = np.linspace(0, fmax, 2000)
            ax.semilogy(fgrid, np.maximum(acc / len(bursts), 1e-30), lw=0.9)
            for h in range(1, nh + 1):
                ax.axvline(h * f0, color="C3", ls=":", lw=1)
                ax.text(h * f0, 1.0, f" {h}x", transform=ax.get_xaxis_transform(), va="top", fontsize=8, color="C3")
            ax.set_xlim(0, fmax)
            ax.set_xlabel("frequency [Hz]")
            ax.set_ylabel(f"amplitude [{units}]")
            ax.grid(alpha=0.3)
            emit(fig, "spectrum")

            # 5 spectrogram
            fig, ax = plt.subplots(figsize=_WIDE)
            fig.subplots_adjust(left=0.08, right=0.95, top=0.88, bottom=0.1)
            frame = min(4.0, min(b.x.size / b.fs for b in bursts) / 2)
            _page_title(fig, "Spectrogram", f"frames of {frame:.2g} s, 75 % overlap; bursts at their own times")
            vmax = None
            ims = []
            for b in bursts:
                nper = max(16, int(round(frame * b.fs)))
                fr, tt, s = spectrogram(b.x, b.fs, nperseg=nper, noverlap=nper * 3 // 4)
                sel = fr <= fmax
                db = 20 * np.log10(np.maximum(s[sel], 1e-30))
                vmax = db.max() if vmax is None else max(vmax, db.max())
                ims.append((b.t0 + tt, fr[sel], db))
            for tt, fr, db in ims:
                im = ax.pcolormesh(tt, fr, db, shading="nearest", vmin=vmax - 60, vmax=vmax, cmap="viridis",
                                   rasterized=True)
            cb = fig.colorbar(im, ax=ax, pad=0.01)
            cb.set_label(f"amplitude [dB re 1 {units}]")
            ax.set_xlabel("time [s]")
            ax.set_ylabel("frequency [Hz]")
            emit(fig, "spectrogram")

            # 6 order spectrum
            fig, ax = plt.subplots(figsize=_WIDE)
            fig.subplots_adjust(left=0.08, right=0.97, top=0.88, bottom=0.1)
            _page_title(fig, "Order spectrum", f"resampled to constant link-pass phase ({f0:.5g} Hz); order 1 = "
                        "link pass, 1/3 = step pass")
            spc = 32
            acc, o_ref = None, None
            for b in bursts:
                ph = 2 * np.pi * f0 * np.arange(b.x.size) / b.fs
                if ph[-1] < 4 * np.pi:
                    continue
                o, a = order_spectrum(resample_to_angle(b.x, b.fs, ph, samples_per_cycle=spc))
                if o_ref is None:
                    o_ref, acc = o, a.copy()
                else:
                    acc += np.interp(o_ref, o, a)
            if o_ref is not None:
                sel = o_ref <= nh + 1.5
                ax.semilogy(o_ref[sel], np.maximum(acc[sel] / len(bursts), 1e-30), lw=0.9)
                for h in range(1, nh + 1):
                    ax.axvline(h, color="C3", ls=":", lw=1)
                ax.axvline(1 / 3, color="C2", ls="--", lw=1, label="step pass (1/3)")
                ax.legend(loc="upper right")
            ax.set_xlabel("order [cycles per link]")
            ax.set_ylabel(f"amplitude [{units}]")
            ax.grid(alpha=0.3)
            emit(fig, "order spectrum")

            _ride_quality_pages(emit, rec, result if sc is not None else None)

            # 7 simulation vs recording
            if comp is not None:
                fig = plt.figure(figsize=_WIDE)
                _page_title(fig, "Simulation against recording",
                            f"scene {sc.name}: {comp.variable} vs {comp.channel}; pitch "
                            f"{'consistent' if comp.pitch_consistent else 'NOT consistent'} "
                            f"({1000 * comp.pitch_meas_m:.2f} mm recorded vs {1000 * comp.pitch_sim_m:.2f} mm simulated)")
                plot_comparison(comp, fig)
                emit(fig, "simulation against recording")
                fig = plt.figure(figsize=_PAGE)
                _page_title(fig, "Harmonics: recording / simulation", f"{100 * comp.confidence:.0f} % intervals")
                ax = fig.add_axes((0.04, 0.45, 0.92, 0.45))
                ax.axis("off")
                head = ["order", "f sim [Hz]", "f rec [Hz]", "ratio", "amp. diff [dB]", "detected"]
                cells = [[str(h["order"]), f"{h['frequency_sim_hz']:.4f}", f"{h['frequency_meas_hz']:.4f}",
                          f"{h['frequency_ratio']:.4f} +- {h['frequency_ratio_sigma']:.1e}",
                          f"{h['amplitude_diff_db']:+.1f} [{h['amplitude_diff_db_ci'][0]:+.1f}, "
                          f"{h['amplitude_diff_db_ci'][1]:+.1f}]",
                          ("sim " if h["detected_sim"] else "") + ("rec" if h["detected_meas"] else "")]
                         for h in comp.harmonics]
                tab = ax.table(cellText=cells, colLabels=head, loc="upper center", cellLoc="center",
                               colWidths=[0.08, 0.14, 0.14, 0.24, 0.26, 0.14])
                tab.auto_set_font_size(False)
                tab.set_fontsize(8.5)
                tab.scale(1, 1.4)
                fig.text(0.06, 0.1, "\n".join(textwrap.fill(m, 105) for m in
                                              [f"score rule: {comp.rule}"] + comp.notes), fontsize=7.5, va="bottom")
                emit(fig, "harmonics")

            # 8 data quality
            fig = plt.figure(figsize=_PAGE)
            _page_title(fig, "Data quality", "what the reader found and decided")
            ax = fig.add_axes((0.06, 0.55, 0.88, 0.36))
            gaps = [bursts[i + 1].t0 - (bursts[i].t0 + bursts[i].x.size / bursts[i].fs) for i in range(len(bursts) - 1)]
            rows = [["samples", f"{rec.sizes['time']}"], ["nominal sample rate", f"{rec.attrs.get('sample_rate_hz', 0):.6g} Hz"],
                    ["bursts", f"{len(bursts)}"],
                    ["gaps", (f"{len(gaps)}, {min(gaps):.4g} to {max(gaps):.4g} s" if gaps else "none")],
                    ["time jitter (rms)", f"{float(rec.attrs.get('time_jitter_rms_percent', 0.0)):.3g} % of the period"],
                    ["resampled to a uniform grid", "yes" if any(b.resampled for b in bursts) else "no"],
                    ["clipping", f"{clip_n} samples at the extremes" + (" (suspected)" if clipped else "")],
                    ["non-finite samples", f"{int(np.sum(~np.isfinite(rec[ch].values)))}"]]
            _table(ax, rows, (0.4, 0.6), 9)
            hist = str(rec.attrs.get("history", "")).split("\n")
            fig.text(0.06, 0.5, "Reader's decisions:", fontsize=10, fontweight="bold")
            fig.text(0.06, 0.48, "\n".join(textwrap.fill("- " + h, 100) for h in hist[:20]), fontsize=8, va="top")
            emit(fig, "data quality")

            # 9 parameters
            fig = plt.figure(figsize=_PAGE)
            _page_title(fig, "Parameters", "everything needed to repeat this report")
            rows = [["channel", ch], ["speed", _fmt(speed, "m/s")], ["speed sigma", _fmt(float(speed_sigma), "m/s")],
                    ["nominal pitch", _fmt(nominal_pitch, "m")], ["limits", " / ".join(f"{v:g} %" for v in limits)],
                    ["search band", (f"{pitch.band_hz[0]:.4g} - {pitch.band_hz[1]:.4g} Hz" if pitch else str(band))],
                    ["Hampel half window", f"{hampel_half_window_s:g} s"],
                    ["Hampel false-alarm rate", f"{hampel_false_alarm_rate:g} per sample"],
                    ["simulated duration", _fmt(duration, "s") if duration else "scene's"]]
            ax = fig.add_axes((0.06, 0.62, 0.88, 0.3))
            _table(ax, rows, (0.4, 0.6), 9)
            if sc is not None:
                lines = [ln for ln in sc.text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")][:48]
                fig.text(0.06, 0.58, f"Scene {os.path.basename(sc.source)}:", fontsize=10, fontweight="bold")
                fig.text(0.06, 0.565, "\n".join(ln[:100] for ln in lines), fontsize=6.5, family="monospace",
                         va="top")
            emit(fig, "parameters")
    return Report(out, pages, pitch, comp, summary)


# ------------------------------------------------------------------------------------ fleet page

#: units drawn on the fleet page (the most urgent ones; the rest are listed by ``vibkit fleet status``)
FLEET_PAGE_MAX_UNITS = 24


def write_fleet_report(trends, measurements, out_path, *, limits_percent=None, database="",
                       max_units=FLEET_PAGE_MAX_UNITS) -> Report:
    """One PDF page of a fleet: elongation against date per unit, with the limits as lines.

    Parameters
    ----------
    trends : list of vibkit.fleet.history.UnitTrend
        Ranked (most urgent first), as :meth:`vibkit.fleet.history.FleetDB.status` returns them.
    measurements : list of vibkit.fleet.history.Measurement
        The stored measurements (error bars: their elongation sigma).
    out_path : str or os.PathLike
        PDF written atomically (the caller decides whether an existing file may be replaced).
    limits_percent : (float, float, float), optional
        Elongation limits [%] (default 1.5, 2, 3).
    database : str
        Named in the page's subtitle.
    max_units : int
        Panels drawn (the most urgent units); the page says how many were left out.

    Returns
    -------
    Report
        ``summary`` holds ``units`` and ``units_drawn``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.dates as mdates
    import matplotlib.pyplot as plt
    from matplotlib.backends.backend_pdf import PdfPages

    from .. import __version__

    limits = tuple(limits_percent) if limits_percent is not None else (1.5, 2.0, 3.0)
    out = os.fspath(out_path)
    shown = list(trends)[: int(max_units)]
    by_unit = {}
    for m in measurements:
        by_unit.setdefault(m.unit, []).append(m)
    date = report_date()
    n = len(shown)
    ncol = 1 if n <= 1 else 2 if n <= 4 else 3 if n <= 9 else 4
    nrow = max(1, math.ceil(n / ncol))
    colors = ("#d4a017", "#e0661b", "#b2182b")
    pages = []

    def utc(text):
        return _dt.datetime.fromisoformat(text.replace("Z", "+00:00"))

    meta = {"Title": "vibkit fleet report", "Author": f"vibkit {__version__}",
            "Subject": "escalator step-chain elongation trends", "Creator": f"vibkit {__version__}",
            "CreationDate": date, "ModDate": date}
    with matplotlib.rc_context({"pdf.compression": 6, "font.size": 7, "axes.titlesize": 8,
                                "svg.hashsalt": "vibkit", "path.simplify": True}):
        with atomic_path(out, ".pdf") as tmp, PdfPages(tmp, metadata=meta) as pdf:
            fig = plt.figure(figsize=_WIDE)
            _page_title(fig, "Fleet: step-chain elongation against date",
                        f"{len(trends)} unit(s), {len(measurements)} measurement(s), most urgent first; limits "
                        f"{' / '.join(f'{v:g}' for v in limits)} % (dashed); database "
                        f"{os.path.basename(str(database))}; {date:%Y-%m-%d}, vibkit {__version__}")
            fig.text(0.06, 0.035, "points: measurements with 1-sigma error bars; line: weighted least-squares trend; "
                     "bar: 2-sigma interval of the date the next limit is reached", fontsize=7.5, color="0.3")
            gs = fig.add_gridspec(nrow, ncol, left=0.06, right=0.98, top=0.90, bottom=0.08, hspace=0.55, wspace=0.25)
            for i, tr in enumerate(shown):
                ax = fig.add_subplot(gs[i // ncol, i % ncol])
                ms = sorted(by_unit.get(tr.unit, []), key=lambda m: m.date_unix_s)
                x = [utc(m.date_utc) for m in ms]
                ax.errorbar(x, [m.elongation_percent for m in ms], yerr=[m.elongation_sigma_percent for m in ms],
                            fmt="o", ms=2.5, color="k", elinewidth=0.8, capsize=1.5)
                t_end = ms[-1].date_unix_s
                fit = getattr(tr, "fit", None)
                if fit is not None and fit.slope_percent_per_year > 0:
                    nxt = [f for f in tr.forecasts if f.status == "forecast" and f.date_utc]
                    if nxt:
                        t_end = max(t_end, min(utc(nxt[0].latest_utc or nxt[0].date_utc).timestamp(),
                                               t_end + 5 * 365.25 * 86400))
                if fit is not None:
                    tt = np.linspace(ms[0].date_unix_s, t_end, 50)
                    ax.plot([_dt.datetime.fromtimestamp(v, tz=_dt.timezone.utc) for v in tt], fit.elongation_at(tt),
                            color="tab:blue", lw=1.0)
                for lim, c in zip(limits, colors):
                    ax.axhline(lim, color=c, lw=0.9, ls="--")
                # the next limit's forecast interval, as a bar on its line
                nxt = [f for f in tr.forecasts if f.status == "forecast" and f.earliest_utc and f.latest_utc]
                if nxt and utc(nxt[0].latest_utc).timestamp() <= t_end + 1.0:
                    ax.plot([utc(nxt[0].earliest_utc), utc(nxt[0].latest_utc)], [nxt[0].limit_percent] * 2,
                            color="tab:blue", lw=3.0, alpha=0.5, solid_capstyle="butt")
                slope = ("no trend" if tr.slope_percent_per_year is None else
                         f"{tr.slope_percent_per_year:+.3f} +- {tr.slope_sigma_percent_per_year:.3f} %/yr")
                ax.set_title(f"#{tr.rank} {tr.unit}: {slope}", loc="left")
                loc = mdates.AutoDateLocator(minticks=2, maxticks=6)
                ax.xaxis.set_major_locator(loc)
                ax.xaxis.set_major_formatter(mdates.ConciseDateFormatter(loc))
                ax.set_ylim(min(-0.2, min(m.elongation_percent for m in ms) - 0.2),
                            max(limits[-1] * 1.15, max(m.elongation_percent for m in ms) + 0.2))
                if i % ncol == 0:
                    ax.set_ylabel("elongation [%]")
                ax.grid(True, lw=0.3, alpha=0.5)
            if len(trends) > n:
                fig.text(0.06, 0.015, f"{len(trends) - n} less urgent unit(s) not drawn; `vibkit fleet status` lists "
                         "all of them", fontsize=8, color="0.3")
            pages.append(("fleet", _texts(fig)))
            pdf.savefig(fig)
            plt.close(fig)
    return Report(out, pages, summary={"units": len(trends), "units_drawn": n})


__all__ += ["write_fleet_report"]
