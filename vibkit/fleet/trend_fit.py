"""A unit's elongation against time: the weighted straight-line fit every trend and screening stands on.

:func:`fit_trend` fits the elongation [%] against the date by weighted least squares, the rate in percent per Julian
year (:data:`SECONDS_PER_YEAR`); :mod:`vibkit.fleet.segments` screens with it and :mod:`vibkit.fleet.trends`
forecasts from it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["SECONDS_PER_YEAR", "TrendFit", "fit_trend"]

SECONDS_PER_YEAR = 365.25 * 86400.0


@dataclass(frozen=True)
class TrendFit:
    """Weighted least-squares line ``e(t) = e_ref + slope (t - t_ref)`` of elongation against time.

    Attributes
    ----------
    n : int
        Measurements fitted.
    t_ref_unix_s : float
        Reference time: the weighted mean of the times (there intercept and slope are uncorrelated).
        [s since 1970]
    elongation_ref_percent, elongation_ref_sigma_percent : float
        Fitted elongation at ``t_ref`` and its standard deviation. [%]
    slope_percent_per_year, slope_sigma_percent_per_year : float
        Elongation rate and its standard deviation. [%/year]
    chi2_per_dof : float
        Weighted residual sum over ``n - 2`` (NaN for two measurements).
    sigma_scale : float
        Factor applied to the sigmas: ``max(1, sqrt(chi2_per_dof))`` (1 for two measurements).
    """

    n: int
    t_ref_unix_s: float
    elongation_ref_percent: float
    elongation_ref_sigma_percent: float
    slope_percent_per_year: float
    slope_sigma_percent_per_year: float
    chi2_per_dof: float
    sigma_scale: float

    def elongation_at(self, t_unix_s):
        """Fitted elongation at times [s since 1970]. [%]"""
        return self.elongation_ref_percent + self.slope_percent_per_year * (
            (np.asarray(t_unix_s, dtype=float) - self.t_ref_unix_s) / SECONDS_PER_YEAR
        )


def fit_trend(t_unix_s, elongation_percent, sigma_percent) -> TrendFit:
    """Weighted least-squares trend of elongation against time, with the slope's uncertainty.

    Parameters
    ----------
    t_unix_s : array_like
        Measurement times. [s since 1970]
    elongation_percent : array_like
        Elongations. [%]
    sigma_percent : array_like
        Their standard deviations (> 0). [%]

    Returns
    -------
    TrendFit

    Raises
    ------
    ValueError
        Fewer than two measurements, arrays of different lengths, non-finite values, a sigma that is
        not positive, or all measurements at the same time.

    Notes
    -----
    With weights ``w_i = 1 / sigma_i^2``, ``t_ref = sum(w t) / sum(w)`` and ``tau = (t - t_ref)`` in
    years:

        slope = sum(w tau e) / sum(w tau^2),   e_ref = sum(w e) / sum(w),
        sigma_slope^2 = 1 / sum(w tau^2),      sigma_ref^2 = 1 / sum(w).

    When the residuals scatter more than the sigmas allow (``chi2 / (n - 2) > 1``: speed errors,
    sensor moved between visits), both sigmas are multiplied by ``sqrt(chi2 / (n - 2))`` (the Birge
    ratio); they are never reduced.
    """
    t = np.asarray(t_unix_s, dtype=float).ravel()
    e = np.asarray(elongation_percent, dtype=float).ravel()
    s = np.asarray(sigma_percent, dtype=float).ravel()
    if not t.size == e.size == s.size:
        raise ValueError(
            f"t_unix_s, elongation_percent and sigma_percent must have the same length, got "
            f"{t.size}, {e.size}, {s.size}"
        )
    if t.size < 2:
        raise ValueError(f"a trend needs at least two measurements, got {t.size}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(e)) and np.all(np.isfinite(s))):
        raise ValueError("t_unix_s, elongation_percent and sigma_percent must be finite")
    if np.any(s <= 0):
        raise ValueError(f"sigma_percent must be > 0, got {s[s <= 0][0]!r}")
    w = 1.0 / s**2
    t_ref = float(np.sum(w * t) / np.sum(w))
    tau = (t - t_ref) / SECONDS_PER_YEAR
    stt = float(np.sum(w * tau**2))
    if not stt > 0 or np.ptp(t) < 1.0:
        raise ValueError("a trend needs measurements at different times (all share one date)")
    e_ref = float(np.sum(w * e) / np.sum(w))
    slope = float(np.sum(w * tau * (e - e_ref)) / stt)
    chi2 = float(np.sum(w * (e - e_ref - slope * tau) ** 2))
    dof = t.size - 2
    chi2_dof = chi2 / dof if dof > 0 else float("nan")
    scale = max(1.0, math.sqrt(chi2_dof)) if dof > 0 else 1.0
    return TrendFit(
        int(t.size), t_ref, e_ref, scale / math.sqrt(float(np.sum(w))), slope, scale / math.sqrt(stt), chi2_dof, scale
    )
