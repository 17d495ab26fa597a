"""What a run may cost, checked before it starts: the size of its result and its wall time.

A scene or an option can imply absurd work: ``--duration 1e9``, ``output_step = 1e-9`` or a
kinematic ``step = 1e-12`` ask for terabytes of samples; ``max_step = 1e-12`` for 1e13 integrator
steps.  :func:`check_run` estimates the memory the result arrays need (samples x columns x 8 bytes,
the columns being those the analysis allocates for the outputs asked for) and the least number of
integrator steps, and raises :class:`BudgetError` naming the file, the key and the limit before any
work is done.  The forward dynamics also get a wall-time budget by default
(:func:`max_wall_time`); the integrator stops with :class:`vibkit.analyses.integrate.IntegrationError`
when it is exceeded.

Limits, the first given wins:

=====================  ============================  ==============================  =================
limit                  keyword / CLI option          scene key                       environment
=====================  ============================  ==============================  =================
result size [bytes]    ``max_result_bytes`` /        ``[solver] max_result_bytes``   ``VIBKIT_MAX_RESULT_BYTES``
                       ``--max-result-bytes``
wall time [s]          ``max_wall_time`` /           ``[solver] max_wall_time``      ``VIBKIT_MAX_WALL_TIME``
                       ``--max-wall-time``
=====================  ============================  ==============================  =================

Defaults: :data:`DEFAULT_MAX_RESULT_BYTES` (2 GiB) and :data:`DEFAULT_MAX_WALL_TIME` (600 s).
``inf`` (or 0 on the command line) removes a limit.
"""

from __future__ import annotations

import math
import os
import re

__all__ = [
    "BudgetError",
    "DEFAULT_MAX_RESULT_BYTES",
    "DEFAULT_MAX_WALL_TIME",
    "MAX_INTEGRATOR_STEPS",
    "estimate_result",
    "check_run",
    "max_result_bytes",
    "max_wall_time",
    "parse_bytes",
]

#: default limit of the result arrays' size [bytes]
DEFAULT_MAX_RESULT_BYTES = 2 * 1024**3
#: default wall-time budget of a forward-dynamics integration [s]
DEFAULT_MAX_WALL_TIME = 600.0
#: a forward run whose max_step implies more steps than this is refused (1e8 steps: hours)
MAX_INTEGRATOR_STEPS = 1e8

_SUFFIX = {
    "": 1,
    "b": 1,
    "k": 1e3,
    "kb": 1e3,
    "m": 1e6,
    "mb": 1e6,
    "g": 1e9,
    "gb": 1e9,
    "t": 1e12,
    "tb": 1e12,
    "kib": 1024,
    "mib": 1024**2,
    "gib": 1024**3,
    "tib": 1024**4,
}


class BudgetError(ValueError):
    """A run that would exceed a stated limit (the message names the limit and how to raise it)."""


def parse_bytes(text) -> float:
    """Bytes from ``2e9``, ``500M``, ``2GiB``, ``inf`` (``0`` also means no limit).

    Raises
    ------
    ValueError
        Not a non-negative number with an optional unit (B, kB, MB, GB, TB, KiB, MiB, GiB, TiB).
    """
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        v = float(text)
    else:
        m = re.fullmatch(r"\s*([0-9.eE+\-]+|inf)\s*([a-zA-Z]*)\s*", str(text))
        if not m or m.group(2).lower() not in _SUFFIX:
            raise ValueError(f"expected a size in bytes such as 2e9, 500MB or 2GiB, got {text!r}")
        try:
            v = float(m.group(1)) * _SUFFIX[m.group(2).lower()]
        except ValueError:
            raise ValueError(f"expected a size in bytes such as 2e9, 500MB or 2GiB, got {text!r}") from None
    if math.isnan(v) or v < 0:
        raise ValueError(f"expected a non-negative size in bytes, got {text!r}")
    return math.inf if v == 0 else v


def _env(name, parse):
    raw = os.environ.get(name, "").strip()
    if not raw:
        return None
    try:
        v = parse(raw)
    except ValueError as exc:
        raise BudgetError(f"environment variable {name}: {exc}") from None
    return v


def _seconds(text) -> float:
    try:
        v = float(text)
    except ValueError:
        raise ValueError(f"expected a number of seconds, got {text!r}") from None
    if math.isnan(v) or v < 0:
        raise ValueError(f"expected a non-negative number of seconds, got {text!r}")
    return math.inf if v == 0 else v


def max_result_bytes(scene, override=None) -> float:
    """The result-size limit [bytes] that applies to ``scene`` (see the module docstring)."""
    if override is not None:
        return parse_bytes(override)
    if scene.solver.max_result_bytes is not None:
        return parse_bytes(scene.solver.max_result_bytes)
    env = _env("VIBKIT_MAX_RESULT_BYTES", parse_bytes)
    return DEFAULT_MAX_RESULT_BYTES if env is None else env


def max_wall_time(scene, override=None) -> float:
    """The wall-time budget [s] of a forward run of ``scene`` (see the module docstring)."""
    if override is not None:
        return _seconds(override)
    if scene.solver.max_wall_time is not None:
        return float(scene.solver.max_wall_time)
    env = _env("VIBKIT_MAX_WALL_TIME", _seconds)
    return DEFAULT_MAX_WALL_TIME if env is None else env


def _samples(scene, duration):
    """(number of samples, the key that sets it, the span key) of a run; floats, no allocation."""
    if scene.analysis == "kinematics":
        k = scene.kinematics
        span = duration if duration is not None else k.stop - k.start
        return (
            span / k.step + 1,
            "kinematics.step",
            "kinematics.stop - kinematics.start" if duration is None else "--duration",
        )
    if scene.analysis == "inverse":
        m = scene.motion
        span = duration or m.duration
        return span / m.step + 1, "motion.step", "motion.duration" if duration is None else "--duration"
    r = scene.run
    span = duration or r.duration
    return span / r.output_step + 1, "run.output_step", "run.duration" if duration is None else "--duration"


def estimate_result(scene, duration=None) -> dict:
    """Samples, columns and bytes of the arrays a run of ``scene`` allocates for its result.

    Parameters
    ----------
    scene : Scene
    duration : float, optional
        The ``duration`` given to :func:`vibkit.simulate` [s] (kinematics: [m]).

    Returns
    -------
    dict
        ``samples``, ``columns`` (float64 values per sample), ``bytes`` (= samples x columns x 8),
        ``step_key`` and ``span_key`` (what sets the number of samples).
    """
    n = scene.chain.n_rollers
    teeth = scene.sprocket.teeth
    outputs = set(scene.outputs["variables"])
    nr = len(scene.outputs["rollers"])
    if scene.analysis == "kinematics":
        cols = 1 + 2 + 1 + 2 * nr
    elif scene.analysis == "inverse":
        cols = 1 + 10 + n + 6 * nr  # the inverse allocates every column whatever is asked
    else:
        cols = (
            1
            + 5
            + 12
            + 6 * nr
            + (n if "link_tension" in outputs else 0)
            + (2 * teeth if outputs & {"indentation", "contact_force"} else 0)
        )
    samples, step_key, span_key = _samples(scene, duration)
    return {
        "samples": samples,
        "columns": cols,
        "bytes": samples * cols * 8.0,
        "step_key": step_key,
        "span_key": span_key,
    }


def _fmt_bytes(b: float) -> str:
    if not math.isfinite(b):
        return "unlimited"
    for unit, f in (("TiB", 1024**4), ("GiB", 1024**3), ("MiB", 1024**2), ("KiB", 1024)):
        if b >= f:
            return f"{b / f:.3g} {unit}"
    return f"{b:.0f} B"


def check_run(scene, *, duration=None, limit_bytes=None) -> dict:
    """Refuse a run whose result or step count would exceed the limits, before any work.

    Parameters
    ----------
    scene : Scene
    duration : float, optional
        As given to :func:`vibkit.simulate`.
    limit_bytes : float or str, optional
        Overrides the scene's / environment's result-size limit [bytes].

    Returns
    -------
    dict
        :func:`estimate_result`, plus ``limit_bytes``.

    Raises
    ------
    BudgetError
        The result would be larger than the limit, or ``solver.max_step`` implies more than
        :data:`MAX_INTEGRATOR_STEPS` steps; the message names the file and the key.
    """
    est = estimate_result(scene, duration)
    limit = max_result_bytes(scene, limit_bytes)
    est["limit_bytes"] = limit
    src = scene.source
    if not math.isfinite(est["samples"]) or est["bytes"] > limit:
        raise BudgetError(
            f"{src}: the run asks for {est['samples']:.3g} samples ({est['span_key']} / '{est['step_key']}') x "
            f"{est['columns']} values = {_fmt_bytes(est['bytes'])} of results, more than the limit of "
            f"{_fmt_bytes(limit)}; shorten the run, take a larger '{est['step_key']}', or raise the limit "
            "([solver] max_result_bytes, VIBKIT_MAX_RESULT_BYTES or --max-result-bytes)"
        )
    if scene.analysis == "forward":
        ms = scene.solver.max_step
        span = duration or scene.run.duration
        if span / ms > MAX_INTEGRATOR_STEPS:
            raise BudgetError(
                f"{src}: 'solver.max_step' = {ms:g} s forces at least {span / ms:.3g} integrator steps over "
                f"{span:g} s (more than {MAX_INTEGRATOR_STEPS:.0e}: hours of work); take max_step >= "
                f"{span / MAX_INTEGRATOR_STEPS:.2g} s or leave it out (the step is adaptive)"
            )
    return est
