"""Is a measurement fit for a trend?  The quality flag stored with every measurement.

A measurement is stored whatever its quality, but only ``"ok"`` ones enter a unit's trend:

``"implausible"``
    The elongation lies outside the physical window :data:`PHYSICAL_WINDOW_PERCENT` (a worn chain
    is replaced at 3 %; no chain runs at 6 %, and a chain is never shorter than its nominal pitch
    by more than the manufacturing tolerance): the link pass is not this chain's, or the speed or
    the nominal pitch is wrong.
``"inconclusive"``
    The elongation's standard deviation is wider than a third of the first limit (0.5 % for the
    limits 1.5 / 2 / 3 %): too short or too noisy a recording to tell one limit from the next.
``"ok"``
    Neither.

The pitch analysis' own decision (:func:`vibkit.diagnose.pitch.estimate_pitch`, where it gives one as
``decision``) is taken when it is stricter.
"""

from __future__ import annotations

import math

from ..diagnose.decision import ELONGATION_WINDOW_PERCENT
from ..diagnose.pitch import DEFAULT_LIMITS_PERCENT

__all__ = ["PHYSICAL_WINDOW_PERCENT", "QUALITIES", "measurement_quality"]

#: stored quality flags; only "ok" measurements enter a trend
QUALITIES = ("ok", "inconclusive", "implausible")
#: elongations a real chain can have [%]: the pitch decision's window (shorter than nominal by 1 % at most,
#: 6 % at most; a chain is replaced at 3 %), one definition for both
PHYSICAL_WINDOW_PERCENT = ELONGATION_WINDOW_PERCENT


def _decision_word(decision):
    """'inconclusive' / 'implausible' from the pitch analysis' decision (a word or an object), else None."""
    if decision is None:
        return None
    for attr in ("verdict", "status", "decision"):
        v = getattr(decision, attr, None)
        if isinstance(v, str):
            decision = v
            break
    text = str(decision).lower()
    for word in ("implausible", "inconclusive"):
        if word in text:
            return word
    return None


def measurement_quality(
    elongation_percent, sigma_percent, *, limits_percent=DEFAULT_LIMITS_PERCENT, decision=None, speed_sigma_percent=None
):
    """The quality flag of one measurement and its reason: ``(flag, reason)``, flag in :data:`QUALITIES`.

    Parameters
    ----------
    elongation_percent, sigma_percent : float
        The measured elongation and its standard deviation. [%]
    limits_percent : sequence of float
        Elongation limits; the first sets the resolution a measurement needs. [%]
    decision : str or object, optional
        The pitch analysis' decision; ``"inconclusive"`` or ``"implausible"`` in it is kept.
    speed_sigma_percent : float, optional
        The speed's relative standard deviation [%]: where it makes most of the sigma, the advice is to measure the
        speed, not to record longer.

    Examples
    --------
    >>> measurement_quality(0.8, 0.05)
    ('ok', '')
    >>> measurement_quality(52.0, 0.4)[0]
    'implausible'
    >>> measurement_quality(0.8, 0.9)[0]
    'inconclusive'
    >>> measurement_quality(0.8, 2.93, speed_sigma_percent=2.9)[1]  # the speed's tolerance: recording longer won't help
    "elongation sigma 2.93 % is wider than a third of the first limit (0.50 %): the speed's sigma alone is 2.90 %: measure the speed on the steps"
    """
    e, s = float(elongation_percent), float(sigma_percent)
    lo, hi = PHYSICAL_WINDOW_PERCENT
    if not (math.isfinite(e) and math.isfinite(s)):
        return "implausible", "elongation or its sigma is not a finite number"
    if not lo <= e <= hi:
        return "implausible", (
            f"elongation {e:+.2f} % is outside the physical window {lo:+g} to {hi:+g} % (a chain "
            "is replaced at 3 %, never shorter than nominal): check the speed, the channel, "
            "the nominal pitch"
        )
    word = _decision_word(decision)
    why = getattr(decision, "reason", None) or decision  # a Decision's reason, not its repr
    if word == "implausible":
        return "implausible", f"the pitch analysis calls it implausible ({why})"
    need = min(float(x) for x in limits_percent) / 3.0
    if not s <= need:
        return "inconclusive", (
            f"elongation sigma {s:.2f} % is wider than a third of the first limit "
            f"({need:.2f} %): "
            + (
                f"the speed's sigma alone is {speed_sigma_percent:.2f} %: measure the speed on the steps"
                if speed_sigma_percent is not None and speed_sigma_percent**2 >= 0.5 * s * s
                else "record longer or closer to the chain"
            )
        )
    if word == "inconclusive":
        return "inconclusive", f"the pitch analysis calls it inconclusive ({why})"
    return "ok", ""
