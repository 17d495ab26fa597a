"""The decision on a link map (:func:`vibkit.signal.linkmap.link_map`): which links deviate, at a stated
false-alarm probability per recording over all links.

The decision (:func:`scan_links`):

* with a *signature* ``T`` (``N`` links by ``samples_per_cycle``: what one link of excess pitch
  ``scale`` adds to the map, link 0 being the worn link; the diagnose layer makes it with the
  model), the amplitude of ``T`` shifted to every link ``k`` is fitted in every loop, ``a_kl``; its
  mean ``a_k`` is tested against the noise of the cycles' shapes (their covariance over the points
  of a cycle from the loop-to-loop scatter pooled over all links: Student t with ``N (L - 1)``
  degrees of freedom), at the per-link level ``1 - (1 - alpha)^(1/N)`` (Sidak) so that a healthy
  recording raises a flag with probability at most ``alpha`` over all ``N`` links.  The largest
  passing link is flagged, its fitted signature removed, and the scan repeated (one flag per worn
  link, not one per neighbour it overlaps).  The flagged links' amounts are fitted together where their
  placements are apart (outside each other's lobe and overlapping by ``|rho| < RHO_APART``): fitted alone, a
  flag takes in ``rho`` times the other's amount (two worn links 30 links apart on the study's chain,
  ``rho = -0.24``: the first read 24 % low); a neighbour's amount (within the lobe, or at the twin half a loop
  away) stays what is left once the earlier flag is taken out, since two placements that overlap nearly as much
  as one would split one worn link's excess between them.  A flag's alternatives are sought in the map net of
  the other flags.  After a flag, the signature's own error (``mismatch``
  near it, ``mismatch_floor`` everywhere, times its amplitude) is added to the noise, so that what an
  imperfect signature leaves is not taken for a second link.  Drift common to neighbouring cycles
  (settling, wander) is not in the cycles' covariance: where the per-loop amplitudes scatter more,
  their scatter is the noise, with ``(L - 1) N / sum(rho^2)`` degrees of freedom (``rho`` the
  signature's autocorrelation over links).  A flagged link's number is stated alone only when the data
  separate it from every other placement of the signature: a placement ``j`` outside the flag's own lobe
  (the links where ``rho > 0``) that is a local maximum of the statistic, with the same sign, past the
  threshold of one link tested alone (``alpha`` two-sided, no Sidak correction) and with
  ``t_k - t_j < z sqrt(2 (1 - r_kj)) + e t_k sqrt(2 (1 - rho_kj))`` is an *alternative* (``z`` the normal
  quantile at the false-alarm probability, ``r_kj`` the correlation of the two fits' noise, ``e`` the
  signature's relative error: the second term bounds what an error of that size can move the difference,
  by Cauchy-Schwarz).  A signature whose halves repeat (a worn link on the
  sprocket and on the lower head, half a loop apart) gives such a second placement;
* without a signature, each link's own cycle is tested: its mean level and its duration against
  the pooled loop-to-loop scatter (Student t with ``N (L - 1) - 1`` degrees of freedom), Sidak over
  ``2 N`` tests.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.stats

from .linkmap import LinkMap

__all__ = ["LinkFlag", "LinkScan", "count_drift", "scan_links", "sidak_threshold"]


def sidak_threshold(false_alarm, n_tests, dof):
    """Two-sided Student t threshold for ``n_tests`` tests at family-wise probability ``false_alarm``."""
    per = -math.expm1(math.log1p(-float(false_alarm)) / n_tests)
    return float(scipy.stats.t.isf(per / 2.0, dof))


@dataclass(frozen=True)
class LinkFlag:
    """One flagged link.

    Attributes
    ----------
    link : int
        1-based link number.
    t : float
        Its test statistic (amplitude over its standard deviation).
    amplitude, sigma : float
        The fitted amount (signature scale: e.g. excess pitch [m]; or the own-cycle feature), and
        its standard deviation.
    feature : str
        ``"signature"``, ``"level"`` or ``"duration"``.
    loops : tuple of int
        1-based loops whose own fit shows it (same sign, beyond twice the single-loop sigma).
    alternatives : tuple of int
        1-based links where the signature fits nearly as well (within what the noise and the signature's
        error allow): the data do not tell them from ``link``. Empty when they do.
    """

    link: int
    t: float
    amplitude: float
    sigma: float
    feature: str
    loops: tuple
    alternatives: tuple = ()


@dataclass(frozen=True)
class LinkScan:
    """Result of :func:`scan_links`.

    Attributes
    ----------
    flagged : tuple of LinkFlag
    statistic : ndarray (n_links,)
        The first pass's absolute t per link (largest over features without a signature).
    threshold : float
        The absolute t a link must pass.
    false_alarm : float
        Family-wise false-alarm probability over all links.
    dof : float
        Degrees of freedom of the scatter.
    amplitude, sigma : ndarray (n_links,)
        The first pass's fitted amount per link and its standard deviation.
    loops : int
    method : str
    unsteady : tuple of int
        Own cycle only: 1-based links that passed the threshold but scatter from loop to loop far beyond the
        pooled scatter (a start-up transient in one loop, not a link that is the same every loop): not flagged.
    residual : ndarray (n_links,) or None
        Signature only: the absolute t of every link once the flagged links' change is taken out (what no
        further link passed); None for the own cycle.
    peaks : tuple of int
        Signature only, where a link is flagged and every loop's own fit of the signature peaks above
        ``PEAK_SIGMA`` of its sigmas: the 1-based link where each peaks. One worn link peaks at one number every loop; a peak that moves by the same D links from loop to
        loop says the chain has ``n_links + D`` links (see :func:`count_drift`).
    """

    flagged: tuple
    statistic: np.ndarray
    threshold: float
    false_alarm: float
    dof: float
    amplitude: np.ndarray
    sigma: np.ndarray
    loops: int
    method: str
    unsteady: tuple = ()
    peaks: tuple = ()
    residual: np.ndarray | None = None


#: two flagged placements whose signatures overlap less than this (and outside each other's lobe) are fitted together
RHO_APART = 0.5

#: a loop's own fit must peak above this many of its sigmas for :attr:`LinkScan.peaks` to be recorded
PEAK_SIGMA = 5.0


def count_drift(peaks, n_links):
    """D, about how many links the per-loop peaks (:attr:`LinkScan.peaks`, 1-based) move from one loop to the
    next, when they move (the chain then has about ``n_links + D`` links, not ``n_links``); 0 when they stay.

    They move when every step from a loop to the next is the same D != 0 (at least 2 links over two loops), or,
    over three loops or more, when their straight line climbs at least 2 links a loop and no peak is off it by
    more than half of that. A step of half a loop (within a link) is no move: the signature's twin (a worn link
    shows on the sprocket and on the lower head, half a loop apart), which one loop's fit may prefer.

    Examples
    --------
    >>> count_drift((209, 213, 217), 360)
    4
    >>> count_drift((212, 206, 202), 368)
    -5
    >>> count_drift((210, 210, 211), 364)
    0
    >>> count_drift((14, 67, 14), 106)  # the twin, half a loop away, in loop 2
    0
    """
    if len(peaks) < 2:
        return 0
    half = n_links // 2
    steps = [((b - a + half) % n_links) - half for a, b in zip(peaks[:-1], peaks[1:])]
    steps = [s - half * int(np.sign(s)) if abs(abs(s) - n_links / 2) <= 1 else s for s in steps]
    if len(set(steps)) == 1 and (abs(steps[0]) >= 2 or len(peaks) >= 3):
        return steps[0]
    if len(peaks) < 3:
        return 0
    x = np.arange(len(peaks), dtype=float)
    u = np.concatenate([[0.0], np.cumsum(steps)])
    slope, icept = np.polyfit(x, u, 1)
    if abs(slope) >= 2.0 and np.max(np.abs(u - (icept + slope * x))) <= abs(slope) / 2.0:
        return int(round(slope))
    return 0


def _check_alpha(false_alarm):
    a = float(false_alarm)
    if not 0.0 < a < 1.0:
        raise ValueError(f"Parameter false_alarm={false_alarm!r} must lie in (0, 1).")
    return a


def _fit_signature(shape, tmpl):
    """Per-loop amplitude of ``tmpl`` shifted to every link: ``(loops, n_links)``."""
    norm = float(np.sum(tmpl * tmpl))
    ft = np.fft.rfft(tmpl, axis=0)
    fx = np.fft.rfft(shape, axis=1)
    # circular cross-correlation over links, summed over the points of the cycle
    cc = np.fft.irfft(fx * np.conj(ft)[None], n=tmpl.shape[0], axis=1).sum(axis=2)
    return cc / norm


def _loops_showing(per_loop, k, amp, s1):
    return tuple(
        int(i) + 1
        for i in np.flatnonzero((np.sign(per_loop[:, k]) == np.sign(amp)) & (np.abs(per_loop[:, k]) > 2 * s1))
    )


def scan_links(
    lmap,
    *,
    signature=None,
    scale=1.0,
    false_alarm=1e-2,
    max_flags=None,
    mismatch=0.25,
    mismatch_floor=0.05,
    signature_error=None,
):
    """Flag the links whose deviation passes a threshold set for ``false_alarm`` over all links.

    Parameters
    ----------
    lmap : LinkMap
    signature : array_like (n_links, samples_per_cycle), optional
        What one link of amount ``scale`` adds to the shape map, row 0 being that link.
    scale : float, optional
        The amount the signature stands for (e.g. an excess pitch [m]); amplitudes are in its unit.
    false_alarm : float, optional
        Probability that a recording without a deviating link raises any flag.
    max_flags : int, optional
        Stop after this many flags (default ``n_links // 4``).
    mismatch : float, optional
        Relative error of the signature: after a flag of amplitude ``a``, links within its reach are
        tested against ``mismatch * a * rho`` in addition to the noise (``rho`` the signature's
        autocorrelation at their distance), so that what an imperfect signature leaves is not a
        second flag.
    mismatch_floor : float, optional
        The same at every link: after a flag of amplitude ``a``, every other link is tested against
        ``mismatch_floor * a`` in addition (the signature of one scene does not reproduce a worn link
        elsewhere on the chain to better than a few per cent).
    signature_error : float, optional
        Relative error of the signature (``|error| / |signature|``) for the decision between two placements
        of it (a flag's ``alternatives``); default ``mismatch``.

    Returns
    -------
    LinkScan
    """
    if not isinstance(lmap, LinkMap):
        raise ValueError("Parameter lmap must be a LinkMap (from link_map).")
    alpha = _check_alpha(false_alarm)
    n, L = lmap.n_links, lmap.loops
    max_flags = n // 4 if max_flags is None else int(max_flags)
    if signature is None:
        return _scan_own(lmap, alpha)
    tmpl = np.asarray(signature, dtype=float)
    if tmpl.shape != (n, lmap.samples_per_cycle):
        raise ValueError(
            f"Parameter signature must have shape (n_links, samples_per_cycle) = {(n, lmap.samples_per_cycle)}, "
            f"got {tmpl.shape}."
        )
    if not np.all(np.isfinite(tmpl)) or not np.any(tmpl):
        raise ValueError("Parameter signature must be finite and not all zero.")
    tmpl = tmpl - tmpl.mean(axis=0)  # the mean cycle is removed from the map: remove it from the signature
    # the noise of one cycle's shape: its covariance over the points of the cycle, pooled over the
    # loop-to-loop differences of every link (independent from cycle to cycle)
    dev = lmap.shape - lmap.shape.mean(axis=0)
    dof = n * (L - 1)
    cov = np.einsum("lni,lnj->ij", dev, dev) / dof
    norm = float(np.sum(tmpl * tmpl))
    # variance of the per-loop amplitude: sum over links of T_n C T_n, over |T|^4 (the same for every shift)
    var1 = float(np.einsum("ni,ij,nj->", tmpl, cov, tmpl)) / norm**2
    # the signature's circular autocorrelation over links: how far one link's fit reaches its neighbours
    ac = np.fft.irfft(np.abs(np.fft.rfft(tmpl, axis=0)) ** 2, n=n, axis=0).sum(axis=1)
    rho = ac / ac[0]
    per_loop = _fit_signature(lmap.shape, tmpl)
    # drift from loop to loop that is common to neighbouring cycles (settling, wander) is missed by the
    # cycle covariance: the per-loop amplitudes' own scatter, with its fewer degrees of freedom, then rules
    var_emp = float(np.sum((per_loop - per_loop.mean(axis=0)) ** 2)) / dof
    # correlation of two placements' fitted amplitudes over their noise (of the cycles' covariance)
    ft = np.fft.rfft(tmpl, axis=0)
    ac_noise = np.fft.irfft(np.sum(np.conj(np.fft.rfft(tmpl @ cov, axis=0)) * ft, axis=1), n=n)
    r_noise = ac_noise / ac_noise[0] if ac_noise[0] > 0 else rho
    if var_emp > var1:
        var1, dof = var_emp, dof / float(np.sum(rho * rho))
        r_noise = rho
    s1 = math.sqrt(max(var1, 0.0))
    sig = s1 / math.sqrt(L)
    thr = sidak_threshold(alpha, n, dof)
    err = float(mismatch if signature_error is None else signature_error)
    lobe = _lobe(rho)
    alone = float(scipy.stats.t.isf(alpha / 2.0, dof))  # one link's own threshold: where an alternative starts
    shape = lmap.shape.copy()
    ts, first, peaks, ks = [], None, (), []  # the flags' statistics and 0-based links, in the order flagged
    extra = np.zeros(n)  # what a flagged link's imperfect signature leaves near it (variance)
    fit0 = per_loop  # every placement's per-loop fit to the map itself, before any flag is taken out
    for _ in range(max(max_flags, 1)):
        per_loop = _fit_signature(shape, tmpl)
        amp = per_loop.mean(axis=0)
        sd = np.sqrt(sig * sig + extra)
        tstat = np.abs(amp) / sd if sig > 0 else np.full(n, np.inf)
        if first is None:
            first = (tstat, amp * scale, np.full(n, sig * scale))
        k = int(np.argmax(np.where(np.isin(np.arange(n), ks), 0.0, tstat)))  # a flagged link is fitted already
        if not tstat[k] > thr or len(ts) >= max_flags:
            break
        if not ts:  # where each loop's own fit peaks, for the first (largest) flag, where every loop shows it
            best = [int(np.argmax(np.sign(amp[k]) * row)) for row in per_loop]
            if all(abs(row[j]) > PEAK_SIGMA * s1 for row, j in zip(per_loop, best)):
                peaks = tuple(j + 1 for j in best)
        ts.append(float(tstat[k]))
        ks.append(k)
        # the flagged links' amplitudes: a neighbour's (within the lobe, or at the twin) after the earlier flag
        # is taken out, as scanned; links apart fitted together (fitted alone, each takes in rho times the other's)
        a_mat, a_inv = _placement_solve(np.array(ks), rho, lobe)
        joint = fit0[:, ks] @ a_inv.T
        amps = joint.mean(axis=0)
        shape = lmap.shape - _placed(tmpl, ks, amps)[None]
        extra = _leftover(ks, amps, rho, (mismatch, mismatch_floor), range(len(ks)))
    flags = []
    if ks:
        ka = np.array(ks)
        rel = np.sqrt(np.clip(np.diag(a_inv @ r_noise[(ka[None, :] - ka[:, None]) % n] @ a_inv.T), 0.0, None))
        flags = [
            _flag_of(i, ks, t, joint, amps, a_mat, rel[i], (sig, s1, scale), lmap.shape, tmpl, rho,
                     (r_noise, alone, alpha, err), (mismatch, mismatch_floor))
            for i, t in enumerate(ts)
        ]  # fmt: skip
    residual = tstat if len(flags) < max_flags else None  # the last pass fitted what the flags left
    return LinkScan(
        tuple(flags), first[0], thr, alpha, dof, first[1], first[2], L, "signature", peaks=peaks, residual=residual
    )


def _lobe(rho):
    """The first lag (links) where two placements' fits stop overlapping, ``rho <= 0``; ``rho.size`` if never."""
    return int(np.argmax(rho <= 0.0)) if np.any(rho <= 0.0) else rho.size


def _placement_solve(ks, rho, lobe):
    """``A`` and ``A^-1`` for the flagged placements ``ks`` (0-based, in the order flagged): their fits to the map alone are
    ``A a``, ``A_ij = rho(k_j - k_i)`` where the two are apart (outside each other's lobe, ``|rho| < RHO_APART``:
    fitted together) or where ``j`` was flagged before ``i`` (a neighbour's amount is what is left after the
    earlier flag is taken out, as the scan found it: fitted together, two placements that overlap nearly as much as
    one split one link's excess between them); one placement, or neighbours only, give the scan's own amounts."""
    n, m = rho.size, ks.size
    d = (ks[None, :] - ks[:, None]) % n
    r = rho[d]
    apart = (np.minimum(d, n - d) >= lobe) & (np.abs(r) < RHO_APART)
    a = np.where(apart | np.tri(m, k=-1, dtype=bool), r, 0.0)
    np.fill_diagonal(a, 1.0)
    if np.linalg.cond(a) > 1e6:  # many links apart that together overlap: the scan's own amounts
        a = np.where(np.tri(m, dtype=bool), r, 0.0)
    return a, np.linalg.inv(a)


def _placed(tmpl, ks, amps):
    """The signature placed at the 0-based links ``ks`` with amplitudes ``amps``, summed: ``(n_links, points)``."""
    return sum(a * np.roll(tmpl, k, axis=0) for k, a in zip(ks, amps))


def _leftover(ks, amps, rho, mismatch, which):
    """The variance that the flags ``which`` (indices into ``ks``) leave at every link through their signature's
    error (``mismatch``: near them and everywhere, relative)."""
    near, floor = mismatch
    return sum(
        ((near * amps[i] * np.roll(rho, ks[i])) ** 2 + (floor * amps[i]) ** 2 for i in which), np.zeros(rho.size)
    )


def _flag_of(i, ks, t, joint, amps, a_mat, rel_sd, sigmas, shape, tmpl, rho, decide, mismatch):
    """Flag ``i`` with its amount, sigma and loops from the placements' fit (``rel_sd`` its sigma over one placement
    fitted alone), its alternatives from the map net of the flags its amount is net of (another flagged link's own
    placement is then no alternative)."""
    (sig, s1, scale), (r_noise, alone, alpha, err) = sigmas, decide
    k, amp = ks[i], amps[i]
    others = [j for j in range(len(ks)) if j != i and a_mat[i, j] != 0.0]
    rest = shape - _placed(tmpl, [ks[j] for j in others], amps[others])[None] if others else shape
    fit = _fit_signature(rest, tmpl).mean(axis=0)
    sd = np.sqrt(sig * sig + _leftover(ks, amps, rho, mismatch, others))
    alt = _alternatives(np.sign(amp) * fit / sd, k, rho, r_noise, alone, alpha, err)
    return LinkFlag(k + 1, t, float(amp * scale), float(sig * rel_sd * scale), "signature",
                    _loops_showing(joint, i, amp, s1 * rel_sd), alt)  # fmt: skip


def _alternatives(t, k, rho, r_noise, floor, alpha, err):
    """1-based links ``j`` where the signature fits nearly as well as at ``k`` (``t`` signed so that ``t[k] > 0``):
    local maxima outside ``k``'s lobe, past ``floor``, with ``t[k] - t[j]`` under the noise's one-sided ``alpha``
    quantile of that difference plus what a signature error ``err`` (relative) can move it."""
    n = t.size
    lobe = _lobe(rho)
    z = float(scipy.stats.norm.isf(alpha))
    out = []
    for j in np.argsort(-t):
        d = (int(j) - k) % n
        if t[j] <= floor or min(d, n - d) < lobe or not (t[j] >= t[(j - 1) % n] and t[j] >= t[(j + 1) % n]):
            continue
        allowed = z * math.sqrt(max(2.0 * (1.0 - r_noise[d]), 0.0)) + err * t[k] * math.sqrt(
            max(2.0 * (1.0 - rho[d]), 0.0)
        )
        if t[k] - t[j] < allowed:
            out.append(int(j) + 1)
    return tuple(out)


def _scan_own(lmap, alpha):
    """Each link's own cycle: mean level and duration against the pooled loop-to-loop scatter."""
    n, L = lmap.n_links, lmap.loops
    dof = n * (L - 1) - 1
    thr = sidak_threshold(alpha, 2 * n, dof)
    # a worn link is the same every loop: its own loop-to-loop scatter is the pool's; one far beyond it (an F test
    # at the same family-wise probability) is a deviation of some loops only, not flagged
    f_max = float(scipy.stats.f.isf(-math.expm1(math.log1p(-alpha) / (2 * n)), L - 1, dof))
    best_t = np.zeros(n)
    best_a = np.zeros(n)
    best_s = np.zeros(n)
    flags, unsteady = [], set()
    for name, feat in (("level", lmap.level), ("duration", lmap.duration_s)):
        m = feat.mean(axis=0)
        ss = np.sum((feat - m) ** 2, axis=0)  # per link
        tot = float(ss.sum())
        # leave the tested link's own scatter out of the pool (a deviating link may also scatter)
        s2 = (tot - ss) / (n * (L - 1) - (L - 1))
        d = m - m.mean()
        sig = np.sqrt(s2 * (1.0 - 1.0 / n) / L)
        # a feature without scatter (a duration from an exact shaft angle) gives no evidence
        tstat = np.where(sig > 0, np.abs(d) / np.where(sig > 0, sig, 1.0), 0.0)
        better = tstat > best_t
        best_t = np.where(better, tstat, best_t)
        best_a = np.where(better, d, best_a)
        best_s = np.where(better, sig, best_s)
        for k in np.flatnonzero(tstat > thr):
            if ss[k] / (L - 1) > f_max * s2[k]:
                unsteady.add(int(k) + 1)
                continue
            s1 = math.sqrt(s2[k])
            loops = tuple(
                int(i) + 1
                for i in np.flatnonzero(
                    (np.sign(feat[:, k] - m.mean()) == np.sign(d[k])) & (np.abs(feat[:, k] - m.mean()) > 2 * s1)
                )
            )
            flags.append(LinkFlag(int(k) + 1, float(tstat[k]), float(d[k]), float(sig[k]), name, loops))
    best = {}
    for f in sorted(flags, key=lambda f: -f.t):  # one flag per link: its stronger feature
        best.setdefault(f.link, f)
    unsteady -= set(best)
    return LinkScan(
        tuple(best.values()), best_t, thr, alpha, float(dof), best_a, best_s, L, "own cycle", tuple(sorted(unsteady))
    )
