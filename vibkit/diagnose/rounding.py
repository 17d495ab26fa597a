"""Numbers as precise as what was measured: every value printed by a command, a report page or a fleet row is
rounded here, to two significant digits of its standard deviation.

:func:`fmt_pm` is the one rounding rule (``value +- sigma``); :func:`decimals_for` gives the decimal places it
uses, for a table that prints the value and the sigma in separate columns; without a sigma a value gets a stated
number of significant digits and the caller says why there is no ``+-`` (never ``+- 0``).
"""

from __future__ import annotations

import math

__all__ = ["length_scale", "fmt_pm", "fmt_length", "decimals_for", "fmt_value", "SPEED_SIGMA_NOT_STATED"]

#: what a value whose uncertainty includes an unstated speed uncertainty says instead of ``+- 0``
SPEED_SIGMA_NOT_STATED = "speed uncertainty not stated"


def _finite_positive(sigma) -> bool:
    return sigma is not None and math.isfinite(float(sigma)) and float(sigma) > 0


def decimals_for(sigma, default=2) -> int:
    """Decimal places of two significant digits of ``sigma`` (``default`` without a positive finite sigma);
    may be negative (rounding to tens)."""
    if not _finite_positive(sigma):
        return default
    d = 1 - int(math.floor(math.log10(float(sigma))))
    # a sigma that rounds up to a third digit (0.09999 to 0.100) has its two digits one place to the left (0.10)
    return d - 1 if round(float(sigma), d) >= 10.0 ** (2 - d) else d


def fmt_value(value, sigma, *, sign=False, default_decimals=2) -> str:
    """``value`` alone, to the decimal place of two significant digits of ``sigma`` (``n/a`` when not finite)."""
    if value is None or not math.isfinite(float(value)):
        return "n/a"
    dec = decimals_for(sigma, default_decimals)
    s = "+" if sign else ""
    if dec <= 0:
        q = 10.0 ** (-dec)
        return f"{round(float(value) / q) * q:{s}.0f}"
    return f"{float(value):{s}.{dec}f}"


def fmt_pm(value, sigma, unit="", digits=4, *, sign=False):
    """``value +- sigma unit`` with sigma to two significant digits and the value to the same decimal
    place; without a positive finite sigma the value to ``digits`` significant digits (never ``+- 0``)."""
    if value is None or not math.isfinite(float(value)):
        return "n/a"
    v = float(value)
    u = f" {unit}" if unit else ""
    s = "+" if sign else ""
    if not _finite_positive(sigma):
        return f"{v:{s}.{digits}g}{u}"
    sg = float(sigma)
    dec = decimals_for(sg)
    if dec <= 0:
        q = 10.0 ** (-dec)
        return f"{round(v / q) * q:{s}z.0f} +- {round(sg / q) * q:.0f}{u}"
    return f"{v:{s}z.{dec}f} +- {sg:.{dec}f}{u}"


def fmt_length(value_m, sigma_m=None, digits=5):
    """A length given in m, shown in mm (rounded to its sigma when one is given)."""
    if value_m is None:
        return "n/a"
    return fmt_pm(1000.0 * value_m, None if sigma_m is None else 1000.0 * sigma_m, "mm", digits)


def fmt_band(band, sep="-") -> str:
    """A frequency band ``(low, high)`` [Hz] as ``"3.90-6.09 Hz"``: a setting, not a measurement, to one common
    number of decimals (two: 0.01 Hz, a fraction of a per cent of a link pass)."""
    lo, hi = (float(v) for v in band)
    return f"{lo:.2f}{sep}{hi:.2f} Hz"


def fmt_interval(value, lo, hi, *, sign=True) -> str:
    """``value [lo, hi]`` to the decimals that the interval's half-width allows (two significant digits of it, as
    :func:`fmt_value` does for a sigma): ``+19.62 [-82.07, +121.30]`` reads ``+20 [-80, +120]``."""
    half = (float(hi) - float(lo)) / 2.0
    return f"{fmt_value(value, half, sign=sign)} [{fmt_value(lo, half, sign=sign)}, {fmt_value(hi, half, sign=sign)}]"


def length_scale(units, peak):
    """A readable unit for a plot of ``units`` whose values reach ``peak``: (factor, unit).

    Lengths in metres are plotted in micrometres below 1 mm and in millimetres below 1 m, as the
    report's tables give them (a tensioner's 27 um ripple reads as 27 um, not 2.7e-5 m); every other
    unit is left as it is.
    """
    peak = float(peak) if peak is not None else float("nan")
    if units != "m" or not math.isfinite(peak) or peak <= 0.0:
        return 1.0, units
    if peak < 1e-3:
        return 1e6, "\u00b5m"
    if peak < 1.0:
        return 1e3, "mm"
    return 1.0, "m"
