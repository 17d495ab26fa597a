"""The report's signal pages: the time signal with its spikes (Hampel events), the amplitude spectrum
with link-pass harmonic markers, the spectrogram, and the order spectrum."""

from __future__ import annotations

import numpy as np

from ...signal import amplitude_spectrum, order_spectrum, resample_to_angle, spectrogram
from .common import _WIDE, _page_title, length_scale

__all__ = ["time_signal_page", "spectrum_page", "spectrogram_page", "order_spectrum_page"]


def _scale(ctx):
    """The signal pages' common plotting unit: from the largest value over the bursts."""
    peak = max((float(np.nanmax(np.abs(b.x))) for b in ctx.bursts if b.x.size), default=float("nan"))
    return length_scale(ctx.units, peak)


def time_signal_page(doc, ctx) -> None:
    """Every burst at its own time; the spikes circled."""
    import matplotlib.pyplot as plt

    events, rec, ch = ctx.events, ctx.rec, ctx.channel
    fig, ax = plt.subplots(figsize=_WIDE)
    fig.subplots_adjust(left=0.08, right=0.97, top=0.88, bottom=0.1)
    _page_title(
        fig,
        "Time signal",
        f"{len(ctx.bursts)} burst(s); red: spikes (Hampel events on the residual "
        f"after the link-pass family, half window {ctx.hampel_half_window_s:g} s, false-alarm rate "
        f"{ctx.hampel_false_alarm_rate:g})",
    )
    k, unit = _scale(ctx)
    for b in ctx.bursts:
        t = b.t0 + np.arange(b.x.size) / b.fs
        ax.plot(t, k * b.x, lw=0.5, color="C0")
    if events:
        ax.plot(
            [e[0] for e in events],
            [k * e[1] for e in events],
            "o",
            mfc="none",
            color="C3",
            ms=8,
            label=f"{len(events)} spike(s)",
        )
        ax.legend(loc="upper right")
    ax.set_xlabel("time [s]")
    ax.set_ylabel(f"{rec[ch].attrs.get('long_name', ch)} [{unit}]")
    ax.grid(alpha=0.3)
    doc.emit(fig, "time signal")


def spectrum_page(doc, ctx) -> None:
    """Hann-windowed amplitude spectrum averaged over the bursts, harmonics of the link pass dotted."""
    import matplotlib.pyplot as plt

    bursts, f0 = ctx.bursts, ctx.f0
    fig, ax = plt.subplots(figsize=_WIDE)
    fig.subplots_adjust(left=0.08, right=0.97, top=0.88, bottom=0.1)
    _page_title(fig, "Spectrum", "Hann-windowed amplitude spectrum averaged over bursts; dotted: link-pass harmonics")
    nh = ctx.harmonic_count
    fmax = ctx.fmax_hz
    nfft = 1 << int(np.ceil(np.log2(max(b.x.size for b in bursts))))
    fgrid = np.linspace(0, fmax, 2000)
    acc = None
    for b in bursts:
        f, a = amplitude_spectrum(b.x, b.fs, nfft=max(nfft, b.x.size))
        a = np.interp(fgrid, f, a)
        acc = a if acc is None else acc + a
    k, unit = _scale(ctx)
    ax.semilogy(fgrid, np.maximum(k * acc / len(bursts), 1e-30), lw=0.9)
    for h in range(1, nh + 1):
        ax.axvline(h * f0, color="C3", ls=":", lw=1)
        ax.text(h * f0, 1.0, f" {h}x", transform=ax.get_xaxis_transform(), va="top", fontsize=8, color="C3")
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
