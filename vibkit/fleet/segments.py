"""Which of a unit's measurements enter its trend: quality flags, chain replacements, outliers.

A unit's measurements (by date) are screened in three steps (:func:`screen_unit`):

1. only measurements whose stored quality flag is ``"ok"`` are used (:mod:`vibkit.fleet.quality`:
   implausible and inconclusive ones are shown and listed, never fitted);
2. a chain is never shorter than it was: a measurement marked ``replaced``, or one whose elongation
   lies more than ``drop_sigma`` combined standard deviations below the previous one, starts a new
   *segment* (a chain replacement).  A lone low point that the next measurement contradicts (back
   at the old level), or a lone high point that the one after it contradicts, is an outlier, not
   a replacement;
3. in the current (latest) segment, with at least four points, the point furthest from the line
   fitted to the others is an *outlier* when it lies more than ``outlier_sigma`` (5) standard
   deviations from it (its sigma and the line's prediction sigma combined, both widened by the
   line's Birge ratio); it is left out and the test repeated.

Only the current segment's remaining points are fitted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from .trend_fit import SECONDS_PER_YEAR, fit_trend

__all__ = ["Screening", "screen_unit"]

#: a drop below the previous point by more than this many combined sigmas starts a new segment (a real
#: replacement drops 1-3 % against sigmas of 0.05-0.1 %: tens of sigmas)
DROP_SIGMA = 4.0
#: a point more than this many sigmas from the trend of the others is an outlier
OUTLIER_SIGMA = 5.0


@dataclass
class Screening:
    """The outcome of :func:`screen_unit`.

    Attributes
    ----------
    used : list of Measurement
        The current segment's measurements that enter the fit (by date).
    labels : dict
        ``id -> label`` for every measurement: ``"ok"`` (fitted), ``"outlier"``, ``"inconclusive"``,
        ``"implausible"`` or ``"earlier segment"``.
    outliers : list of (Measurement, float)
        Outliers with their distance from the trend of the others in sigmas (``nan`` for a lone low
        or high point that its neighbours contradict, found by the step test).
    segment_starts : list of (Measurement, str)
        Measurements that start a new segment, with the reason.
    """

    used: list = field(default_factory=list)
    labels: dict = field(default_factory=dict)
    outliers: list = field(default_factory=list)
    segment_starts: list = field(default_factory=list)


def _key(m):
    return m.id if m.id is not None else id(m)


def _drop(a, b, k):
    """How many combined sigmas ``b`` lies below ``a`` (positive: a drop), and whether it exceeds ``k``."""
    z = (a.elongation_percent - b.elongation_percent) / math.hypot(
        a.elongation_sigma_percent, b.elongation_sigma_percent
    )
    return z, z > k


def _leave_one_out(points, outlier_sigma):
    """Index and distance [sigmas] of the point furthest from the line through the others, if beyond."""
    worst, worst_z = None, 0.0
    for i, m in enumerate(points):
        rest = points[:i] + points[i + 1 :]
        try:
            fit = fit_trend(
                [r.date_unix_s for r in rest],
                [r.elongation_percent for r in rest],
                [r.elongation_sigma_percent for r in rest],
            )
        except ValueError:
            continue
        tau = (m.date_unix_s - fit.t_ref_unix_s) / SECONDS_PER_YEAR
        pred_var = fit.elongation_ref_sigma_percent**2 + (fit.slope_sigma_percent_per_year * tau) ** 2
        sig = math.sqrt((fit.sigma_scale * m.elongation_sigma_percent) ** 2 + pred_var)
        z = abs(m.elongation_percent - float(fit.elongation_at(m.date_unix_s))) / sig
        if z > worst_z:
            worst, worst_z = i, z
    return (worst, worst_z) if worst is not None and worst_z > outlier_sigma else (None, worst_z)


def screen_unit(measurements, *, drop_sigma=DROP_SIGMA, outlier_sigma=OUTLIER_SIGMA) -> Screening:
    """Screen one unit's measurements (any order) for its trend; see the module docstring."""
    ms = sorted(measurements, key=lambda m: (m.date_unix_s, m.id or 0))
    out = Screening()
    good = []
    for m in ms:
        if m.quality != "ok":
            out.labels[_key(m)] = m.quality
        else:
            good.append(m)
    segments, prev = [[]], None
    for i, m in enumerate(good):
        if m.replaced and segments[-1]:
            out.segment_starts.append((m, "chain replaced (given when it was added)"))
            segments.append([])
            prev = None
        elif prev is not None:
            z, dropped = _drop(prev, m, drop_sigma)
            if dropped:
                nxt = good[i + 1] if i + 1 < len(good) else None
                if (
                    nxt is not None
                    and not nxt.replaced
                    and not _drop(prev, nxt, drop_sigma)[1]
                    and _drop(nxt, m, drop_sigma)[1]
                ):
                    out.outliers.append((m, z))  # the next point is back at the old level; z: m's drop
                    out.labels[_key(m)] = "outlier"
                    continue
                seg = segments[-1]
                pp = seg[-2] if len(seg) >= 2 else None
                if pp is not None and _drop(prev, pp, drop_sigma)[1] and not _drop(pp, m, drop_sigma)[1]:
                    # prev rose above the point before it and m is back at that level: prev alone is wrong
                    seg.pop()
                    out.outliers.append((prev, _drop(prev, pp, drop_sigma)[0]))  # how far prev rose above pp
                    out.labels[_key(prev)] = "outlier"
                    dropped = False
            if dropped:
                out.segment_starts.append(
                    (
                        m,
                        f"elongation fell from {prev.elongation_percent:+.2f} to "
                        f"{m.elongation_percent:+.2f} % ({z:.1f} sigma): chain replaced?",
                    )
                )
                segments.append([])
        segments[-1].append(m)
        prev = m
    for seg in segments[:-1]:
        for m in seg:
            out.labels[_key(m)] = "earlier segment"
    current = list(segments[-1])
    while len(current) >= 4:
        i, z = _leave_one_out(current, outlier_sigma)
        if i is None:
            break
        m = current.pop(i)
        out.outliers.append((m, z))
        out.labels[_key(m)] = "outlier"
    for m in current:
        out.labels[_key(m)] = "ok"
    out.used = current
    return out
