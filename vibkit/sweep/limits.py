"""What a sweep may ask for, checked before anything is allocated: keys its analysis uses, a start-up
that leaves samples, and the size of its result.

* :func:`check_key_used`: a varied key must change what the scene's analysis computes.  An inverse
  run reads ``[motion]``, not ``[run]`` or ``[solver]``; a kinematic sweep reads ``[kinematics]``
  and the geometry only; ``run.seed`` is read by no analysis; a key that ``duration`` overrides
  (``run.duration``, ``motion.duration``, ``kinematics.stop``) changes nothing either.  Such a sweep
  would give identical runs and is refused, naming the key and the analysis.
* :func:`check_settle`: the start-up left out of the summaries must leave at least two samples.
* :func:`estimate_sweep` / :func:`check_size`: runs x (summaries + kept series) x 8 bytes, plus the
  driver's bookkeeping per run (:data:`BYTES_PER_RUN`), from the plan's shape alone (floats, no
  allocation), refused past the result budget of :mod:`vibkit.runtime.budget` (2 GiB by default;
  ``max_result_bytes=`` / ``--max-result-bytes``, ``VIBKIT_MAX_RESULT_BYTES``).

The scene's declarations only at load time (:mod:`vibkit.model.schema`: the effects each analysis
applies, the columns of each output).
"""

from __future__ import annotations

import math

from ..model.schema import ANALYSIS_EFFECTS, OUTPUT_COLUMNS
from ..runtime.budget import BudgetError, _fmt_bytes, check_run, max_result_bytes
from .errors import SweepError
from .records import SUMMARIES

__all__ = ["check_key_used", "check_settle", "estimate_sweep", "check_size", "BYTES_PER_RUN"]

#: what the driver keeps per run besides the numbers (its record in memory, its group in the store) [bytes]
BYTES_PER_RUN = 1024

# the sections an analysis reads (keys of other sections change nothing); None: every key of the section
_READS = {
    "kinematics": {
        "guide": None,
        "chain": None,
        "sprocket": {"teeth", "base_width", "tip_width", "tooth_height"},
        "kinematics": None,
    },
    "inverse": {"guide": None, "chain": None, "sprocket": None, "motion": None},
    "forward": {
        "guide": None,
        "chain": None,
        "sprocket": None,
        "run": {"duration", "output_step", "start", "initial_speed"},
        "solver": None,
    },
}
# the effects an analysis applies (every effect of the schema, for the forward dynamics)
_EFFECTS = ANALYSIS_EFFECTS
# keys that the duration override replaces
_OVERRIDDEN = {"kinematics": "kinematics.stop", "inverse": "motion.duration", "forward": "run.duration"}


def check_key_used(key: str, analysis: str, source: str, *, duration=None):
    """Raise :class:`~vibkit.sweep.plan.SweepError` if varying ``key`` cannot change an ``analysis`` run."""
    parts = key.split(".")
    hint = "vary a key the analysis reads"
    if parts[0] == "effects":
        if parts[1] not in _EFFECTS[analysis]:
            raise SweepError(
                f"{source}: varying '{key}' would give identical runs: the {analysis} analysis does not "
                f"apply effects.{parts[1]} (it applies: {', '.join(sorted(_EFFECTS[analysis])) or 'none'})"
                f"; {hint}"
            )
    else:
        reads = _READS[analysis]
        if parts[0] not in reads:
            raise SweepError(
                f"{source}: varying '{key}' would give identical runs: the {analysis} analysis does not "
                f"read [{parts[0]}] (it reads [{'], ['.join(reads)}]); {hint}"
            )
        keys = reads[parts[0]]
        if keys is not None and parts[1] not in keys:
            raise SweepError(
                f"{source}: varying '{key}' would give identical runs: the {analysis} analysis does not "
                f"use it (of [{parts[0]}] it uses {', '.join(sorted(keys))}); {hint}"
            )
    if duration is not None and key == _OVERRIDDEN[analysis]:
        raise SweepError(
            f"{source}: varying '{key}' would give identical runs: --duration / duration= "
            f"({duration:g}) replaces it in every run; leave one of them out"
        )


def _span_and_step(scene, duration):
    """(span, output step, the step's key) of a run: seconds (kinematics: metres of advance)."""
    if scene.analysis == "kinematics":
        k = scene.kinematics
        return (duration if duration is not None else k.stop - k.start), k.step, "kinematics.step"
    if scene.analysis == "inverse":
        m = scene.motion
        return (duration or m.duration), m.step, "motion.step"
    r = scene.run
    return (duration or r.duration), r.output_step, "run.output_step"


def check_settle(scene, settle, duration, source):
    """``settle`` [s] must leave at least two output samples of the run (and needs a time axis)."""
    if settle is None:
        return
    if scene.analysis == "kinematics":
        raise SweepError(
            f"{source}: settle applies to runs along time (inverse, forward); a kinematic sweep has "
            f"no start-up; leave --settle out"
        )
    span, step, key = _span_and_step(scene, duration)
    if not settle <= span - step:
        raise SweepError(
            f"{source}: --settle {settle:g} s leaves fewer than two samples of the {span:g} s runs "
            f"('{key}' = {step:g} s); take a settle below {max(span - step, 0.0):g} s or a longer run"
        )


def estimate_sweep(scene, runs: int, keep=(), duration=None) -> dict:
    """Runs, values per run and bytes of a sweep's result, from numbers alone (nothing allocated).

    Returns
    -------
    dict
        ``runs``, ``samples`` (per run), ``values_per_run`` (summaries + status + wall time + the kept
        series' samples x columns), ``bytes`` (= runs x (values x 8 + :data:`BYTES_PER_RUN`)).
    """
    span, step, _ = _span_and_step(scene, duration)
    samples = span / step + 1 if step > 0 else math.inf
    cols = {"n": scene.chain.n_rollers, "t": scene.sprocket.teeth, "r": len(scene.outputs["rollers"])}
    kept = 0.0
    for name in keep:
        # an output's own columns; one variable of an output that gives several (kinetic_energy) is one
        c = OUTPUT_COLUMNS.get(name, "1")
        kept += samples * (int(c[:-1] or 1) * cols[c[-1]] if c[-1] in cols else int(c))
    values = len(SUMMARIES) + 2 + kept
    return {
        "runs": runs,
        "samples": samples,
        "values_per_run": values,
        "bytes": float(runs) * (values * 8.0 + BYTES_PER_RUN),
    }


def check_size(scene, runs: int, *, keep=(), duration=None, limit_bytes=None, source=""):
    """Refuse a sweep whose result would exceed the result budget, in one line naming size and option."""
    if duration is not None:  # each run as simulate would refuse it (--duration 1e308: every run would fail)
        check_run(scene, duration=duration)
    est = estimate_sweep(scene, runs, keep, duration)
    limit = max_result_bytes(scene, limit_bytes)
    est["limit_bytes"] = limit
    if not math.isfinite(est["bytes"]) or est["bytes"] > limit:
        kept = f", {est['samples']:.3g} samples of each kept output" if keep else ""
        raise BudgetError(
            f"{source}: the sweep asks for {runs:.4g} runs x {est['values_per_run']:.4g} values{kept} = "
            f"{_fmt_bytes(est['bytes'])} of results (with {BYTES_PER_RUN} B of bookkeeping a run), more than the "
            f"limit of {_fmt_bytes(limit)}; vary fewer values, keep fewer series, or raise the limit "
            f"(--max-result-bytes, [solver] max_result_bytes or VIBKIT_MAX_RESULT_BYTES)"
        )
    return est
