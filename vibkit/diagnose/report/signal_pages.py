"""The report's signal pages: the time signal with its spikes (Hampel events), the amplitude spectrum
with link-pass harmonic markers, the spectrogram, and the order spectrum."""

from __future__ import annotations

import numpy as np

from ...signal import amplitude_spectrum, order_spectrum, resample_to_angle, spectrogram
from .common import _WIDE, _page_title, length_scale

__all__ = ["time_signal_page", "spectrum_page", "spectrogram_page", "order_spectrum_page", "envelope"]


def _scale(ctx):
    """The signal pages' common plotting unit: from the largest value over the bursts."""
    peak = max((float(np.nanmax(np.abs(b.x))) for b in ctx.bursts if b.x.size), default=float("nan"))
    return length_scale(ctx.units, peak)


#: link-pass cycles in the time signal page's zoom, and in each frame of the spectrum page's average
ZOOM_CYCLES = 6
FRAME_CYCLES = 40


def zoom_span(ctx):
    """(start, end) [s] of the time signal page's zoom: :data:`ZOOM_CYCLES` link passes in the middle of the
    longest burst (2 s without a link pass)."""
    b = max(ctx.bursts, key=lambda b: b.x.size)
    length = b.x.size / b.fs
    span = min(length, ZOOM_CYCLES / ctx.f0 if ctx.found and ctx.f0 > 0 else 2.0)
    mid = b.t0 + length / 2
    return mid - span / 2, mid + span / 2


#: columns per inch of the time signal's overview in which a long signal is drawn as its envelope (print resolution)
ENVELOPE_COLUMNS_PER_INCH = 300


def envelope(t, x, columns):
    """``(t, x)`` cut to the least and the largest sample of each of ``columns`` spans, each pair at its own
    times and in time order: drawn as a line, what every sample drawn would show at ``columns`` across the
    axes (every extreme, a spike included, where it is), in a fraction of the points.  A signal of at most two
    samples a column, or with a gap (NaN), is returned whole."""
    x = np.asarray(x)
    m = -(-x.size // max(1, int(columns)))  # samples a column (the last column may have fewer)
    if m <= 2 or not np.isfinite(x).all():
        return t, x
    k = x.size // m
    lo = np.argmin(x[: k * m].reshape(k, m), axis=1) + m * np.arange(k)
    hi = np.argmax(x[: k * m].reshape(k, m), axis=1) + m * np.arange(k)
    if x.size > k * m:  # the last, shorter column
        lo = np.append(lo, k * m + np.argmin(x[k * m :]))
        hi = np.append(hi, k * m + np.argmax(x[k * m :]))
    idx = np.sort(np.stack([lo, hi], axis=1), axis=1).ravel()
    return t[idx], x[idx]


def time_signal_page(doc, ctx) -> None:
    """Every burst at its own time, the spikes circled (above); a few link passes of it (below)."""
    import matplotlib.pyplot as plt

    events, rec, ch = ctx.events, ctx.rec, ctx.channel
    fig, (ax, zx) = plt.subplots(2, 1, figsize=_WIDE, gridspec_kw={"height_ratios": [1, 1]})
    fig.subplots_adjust(left=0.08, right=0.97, top=0.86, bottom=0.08, hspace=0.32)
    _page_title(
        fig,
        "Time signal",
        f"{len(ctx.bursts)} burst(s); above: the whole recording, red circles: spikes (Hampel events on the "
        f"residual after the link-pass family, half window {ctx.hampel_half_window_s:g} s, false-alarm rate "
        f"{ctx.hampel_false_alarm_rate:g} a sample); below: the shaded span, "
        + (f"{ZOOM_CYCLES} link passes" if ctx.found else "2 s (no link pass found)"),
    )
    k, unit = _scale(ctx)
    t0z, t1z = zoom_span(ctx)
    label = f"{rec[ch].attrs.get('long_name', ch)} [{unit}]"
    # the overview's columns at print resolution over the time from the first burst's start to the last's end
    span = max(b.t0 + b.x.size / b.fs for b in ctx.bursts) - min(b.t0 for b in ctx.bursts)
    columns = ENVELOPE_COLUMNS_PER_INCH * ax.get_position().width * fig.get_size_inches()[0]
    for b in ctx.bursts:
        t = b.t0 + np.arange(b.x.size) / b.fs
        ax.plot(*envelope(t, k * b.x, columns * (b.x.size / b.fs) / span), lw=0.5, color="C0")
        sel = (t >= t0z) & (t <= t1z)
        if sel.any():
            zx.plot(t[sel], k * b.x[sel], lw=0.9, color="C0", marker=".", ms=2)
    ax.axvspan(t0z, t1z, color="C1", alpha=0.3, lw=0)
    ax.set_title(
        f"the whole recording: {len(events)} spike(s) circled; chance alone gives about {ctx.spikes_expected:.2g}",
        loc="left",
        fontsize=9,
    )
    if events:
        ax.plot(
            [e[0] for e in events],
            [k * e[1] for e in events],
            "o",
            mfc="none",
            color="C3",
            ms=8,
        )
        inside = [e for e in events if t0z <= e[0] <= t1z]
        if inside:
            zx.plot([e[0] for e in inside], [k * e[1] for e in inside], "o", mfc="none", color="C3", ms=8)
    if ctx.found:
        # one tick a link pass from the span's start: each cycle readable against it
        zx.set_xticks(t0z + np.arange(ZOOM_CYCLES + 1) / ctx.f0)
        zx.xaxis.set_major_formatter(plt.FormatStrFormatter("%.2f"))
    zx.set_xlim(t0z, t1z)
    ax.set_xlabel("time [s]")
    zx.set_xlabel("time [s]" + (f" (ticks one link pass apart, {1 / ctx.f0:.3g} s)" if ctx.found else ""))
    ax.set_ylabel(label)
    zx.set_ylabel(label)
    for a in (ax, zx):
        a.grid(alpha=0.3)
    doc.emit(fig, "time signal")


def averaged_spectrum(ctx):
    """(f, amplitude) of the spectrum page: flat-top windowed frames of :data:`FRAME_CYCLES` link passes (the
    whole burst where shorter), half overlapping, their amplitudes averaged over every frame of every burst.

    A flat-top window reads a line's amplitude to 0.1 dB wherever it falls between bins, and frames a few
    dozen link passes long keep a wandering speed's line in one bin: the peak drawn is the line's amplitude,
    as the harmonics' table gives it (a Hann spectrum of a whole long record read the line many times lower,
    spread over bins the speed's wander had smeared it across).
    """
    f_ref, total, weight = None, None, 0
    for b in ctx.bursts:
        cycles = FRAME_CYCLES / ctx.f0 if ctx.f0 > 0 else b.x.size / b.fs
        n = min(b.x.size, max(16, int(round(cycles * b.fs))))
        if b.x.size < 16:
            continue
        frames = np.lib.stride_tricks.sliding_window_view(b.x, n)[:: max(1, n // 2)]
        # zero-padded four times: a short burst's lobes drawn smooth, not as a few straight segments
        f, a = amplitude_spectrum(frames, b.fs, window="flattop", axis=-1, nfft=1 << int(np.ceil(np.log2(4 * n))))
        a = a.mean(axis=0)
        if f_ref is None:
            f_ref, total = f, a * len(frames)
        else:
            total = total + np.interp(f_ref, f, a) * len(frames)
        weight += len(frames)
    return f_ref, total / weight


def _max_hold(f, a, fmax, cells=3000):
    """``(f, a)`` up to ``fmax`` cut to at most ``cells`` points, each the largest of its cell: no line is
    lost between the points drawn."""
    sel = f <= fmax
    f, a = f[sel], a[sel]
    if f.size <= cells:
        return f, a
    edges = np.linspace(0, f.size, cells + 1).astype(int)
    idx = np.array([lo + int(np.argmax(a[lo:hi])) for lo, hi in zip(edges[:-1], edges[1:]) if hi > lo])
    return f[idx], a[idx]


def spectrum_page(doc, ctx) -> None:
    """Flat-top amplitude spectrum averaged over frames (:func:`averaged_spectrum`), harmonics of the link
    pass dotted and their fitted amplitudes (the tables' and ``vibkit pitch``'s) marked."""
    import matplotlib.pyplot as plt

    f0 = ctx.f0
    fig, ax = plt.subplots(figsize=_WIDE)
    fig.subplots_adjust(left=0.08, right=0.97, top=0.86, bottom=0.1)
    _page_title(
        fig,
        "Spectrum",
        f"amplitude spectrum: flat-top window, frames of {FRAME_CYCLES} link passes averaged over the recording, "
        "so a line's peak reads its amplitude; dotted: link-pass harmonics; crosses: each harmonic's fitted "
        "amplitude, as vibkit pitch and the tables give it",
    )
    nh = ctx.harmonic_count
    fmax = ctx.fmax_hz
    f, a = averaged_spectrum(ctx)
    k, unit = _scale(ctx)
    fd, ad = _max_hold(f, a, fmax)
    ax.semilogy(fd, np.maximum(k * ad, 1e-30), lw=0.9, label="spectrum")
    for h in range(1, nh + 1):
        ax.axvline(h * f0, color="C3", ls=":", lw=1)
        ax.text(h * f0, 1.0, f" {h}x", transform=ax.get_xaxis_transform(), va="top", fontsize=8, color="C3")
    fitted = [h for h in (ctx.pitch.harmonics if ctx.pitch is not None else []) if h.get("amplitude")]
    if fitted:
        ax.plot(
            [h["frequency_hz"] for h in fitted],
            [k * h["amplitude"] for h in fitted],
            "x",
            color="C3",
            ms=8,
            mew=1.5,
            label="fitted amplitude",
        )
        lines = [
            f"{h['order']}x: {k * h['amplitude']:.3g} {unit}" + ("" if h.get("detected", True) else " (not detected)")
            for h in fitted
        ]
        ax.text(
            0.99,
            0.9,
            "fitted amplitudes\n" + "\n".join(lines),
            transform=ax.transAxes,
            ha="right",
            va="top",
            fontsize=8,
            bbox={"boxstyle": "round", "fc": "white", "ec": "0.7"},
        )
        ax.legend(loc="upper left", fontsize=8)
    ax.set_xlim(0, fmax)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(f"amplitude [{unit}]")
    ax.grid(alpha=0.3)
    doc.emit(fig, "spectrum")


def spectrogram_page(doc, ctx) -> None:
    """Spectrogram of every burst at its own time, one colour scale (60 dB)."""
    import matplotlib.pyplot as plt

    bursts, fmax = ctx.bursts, ctx.fmax_hz
    fig, ax = plt.subplots(figsize=_WIDE)
    fig.subplots_adjust(left=0.08, right=0.95, top=0.88, bottom=0.1)
    frame = min(4.0, min(b.x.size / b.fs for b in bursts) / 2)
    _page_title(fig, "Spectrogram", f"frames of {frame:.2g} s, 75 % overlap; bursts at their own times")
    k, unit = _scale(ctx)
    vmax = None
    ims = []
    for b in bursts:
        nper = max(16, int(round(frame * b.fs)))
        fr, tt, s = spectrogram(b.x, b.fs, nperseg=nper, noverlap=nper * 3 // 4)
        sel = fr <= fmax
        db = 20 * np.log10(np.maximum(k * s[sel], 1e-30))
        vmax = db.max() if vmax is None else max(vmax, db.max())
        ims.append((b.t0 + tt, fr[sel], db))
    for tt, fr, db in ims:
        im = ax.pcolormesh(tt, fr, db, shading="nearest", vmin=vmax - 60, vmax=vmax, cmap="viridis", rasterized=True)
    cb = fig.colorbar(im, ax=ax, pad=0.01)
    cb.set_label(f"amplitude [dB re 1 {unit}]")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("frequency [Hz]")
    doc.emit(fig, "spectrogram")


def order_spectrum_page(doc, ctx) -> None:
    """Bursts resampled to constant link-pass phase; order 1 = link pass, 1/k = step pass (k links a step)."""
    import matplotlib.pyplot as plt

    if not ctx.found:  # no link pass: nothing to resample to (the band's centre would be drawn as if it were one)
        return
    bursts, f0, nh = ctx.bursts, ctx.f0, ctx.harmonic_count
    lps = getattr(ctx, "links_per_step", 3)
    fig, ax = plt.subplots(figsize=_WIDE)
    fig.subplots_adjust(left=0.08, right=0.97, top=0.88, bottom=0.1)
    _page_title(
        fig,
        "Order spectrum",
        f"resampled to constant link-pass phase ({f0:.5g} Hz); order 1 = link pass, 1/{lps} = step pass",
    )
    spc = 32
    k, unit = _scale(ctx)
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
        ax.semilogy(o_ref[sel], np.maximum(k * acc[sel] / len(bursts), 1e-30), lw=0.9)
        for h in range(1, nh + 1):
            ax.axvline(h, color="C3", ls=":", lw=1)
        ax.axvline(1 / lps, color="C2", ls="--", lw=1, label=f"step pass (1/{lps})")
        ax.legend(loc="upper right")
    ax.set_xlabel("order [cycles per link]")
    ax.set_ylabel(f"amplitude [{unit}]")
    ax.grid(alpha=0.3)
    doc.emit(fig, "order spectrum")
