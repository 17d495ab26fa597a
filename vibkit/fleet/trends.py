"""Elongation trends of a unit and forecasts of when it reaches each limit (pure functions, no database).

:func:`~vibkit.fleet.trend_fit.fit_trend` (re-exported here) fits the elongation against time by weighted least
squares, :func:`forecast_limits`
gives the dates at which each elongation limit will be reached, :func:`unit_trend` sums a unit's
measurements up as a :class:`UnitTrend` and :func:`rank_units` ranks the units by urgency (the work
list).  Only the measurements that :func:`vibkit.fleet.segments.screen_unit` keeps are fitted: flagged
ones (implausible, inconclusive), outliers (> 5 sigma from the trend of the others) and those before a
chain replacement are shown and listed, never fitted.  A rate that is negative beyond its uncertainty
(a chain that gets shorter) is reported ``"implausible"`` and not forecast.  Trends are in percent per
Julian year (365.25 days).
"""

from __future__ import annotations

import datetime as _dt
import math
from dataclasses import asdict, dataclass

from ..diagnose.pitch import DEFAULT_LIMITS_PERCENT, elongation_verdict
from .dates import _unix_to_iso
from .segments import screen_unit
from .trend_fit import SECONDS_PER_YEAR, TrendFit, fit_trend

__all__ = [
    "LimitForecast",
    "SECONDS_PER_YEAR",
    "TrendFit",
    "UnitTrend",
    "fit_trend",
    "forecast_limits",
    "rank_units",
    "unit_trend",
]

#: no rate and no forecast from usable visits spanning less than this [days]: within a month a chain's wear is far
#: below what a measurement resolves, so a slope would be noise divided by a short time
MIN_TREND_SPAN_DAYS = 30.0
#: a rate below zero by more than this many of its sigmas is implausible (a chain does not shorten)
IMPLAUSIBLE_RATE_SIGMA = 3.0
#: a rate below zero by more than this many of its sigmas (but not implausible) is flagged for a check
DOUBTFUL_RATE_SIGMA = 2.0


@dataclass(frozen=True)
class LimitForecast:
    """When a unit reaches one elongation limit.

    Attributes
    ----------
    limit_percent : float
        [%]
    status : str
        ``"reached"`` (the latest measurement is at or over the limit), ``"forecast"`` (the slope is
        significantly positive: a date and an interval), ``"not before"`` (the slope is not
        significantly positive but may be: only the earliest date is known), ``"none"`` (no
        growth within the uncertainty, or fewer than two measurements) or ``"implausible"`` (the
        rate is negative beyond its uncertainty: no forecast from it).
    date_utc : str or None
        Forecast date where the fitted line reaches the limit (``"forecast"``).
    earliest_utc, latest_utc : str or None
        The interval from the slope's (and the intercept's) ``coverage_sigma`` bounds.
    """

    limit_percent: float
    status: str
    date_utc: str | None = None
    earliest_utc: str | None = None
    latest_utc: str | None = None

    def overdue(self, today_unix_s) -> bool:
        """Whether the forecast date has passed on ``today_unix_s``: the limit was probably reached since the
        last measurement (``"forecast"``), or may have been (``"not before"`` a date now past): re-measure."""
        if self.status == "forecast":
            return self.date_utc is not None and self.urgency_unix_s() <= today_unix_s
        if self.status == "not before":
            return self.earliest_utc is not None and self.urgency_unix_s() <= today_unix_s
        return False

    def urgency_unix_s(self):
        """Date used to rank units: the forecast, else the earliest date; +inf without one."""
        d = self.date_utc or self.earliest_utc
        return _dt.datetime.fromisoformat(d).timestamp() if d else math.inf


def forecast_limits(fit, limits_percent=DEFAULT_LIMITS_PERCENT, *, latest_elongation_percent=None, coverage_sigma=2.0):
    """Dates at which the fitted trend reaches each elongation limit, with an interval.

    Parameters
    ----------
    fit : TrendFit or None
        The unit's trend (None: fewer than two measurements, every limit not reached is ``"none"``).
    limits_percent : sequence of float
        Elongation limits. [%]
    latest_elongation_percent : float, optional
        The latest measured elongation; a limit it reaches is ``"reached"``. [%]
    coverage_sigma : float
        Half-width of the intervals in standard deviations (2: about 95 %).

    Returns
    -------
    tuple of LimitForecast

    Notes
    -----
    The slope is *significantly positive* when ``slope > k sigma_slope`` (``k = coverage_sigma``).
    Then the forecast is ``t_ref + (L - e_ref) / slope`` and the interval the extreme crossing times
    of the lines with ``e_ref +- k sigma_ref`` and ``slope +- k sigma_slope``.  When only
    ``slope + k sigma_slope > 0``, the limit is reached *not before* the crossing of the steepest of
    those lines; when even that is not positive, no date is given.
    """
    k = float(coverage_sigma)
    if not (math.isfinite(k) and k > 0):
        raise ValueError(f"coverage_sigma must be > 0, got {coverage_sigma!r}")
    out = []
    for lim in limits_percent:
        lim = float(lim)
        if latest_elongation_percent is not None and latest_elongation_percent >= lim:
            out.append(LimitForecast(lim, "reached"))
            continue
        if fit is None:
            out.append(LimitForecast(lim, "none"))
            continue
        b, sb = fit.slope_percent_per_year, fit.slope_sigma_percent_per_year
        a, sa = fit.elongation_ref_percent, fit.elongation_ref_sigma_percent
        year = SECONDS_PER_YEAR

        def cross(a_, b_):
            return fit.t_ref_unix_s + (lim - a_) / b_ * year

        if b > k * sb:
            corners = [cross(a_, b_) for a_ in (a - k * sa, a + k * sa) for b_ in (b - k * sb, b + k * sb)]
            out.append(
                LimitForecast(
                    lim, "forecast", _unix_to_iso(cross(a, b)), _unix_to_iso(min(corners)), _unix_to_iso(max(corners))
                )
            )
        elif b + k * sb > 0:
            out.append(LimitForecast(lim, "not before", None, _unix_to_iso(cross(a + k * sa, b + k * sb)), None))
        else:
            out.append(LimitForecast(lim, "none"))
    return tuple(out)


@dataclass(frozen=True)
class UnitTrend:
    """The state of one unit: latest measurement, elongation trend and limit forecasts.

    Attributes
    ----------
    unit : str
    n_measurements : int
    first_date_utc, latest_date_utc : str
    nominal_pitch_m : float
        [m]
    latest_elongation_percent, latest_elongation_sigma_percent : float
        [%]
    latest_verdict : str
        :func:`vibkit.diagnose.pitch.elongation_verdict` of the latest elongation.
    slope_percent_per_year, slope_sigma_percent_per_year : float or None
        Elongation rate and its standard deviation (None with one measurement or one date). [%/year]
    chi2_per_dof : float or None
    over_limit_percent : float or None
        The highest limit the latest measurement reaches. [%]
    forecasts : tuple of LimitForecast
    rank : int
        1 = most urgent.
    rate_verdict : str
        ``"growing"`` (rate > 2 sigma), ``"flat"`` (not significantly positive), ``"implausible"``
        (negative beyond 3 sigma: a measurement problem; re-measure), ``"too few"`` (fewer than two
        usable measurements at different dates).
    n_used : int
        Measurements fitted (the current segment, without flagged ones and outliers).
    segment_start_utc : str or None
        Date of the chain replacement that starts the current segment (None: one segment).
    outliers : tuple of dict
        ``id``, ``date_utc``, ``elongation_percent``, ``sigma_percent``, ``deviation_sigma``.
    flagged : tuple of dict
        Measurements left out for their quality: ``id``, ``date_utc``, ``quality``, ``reason``.
    replacements : tuple of dict
        ``id``, ``date_utc``, ``reason`` of every measurement that starts a segment.
    point_labels : tuple of (int, str)
        ``(id, label)`` of every measurement (see :class:`vibkit.fleet.segments.Screening`).
    flags : tuple of str
        Short notes for the work list (outliers, flagged, replaced, implausible rate, latest flagged).
    """

    unit: str
    n_measurements: int
    first_date_utc: str
    latest_date_utc: str
    nominal_pitch_m: float
    latest_elongation_percent: float
    latest_elongation_sigma_percent: float
    latest_verdict: str
    slope_percent_per_year: float | None
    slope_sigma_percent_per_year: float | None
    chi2_per_dof: float | None
    over_limit_percent: float | None
    forecasts: tuple
    fit: TrendFit | None = None
    rank: int = 0
    rate_verdict: str = "too few"
    n_used: int = 0
    segment_start_utc: str | None = None
    outliers: tuple = ()
    flagged: tuple = ()
    replacements: tuple = ()
    point_labels: tuple = ()
    flags: tuple = ()
    speed_sigma_stated: bool = True

    def next_limit(self):
        """The first limit not yet reached, as its :class:`LimitForecast` (None when all are reached)."""
        return next((f for f in self.forecasts if f.status != "reached"), None)

    def overdue(self, today_unix_s) -> bool:
        """Whether the next limit's forecast date has passed on ``today_unix_s`` (:meth:`LimitForecast.overdue`)."""
        nxt = self.next_limit()
        return nxt is not None and nxt.overdue(today_unix_s)

    def as_dict(self, today_unix_s=None) -> dict:
        """JSON-ready dict; with ``today_unix_s`` every forecast says whether it is ``overdue`` (its date passed)."""
        skip = ("forecasts", "fit", "outliers", "flagged", "replacements", "point_labels", "flags")
        d = {k: getattr(self, k) for k in self.__dataclass_fields__ if k not in skip}
        d["forecasts"] = [asdict(f) for f in self.forecasts]
        nxt = self.next_limit()
        d["next_limit"] = None if nxt is None else asdict(nxt)
        if today_unix_s is not None:
            for f, fd in zip(self.forecasts, d["forecasts"]):
                fd["overdue"] = f.overdue(today_unix_s)
            if d["next_limit"] is not None:
                d["next_limit"]["overdue"] = nxt.overdue(today_unix_s)
            d["overdue"] = self.overdue(today_unix_s)
        d["flags"] = list(self.flags)
        d["outliers"] = [dict(o) for o in self.outliers]
        d["flagged"] = [dict(o) for o in self.flagged]
        d["replacements"] = [dict(o) for o in self.replacements]
        if self.fit is not None:
            d["trend_reference_utc"] = _unix_to_iso(self.fit.t_ref_unix_s)
            d["elongation_at_reference_percent"] = self.fit.elongation_ref_percent
            d["elongation_at_reference_sigma_percent"] = self.fit.elongation_ref_sigma_percent
        return d


def _finite_or_none(x):
    return None if x is None or not math.isfinite(x) else float(x)


def unit_trend(unit, measurements, *, limits_percent=DEFAULT_LIMITS_PERCENT, coverage_sigma=2.0) -> UnitTrend:
    """The :class:`UnitTrend` of one unit's measurements (any order).

    The measurements are screened first (:func:`vibkit.fleet.segments.screen_unit`); the latest
    elongation is the latest fitted one (the latest measurement when none is usable).
    """
    ms = sorted(measurements, key=lambda m: (m.date_unix_s, m.id or 0))
    scr = screen_unit(ms)
    used = scr.used
    fit = None
    span_days = (used[-1].date_unix_s - used[0].date_unix_s) / 86400.0 if len(used) >= 2 else 0.0
    short = len(used) >= 2 and span_days < MIN_TREND_SPAN_DAYS
    if len(used) >= 2 and not short:
        try:
            fit = fit_trend(
                [m.date_unix_s for m in used],
                [m.elongation_percent for m in used],
                [m.elongation_sigma_percent for m in used],
            )
        except ValueError:  # one date only
            fit = None
    last = used[-1] if used else ms[-1]
    flags = []
    if short:
        flags.append(
            f"visits span {span_days:.2g} days, less than {MIN_TREND_SPAN_DAYS:g} days: no rate and no forecast "
            "(measure again later)"
        )
    if fit is None:
        rate = "too few"
    elif fit.slope_percent_per_year + IMPLAUSIBLE_RATE_SIGMA * fit.slope_sigma_percent_per_year < 0:
        rate = "implausible"
        flags.append(f"rate {fit.slope_percent_per_year:+.2f} %/year: a chain does not shorten; re-measure")
    elif fit.slope_percent_per_year > coverage_sigma * fit.slope_sigma_percent_per_year:
        rate = "growing"
    else:
        rate = "flat"
        if fit.slope_percent_per_year + DOUBTFUL_RATE_SIGMA * fit.slope_sigma_percent_per_year < 0:
            flags.append(
                f"rate {fit.slope_percent_per_year:+.2f} %/year is below zero by "
                f"{-fit.slope_percent_per_year / fit.slope_sigma_percent_per_year:.1f} sigma: a chain does not "
                "shorten; check the visits' speeds and sensors"
            )
    reached = [lim for lim in limits_percent if last.elongation_percent >= lim]
    fc = forecast_limits(
        None if rate == "implausible" else fit,
        limits_percent,
        latest_elongation_percent=last.elongation_percent if used else None,
        coverage_sigma=coverage_sigma,
    )
    if rate == "implausible":
        fc = tuple(f if f.status == "reached" else LimitForecast(f.limit_percent, "implausible") for f in fc)
    outliers = tuple(
        {
            "id": m.id,
            "date_utc": m.date_utc,
            "elongation_percent": m.elongation_percent,
            "sigma_percent": m.elongation_sigma_percent,
            "deviation_sigma": _finite_or_none(z),
        }
        for m, z in scr.outliers
    )
    flagged = tuple(
        {"id": m.id, "date_utc": m.date_utc, "quality": m.quality, "reason": m.quality_reason}
        for m in ms
        if m.quality != "ok"
    )
    repl = tuple({"id": m.id, "date_utc": m.date_utc, "reason": why} for m, why in scr.segment_starts)
    if outliers:
        flags.append(f"{len(outliers)} outlier(s) left out: " + ", ".join(o["date_utc"][:10] for o in outliers))
    left_out = [f"{n} {q}" for q in ("implausible", "inconclusive") if (n := sum(f["quality"] == q for f in flagged))]
    if not used:  # one flag says it all: nothing to trend, and why
        flags.append(f"no usable measurement ({', '.join(left_out)})" if left_out else "no usable measurement")
    flags += [f"{lo} measurement(s) left out" for lo in left_out if used]
    if repl:
        flags.append(f"chain replaced {repl[-1]['date_utc'][:10]} (new segment)")
    unstated = sum(1 for m in used if not m.speed_sigma_stated)
    if unstated:
        flags.append(
            f"speed uncertainty not stated in {unstated} measurement(s): their sigmas, the rate's and "
            "the forecast intervals are too small"
        )
    if used and ms[-1] is not last:
        flags.append(f"latest measurement ({ms[-1].date_utc[:10]}) not used")
    seg_start = repl[-1]["date_utc"] if repl else None
    return UnitTrend(
        unit=str(unit),
        n_measurements=len(ms),
        first_date_utc=ms[0].date_utc,
        latest_date_utc=last.date_utc,
        nominal_pitch_m=last.nominal_pitch_m,
        latest_elongation_percent=last.elongation_percent,
        latest_elongation_sigma_percent=last.elongation_sigma_percent,
        latest_verdict=elongation_verdict(last.elongation_percent, limits_percent) if used else "inconclusive",
        slope_percent_per_year=None if fit is None else fit.slope_percent_per_year,
        slope_sigma_percent_per_year=None if fit is None else fit.slope_sigma_percent_per_year,
        chi2_per_dof=None if fit is None or math.isnan(fit.chi2_per_dof) else fit.chi2_per_dof,
        over_limit_percent=max(reached) if reached and used else None,
        forecasts=fc,
        fit=fit,
        rate_verdict=rate,
        n_used=len(used),
        segment_start_utc=seg_start,
        outliers=outliers,
        flagged=flagged,
        replacements=repl,
        point_labels=tuple((m.id, scr.labels.get(m.id if m.id is not None else id(m), "ok")) for m in ms),
        flags=tuple(flags),
        speed_sigma_stated=last.speed_sigma_stated,
    )


def rank_units(trends):
    """Sort by urgency (the work list): units over a limit first (highest limit, then largest
    elongation), then by the earliest forecast date of a limit not yet reached, then units whose
    measurements need a visit (an implausible rate, or no usable measurement; largest elongation
    first), then by the earliest "not before" date, then the rest (largest elongation first);
    ``rank`` set from 1."""

    def key(u):
        if u.over_limit_percent is not None:
            return (0, -u.over_limit_percent, -u.latest_elongation_percent, u.unit)
        dated = [f.urgency_unix_s() for f in u.forecasts if f.status == "forecast"]
        if dated:
            return (1, min(dated), 0.0, u.unit)
        if u.rate_verdict == "implausible" or u.n_used == 0:
            return (2, -u.latest_elongation_percent, 0.0, u.unit)
        when = min((f.urgency_unix_s() for f in u.forecasts if f.status == "not before"), default=math.inf)
        if math.isfinite(when):
            return (3, when, 0.0, u.unit)
        return (4, -u.latest_elongation_percent, 0.0, u.unit)

    out = sorted(trends, key=key)
    return [
        UnitTrend(**{**{k: getattr(u, k) for k in u.__dataclass_fields__}, "rank": i}) for i, u in enumerate(out, 1)
    ]
