"""The guide: the closed path of lines and arcs followed by the roller centres (model.md section 1).

The guide is data: a table of 14 segments (line or arc) joined with a continuous tangent. A moving
walk's guide is the same path: two heads and straight runs, its transitions the arcs between the
landings and an incline of 12 degrees at most; where the walk is level (incline 0) the transitions
turn nothing and are kept as empty segments, so that every segment keeps its index and name. The
tensioner displacement ``delta`` shortens the two telescopic runs (segments 1 and 13) and moves the
lower head (segment 14) by ``delta`` along x; everything else is fixed.

Two arc-length coordinates are used:

``s0``
    arc length on the *undeformed* guide, period P0 (the study's coordinate). On the telescopic
    runs it is mapped linearly onto the shortened run, so ``s0`` has a fixed period whatever delta.
``s``
    arc length on the *deformed* guide, measured from the top of the lower head at (delta, R),
    period P0 - 2 delta.

For a segment k with undeformed start ``s0_k``, the local arc length is ``lam = s0 - s0_k`` on
fixed segments. On the two telescopic runs (undeformed length Lt, deformed length Lt - delta) it is
``lam = s - delta w(s / Lt)`` with s = s0 - s0_k and w a smooth ramp (w(0) = 0, w(1) = 1,
w'(0) = w'(1) = 0, w' = 1/(1 - eps) in the middle, cosine ramps of width eps = 0.1 at the ends).
The study maps s0 *linearly* onto the shortened run (w(u) = u); that makes dr/ds0 jump at the four
ends of the telescopic runs, so a roller crossing them changes its speed discontinuously in that
coordinate and the reduced dynamics does not conserve energy. With the ramp, r(s0, delta) is C1 in
both arguments everywhere, for |delta| < (1 - eps) Lt. Positions, and so every physical result, do
not depend on this choice of coordinate. The point is ``r = A_k + B_k delta + f_k(lam)`` where
``f_k`` is the line or arc from the segment's start heading. The kernels below return r and its first and second partial derivatives
with respect to s0 and delta, which is all the chain closure and its velocity and acceleration
recursions need.
"""

from __future__ import annotations

import math

import numpy as np

from ..runtime.kernel import kernel
from .params import RAMP, TRAVEL, GuideParams  # noqa: F401 (TRAVEL: the guide's, as its users import it)

__all__ = ["Guide", "SEGMENT_NAMES"]

SEGMENT_NAMES = (
    "tensioner, top run",
    "lower landing, top run",
    "lower transition",
    "incline, top run",
    "upper transition",
    "upper landing, top run",
    "upper head (drive sprocket)",
    "upper landing, return run",
    "upper transition, return",
    "incline, return run",
    "lower transition, return",
    "lower landing, return run",
    "tensioner, return run",
    "lower head (tensioner carriage)",
)

# columns of the segment table
S0, LEN0, KAPPA, PHI0, AX, AZ, BX, BZ, SIGP, CUMD, COS0, SIN0 = range(12)
NCOL = 12


def build_table(p: GuideParams) -> np.ndarray:
    """Segment table (14 x 10 float64) of the guide; see module docstring for the columns."""
    lt, l1, l2, rt, a, ll, rr = (
        p.tensioner_length,
        p.lower_landing,
        p.upper_landing,
        p.transition_radius,
        p.incline_angle,
        p.incline_length,
        p.head_radius,
    )
    # (kind length-or-radius, turn) as in model.md section 1
    segs = [
        ("line", lt, 0.0, True),
        ("line", l1, 0.0, False),
        ("arc", rt, +a, False),
        ("line", ll, 0.0, False),
        ("arc", rt, -a, False),
        ("line", l2, 0.0, False),
        ("arc", rr, -math.pi, False),
        ("line", l2, 0.0, False),
        ("arc", rt, +a, False),
        ("line", ll, 0.0, False),
        ("arc", rt, -a, False),
        ("line", l1, 0.0, False),
        ("line", lt, 0.0, True),
        ("arc", rr, -math.pi, False),
    ]
    tab = np.zeros((len(segs), NCOL))
    x, z, phi, s0, cumd = 0.0, rr, 0.0, 0.0, 0.0
    for k, (kind, size, turn, tele) in enumerate(segs):
        if kind == "line" or turn == 0.0:
            # (a moving walk's level guide, incline 0: its transitions turn nothing and are empty lines)
            length, kappa = (size, 0.0) if kind == "line" else (0.0, 0.0)
        else:
            length, kappa = size * abs(turn), math.copysign(1.0 / size, turn)
        tab[k] = (
            s0,
            length,
            kappa,
            phi,
            x,
            z,
            0.0,
            0.0,
            (-1.0 / lt) if tele else 0.0,
            cumd,
            math.cos(phi),
            math.sin(phi),
        )
        if k in (0, 13):  # the start of the top tensioner run and of the lower head move with delta
            tab[k, BX] = 1.0
        # advance the undeformed pose
        if kappa == 0.0:
            x += length * math.cos(phi)
            z += length * math.sin(phi)
        else:
            phi1 = phi + kappa * length
            x += (math.sin(phi1) - math.sin(phi)) / kappa
            z += (math.cos(phi) - math.cos(phi1)) / kappa
            phi = phi1
        s0 += length
        cumd += length * tab[k, SIGP]
    if abs(x) > 1e-9 or abs(z - rr) > 1e-9 or abs(math.remainder(phi, 2 * math.pi)) > 1e-12:
        raise ValueError(
            f"guide does not close: it ends at ({x:.6g}, {z:.6g}) m heading {math.degrees(phi):.6g} deg "
            f"instead of (0, {rr:.6g}) m heading 0 deg; check incline_length against the rise"
        )
    return tab


# --------------------------------------------------------------------------------------------
# compiled kernels (all take the segment table ``tab`` and the period ``p0``)


@kernel()
def locate(tab, s0):
    """Segment index holding s0 (already reduced to [0, P0))."""
    n = tab.shape[0]
    lo, hi = 0, n - 1
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if tab[mid, S0] <= s0:
            lo = mid
        else:
            hi = mid - 1
    return lo


@kernel()
def tele_ramp(u):
    """w(u), w'(u), w''(u) of the telescopic map (see module docstring), u in [0, 1]."""
    eps = RAMP
    a = 1.0 / (1.0 - eps)
    if u < eps:
        x = math.pi * u / eps
        return (
            a * 0.5 * (u - eps / math.pi * math.sin(x)),
            a * 0.5 * (1.0 - math.cos(x)),
            a * 0.5 * math.pi / eps * math.sin(x),
        )
    if u > 1.0 - eps:
        v = 1.0 - u
        x = math.pi * v / eps
        return (
            1.0 - a * 0.5 * (v - eps / math.pi * math.sin(x)),
            a * 0.5 * (1.0 - math.cos(x)),
            -a * 0.5 * math.pi / eps * math.sin(x),
        )
    return a * (0.5 * eps + (u - eps)), a, 0.0


@kernel()
def local_map(tab, k, s0loc, delta):
    """lam and its partials (lam_s, lam_d, lam_ss, lam_sd) at s0loc = s0 - s0_k on segment k."""
    if tab[k, SIGP] == 0.0:
        return s0loc, 1.0, 0.0, 0.0, 0.0
    lt = tab[k, LEN0]
    w, w1, w2 = tele_ramp(s0loc / lt)
    return s0loc - delta * w, 1.0 - delta * w1 / lt, -w, -delta * w2 / (lt * lt), -w1 / lt


@kernel()
def local_inverse(tab, k, lam, delta):
    """s0loc whose local arc length is lam on segment k.

    On a telescopic run the map is monotonic but strongly curved near the ends of the travel, so
    Newton's method is safeguarded by bisection on [0, Lt] (a local arc length slightly outside
    the run, as the walk's tolerance allows, is extrapolated linearly).
    """
    if tab[k, SIGP] == 0.0:
        return lam
    lt = tab[k, LEN0]
    if lam <= 0.0:
        return lam
    length = lt - delta
    if lam >= length:
        return lt + (lam - length)
    lo, hi = 0.0, lt
    x = lam * lt / length
    for _ in range(200):
        f, fs, _, _, _ = local_map(tab, k, x, delta)
        f -= lam
        if f == 0.0:
            return x  # on the root: a bisection from here would walk away from it
        if f > 0.0:
            hi = x
        else:
            lo = x
        xn = x - f / fs if fs > 0.0 else 0.5 * (lo + hi)
        if not (lo < xn < hi):
            xn = 0.5 * (lo + hi)
        if abs(xn - x) <= 1e-16 * lt or hi - lo <= 1e-16 * lt:
            return xn
        x = xn
    return x


@kernel()
def local_point(tab, k, lam, delta):
    """Position, unit tangent angle and left normal on segment k at local arc length lam."""
    kap = tab[k, KAPPA]
    phi0 = tab[k, PHI0]
    x0 = tab[k, AX] + tab[k, BX] * delta
    z0 = tab[k, AZ] + tab[k, BZ] * delta
    if kap == 0.0:
        c, s = math.cos(phi0), math.sin(phi0)
        return x0 + lam * c, z0 + lam * s, phi0
    phi = phi0 + kap * lam
    return (x0 + (math.sin(phi) - math.sin(phi0)) / kap, z0 + (math.cos(phi0) - math.cos(phi)) / kap, phi)


@kernel()
def local_frame(tab, k, lam, delta):
    """Position and unit tangent (x, z, tx, tz) on segment k at local arc length lam.

    Same as :func:`local_point` with the tangent instead of its angle; no trigonometry on lines.
    """
    kap = tab[k, KAPPA]
    x0 = tab[k, AX] + tab[k, BX] * delta
    z0 = tab[k, AZ] + tab[k, BZ] * delta
    c0, s0 = tab[k, COS0], tab[k, SIN0]
    if kap == 0.0:
        return x0 + lam * c0, z0 + lam * s0, c0, s0
    phi = tab[k, PHI0] + kap * lam
    c, s = math.cos(phi), math.sin(phi)
    return x0 + (s - s0) / kap, z0 + (c0 - c) / kap, c, s


@kernel()
def point_partials(tab, k, lam, s0loc, delta, out):
    """r and its partial derivatives with respect to s0 and delta on segment k.

    ``s0loc`` is s0 - s0_k and ``lam`` its local arc length (``local_map``). Fills ``out``
    (length 12) with x, z, rs_x, rs_z, rd_x, rd_z, rss_x, rss_z, rsd_x, rsd_z, rdd_x, rdd_z.
    """
    x, z, tx, tz = local_frame(tab, k, lam, delta)
    kap = tab[k, KAPPA]
    _, ls, ld, lss, lsd = local_map(tab, k, s0loc, delta)
    nx, nz = -tz, tx
    out[0] = x
    out[1] = z
    out[2] = ls * tx
    out[3] = ls * tz
    out[4] = tab[k, BX] + ld * tx
    out[5] = tab[k, BZ] + ld * tz
    out[6] = lss * tx + ls * ls * kap * nx
    out[7] = lss * tz + ls * ls * kap * nz
    out[8] = lsd * tx + ls * ld * kap * nx
    out[9] = lsd * tz + ls * ld * kap * nz
    out[10] = kap * ld * ld * nx
    out[11] = kap * ld * ld * nz


@kernel()
def seg_length(tab, k, delta):
    return tab[k, LEN0] * (1.0 + tab[k, SIGP] * delta)


@kernel()
def circle_hit(tab, k, delta, qx, qz, radius, lam_lo):
    """Smallest local arc length lam >= lam_lo on segment k whose point is at ``radius`` from q, and
    that point: (lam, x, z), lam = -1.0 when the segment holds no such point. Exact (closed form)
    for lines and arcs."""
    tol = 1e-12
    length = seg_length(tab, k, delta)
    kap = tab[k, KAPPA]
    phi0 = tab[k, PHI0]
    x0 = tab[k, AX] + tab[k, BX] * delta
    z0 = tab[k, AZ] + tab[k, BZ] * delta
    best = -1.0
    bx = bz = 0.0
    if kap == 0.0:
        tx, tz = tab[k, COS0], tab[k, SIN0]
        wx, wz = x0 - qx, z0 - qz
        b = tx * wx + tz * wz
        c = wx * wx + wz * wz - radius * radius
        disc = b * b - c
        if disc < 0.0:
            return -1.0, 0.0, 0.0
        sq = math.sqrt(disc)
        hit = False
        for lam in (-b - sq, -b + sq):
            # (a hit just before the start, within tol, counts: the walk's tolerance allows it)
            if lam >= lam_lo - tol and lam <= length + tol:
                if best < 0.0 or lam < best:
                    best = lam
                    hit = True
        if not hit:
            return -1.0, 0.0, 0.0
        return best, x0 + best * tx, z0 + best * tz
    rho = 1.0 / abs(kap)
    cx = x0 - tab[k, SIN0] / kap
    cz = z0 + tab[k, COS0] / kap
    dx, dz = qx - cx, qz - cz
    d = math.sqrt(dx * dx + dz * dz)
    if d > rho + radius or d < abs(rho - radius) or d == 0.0:
        return -1.0, 0.0, 0.0
    a = (rho * rho - radius * radius + d * d) / (2.0 * d)
    h2 = rho * rho - a * a
    h = math.sqrt(h2) if h2 > 0.0 else 0.0
    ex, ez = dx / d, dz / d
    full = 2.0 * math.pi * rho
    found = False
    for sgn in (-1.0, 1.0):
        px = cx + a * ex - sgn * h * ez
        pz = cz + a * ez + sgn * h * ex
        phi = math.atan2(kap * (px - cx), -kap * (pz - cz))
        lam = (phi - phi0) / kap
        lam = lam - full * math.floor(lam / full)
        if lam > full - 1e-9:
            lam -= full
        if lam >= lam_lo - tol and lam <= length + tol:
            if not found or lam < best:
                best = lam
                bx, bz = px, pz
                found = True
    return (best, bx, bz) if found else (-1.0, 0.0, 0.0)


@kernel(inline="always")
def hit_next(tab, delta, k, qx, qz, radius, wraps):
    """The first point at ``radius`` from q on the segments after segment k (round the loop, counting
    ``wraps``): (segment, local arc length, wraps, x, z), segment -1 where the guide has none."""
    nseg = tab.shape[0]
    k += 1
    if k == nseg:
        k = 0
        wraps += 1
    for _ in range(nseg + 1):
        found, x, z = circle_hit(tab, k, delta, qx, qz, radius, 0.0)
        if found != -1.0:
            return k, found, wraps, x, z
        k += 1
        if k == nseg:
            k = 0
            wraps += 1
    return -1, 0.0, wraps, 0.0, 0.0


# --------------------------------------------------------------------------------------------


class Guide:
    """The guide of one escalator, deformed by the tensioner displacement delta.

    Parameters
    ----------
    params : GuideParams
        Geometry of the guide.

    Examples
    --------
    >>> from vibkit.model.params import reference_guide
    >>> g = Guide(reference_guide())
    >>> round(g.perimeter(0.0), 4)
    21.2751
    """

    def __init__(self, params: GuideParams):
        self.params = params
        self.table = build_table(params)
        self.p0 = float(self.table[:, LEN0].sum())

    def breakpoints(self, *, smooth_joints: bool = True) -> np.ndarray:
        """Undeformed coordinates s0 where the guide's second derivatives are not smooth. [m]

        Every segment start (a curvature jump between a line and an arc, or the end of a telescopic
        run) and the four inner ends of the telescopic runs' cosine ramps. They do not move with
        delta. The acceleration of a roller jumps (or its rate does) when it crosses one, so the
        forward integrator ends its steps there (:meth:`vibkit.model.chain.Chain.crossing_table`).
        """
        tab = self.table
        jump = tab[:, KAPPA] != np.roll(tab[:, KAPPA], 1)
        pts = list(tab[jump, S0])
        if smooth_joints:
            pts += list(tab[~jump, S0])
            for k in np.flatnonzero(tab[:, SIGP] != 0.0):
                pts += [tab[k, S0] + RAMP * tab[k, LEN0], tab[k, S0] + (1.0 - RAMP) * tab[k, LEN0]]
        return np.unique(np.mod(np.asarray(pts), self.p0))

    def perimeter(self, delta: float = 0.0) -> float:
        """Perimeter of the deformed guide P0 - 2 delta. [m]"""
        self._check_delta(delta)
        return self.p0 - 2.0 * delta

    def _check_delta(self, delta):
        lim = TRAVEL * self.params.tensioner_length
        d = np.asarray(delta)
        if np.any(d >= lim) or np.any(d <= -lim):
            raise ValueError(f"delta must lie in (-{lim:.4g}, {lim:.4g}) m (the tensioner travel), got {delta!r}")

    def segment_lengths(self, delta: float = 0.0) -> np.ndarray:
        """Length of each of the 14 segments on the deformed guide. [m]"""
        self._check_delta(delta)
        return self.table[:, LEN0] * (1.0 + self.table[:, SIGP] * delta)

    def s0_to_s(self, s0, delta: float = 0.0):
        """Undeformed-guide coordinate s0 to deformed arc length s (both wrapped to one loop). [m]"""
        self._check_delta(delta)
        s0 = np.mod(np.asarray(s0, dtype=float), self.p0)
        flat = np.atleast_1d(s0)
        out = np.empty(flat.size)
        for j, v in enumerate(flat):
            k = locate(self.table, v)
            out[j] = (
                self.table[k, S0]
                + self.table[k, CUMD] * delta
                + local_map(self.table, k, v - self.table[k, S0], delta)[0]
            )
        return out.reshape(np.shape(s0))

    def s_to_s0(self, s, delta: float = 0.0):
        """Deformed arc length s to the undeformed-guide coordinate s0. [m]"""
        self._check_delta(delta)
        s = np.mod(np.asarray(s, dtype=float), self.perimeter(delta))
        starts = self.table[:, S0] + self.table[:, CUMD] * delta
        flat = np.atleast_1d(s)
        k = np.searchsorted(starts, flat, side="right") - 1
        out = np.array(
            [self.table[kk, S0] + local_inverse(self.table, kk, v - starts[kk], delta) for kk, v in zip(k, flat)]
        )
        return out.reshape(np.shape(s))

    def _frame(self, s, delta):
        s0 = self.s_to_s0(s, delta)
        s0 = np.atleast_1d(s0)
        out = np.empty((s0.size, 12))
        kap = np.empty(s0.size)
        for j, v in enumerate(s0):
            k = locate(self.table, v)
            loc = v - self.table[k, S0]
            point_partials(self.table, k, local_map(self.table, k, loc, delta)[0], loc, delta, out[j])
            kap[j] = self.table[k, KAPPA]
        return out, kap

    def position(self, s, delta: float = 0.0) -> np.ndarray:
        """Point (x, z) of the guide at deformed arc length s; shape (..., 2). [m]"""
        out, _ = self._frame(s, delta)
        return out[:, 0:2].reshape(np.shape(s) + (2,))

    def tangent(self, s, delta: float = 0.0) -> np.ndarray:
        """Unit tangent (direction of travel) at deformed arc length s; shape (..., 2)."""
        out, _ = self._frame(s, delta)
        t = out[:, 2:4] / np.hypot(out[:, 2], out[:, 3])[:, None]
        return t.reshape(np.shape(s) + (2,))

    def curvature(self, s, delta: float = 0.0) -> np.ndarray:
        """Signed curvature at deformed arc length s (positive turning left). [1/m]"""
        _, kap = self._frame(s, delta)
        return kap.reshape(np.shape(s))

    def segment_at(self, s, delta: float = 0.0):
        """Index (0-13) of the segment holding deformed arc length s."""
        s0 = np.atleast_1d(self.s_to_s0(s, delta))
        return np.array([locate(self.table, v) for v in s0]).reshape(np.shape(s))
