"""Irregular time stamps: whether the way a burst was put on a uniform grid changes its link-pass estimate.

A step of :func:`vibkit.diagnose.pitch.estimate_pitch` (:mod:`vibkit.diagnose.pitch_steps` names the order).
"""

from __future__ import annotations

import numpy as np

from ..signal import link_pass_estimate
from ..signal.bursts import segment_numbers


def jitter_effect(recording, name, ests, band, n_harmonics):
    """``(warnings, notes)`` on irregular time stamps.  A burst with irregular stamps was resampled linearly to
    a uniform grid; it is resampled again with a cubic spline and estimated again: a warning only when the two
    frequencies differ by more than the burst's sigma (the handling of the stamps then changes the estimate),
    else a note."""
    from scipy.interpolate import CubicSpline

    warnings, notes = [], []
    t_all = np.asarray(recording["time"].values, dtype=float)
    x_all = np.asarray(recording[name].values, dtype=float)
    seg = segment_numbers(recording)
    for be in ests:
        b = be.scaled  # the burst at its recorded grid (a long record's estimates used a decimated copy)
        if not b.resampled:
            continue
        grid = b.t0 + np.arange(b.x.size) / b.fs
        keep = (t_all >= grid[0]) & (t_all <= grid[-1]) & np.isfinite(x_all)
        if seg is not None:
            keep &= np.asarray(seg) == b.segment
        t, idx = np.unique(t_all[keep], return_index=True)
        if t.size < 16:
            continue
        try:
            xs = CubicSpline(t, x_all[keep][idx])(np.clip(grid, t[0], t[-1]))
            alt = link_pass_estimate(xs, b.fs, band=band, n_harmonics=n_harmonics)
        except ValueError:
            continue
        f, sf = be.spectral.fundamental_hz, be.spectral.fundamental_sigma_hz
        delta = abs(alt.fundamental_hz - f)
        text = (
            f"burst {b.segment}: irregular time stamps, resampled to a uniform grid; resampled with a cubic spline "
            f"instead, the link pass moves by {delta:.2g} Hz against its sigma {sf:.2g} Hz"
        )
        (warnings if delta > sf else notes).append(text + (": the stamps are too irregular" if delta > sf else ""))
    return warnings, notes
