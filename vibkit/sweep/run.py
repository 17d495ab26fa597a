"""Parameter sweeps: one scene, some of its keys varied, every run on Dask, results streamed to Zarr.

``vibkit.sweep(scene, {"chain.link_pitch": "0.1333:0.1373:9", "effects.contact.stiffness": [1e5, 1e6, 1e7]})``
runs the 27 varied scenes and returns one :class:`xarray.Dataset` whose dimensions are the varied
keys, holding per-run summaries (link-pass frequency, delta mean and ripple, peak link tension,
contact episodes, wall time ...), a ``status`` and an ``error`` per run, and the full time series of
the outputs asked for with ``keep``. With ``samples=N`` the keys are drawn at random (uniformly in
``A:B``, or among the listed values) and the dimension is ``sample``.

Keys are the scene TOML's dotted keys (``chain.link_pitch``, ``effects.contact.stiffness``,
``solver.rtol`` ...). A key the scene loader does not know, or an effect the scene does not switch
on, is an error naming the key before any run starts; every varied scene is validated when the
sweep is planned, and a varied value the loader refuses is recorded as that run's failure
(status ``invalid``), as is a run whose integration fails (status ``failed``): neither stops the sweep.

Storage (``output=...``, a Zarr directory, format 2): the root group's attrs hold the sweep's
definition; each finished run is written by the driver to its own group ``runs/rNNNNNN`` (kept
series first, then the summaries and ``done = true`` in the group's attrs, one atomic file
replace), so a run counts as done only when both are on disk. Re-running the same sweep on the same
store resumes: finished runs are read back, only the others are computed. When every run is done
the results are consolidated into the root group (``xr.open_zarr(path)`` reads them), the per-run
groups are removed and the metadata consolidated. A store that holds a different sweep is refused
unless ``force=True``. The workers never touch the store, so a remote Dask cluster works without a
shared file system.

This module imports only the standard library at load time (``vibkit/__init__`` imports its
``sweep`` function eagerly, so that ``vibkit.sweep.run`` is always the function; the module itself is
``sys.modules["vibkit.sweep.run"]``, and ``from vibkit.sweep.run import parse_vary`` works as usual).
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import shutil
import sys
import time
import traceback
from pathlib import Path

__all__ = ["sweep", "parse_vary", "plan_sweep", "SweepPlan", "SweepError", "summarize", "SUMMARIES", "STATUS"]

SCHEMA = 1

#: run status codes (the ``status`` variable; CF ``flag_values`` / ``flag_meanings``)
STATUS = {"ok": 0, "failed": 1, "invalid": 2}
PENDING = -1

#: per-run summaries: name -> (units, long_name)
SUMMARIES = {
    "link_pass_frequency": ("Hz", "link-pass frequency: forward, roller 1's advance along the guide after the "
                                  "start-up / time / mean pitch; inverse, imposed speed / mean pitch"),
    "delta_mean": ("m", "mean tensioner displacement delta after the start-up"),
    "delta_ripple": ("m", "peak-to-peak of delta after the start-up"),
    "peak_link_tension": ("N", "largest link tension of the run (needs the link_tension output)"),
    "contact_episodes": ("1", "roller-tooth contact episodes, summed over teeth (needs the contact_force output)"),
    "last_contact_time": ("s", "last time any tooth carries a contact force (needs the contact_force output)"),
    "back_flank_episodes": ("1", "episodes of load on the back flanks (needs the flank_force output)"),
    "last_back_flank_time": ("s", "last time a back flank carries load (needs the flank_force output)"),
    "closure_residual_max": ("m", "largest closure residual of the run"),
    "solver_steps": ("1", "integrator steps (forward dynamics)"),
    "wall_time": ("s", "wall time of the run in its worker (the first run of a worker includes loading the "
                       "compiled kernels)"),
}

# units of the scene keys a sweep can vary (the coordinates' ``units``)
KEY_UNITS = {
    "guide.tensioner_length": "m", "guide.lower_landing": "m", "guide.upper_landing": "m",
    "guide.transition_radius": "m", "guide.incline_angle_deg": "deg", "guide.incline_length": "m",
    "guide.head_radius": "m",
    "chain.link_pitch": "m", "chain.roller_radius": "m", "chain.roller_mass": "kg", "chain.n_rollers": "1",
    "chain.worn_link": "1", "chain.worn_link_pitch": "m",
    "sprocket.teeth": "1", "sprocket.base_width": "m", "sprocket.tip_width": "m", "sprocket.tooth_height": "m",
    "sprocket.mass": "kg", "sprocket.inertia": "kg m^2",
    "kinematics.start": "m", "kinematics.stop": "m", "kinematics.step": "m",
    "motion.speed": "m/s", "motion.duration": "s", "motion.step": "s", "motion.start": "m",
    "run.duration": "s", "run.output_step": "s", "run.start": "m", "run.initial_speed": "m/s", "run.seed": "1",
    "solver.method": "", "solver.rtol": "1", "solver.atol": "1", "solver.max_step": "s", "solver.first_step": "s",
    "solver.max_wall_time": "s",
    "effects.gravity.g": "m/s^2", "effects.gravity.enabled": "",
    "effects.contact.stiffness": "N/m^exponent", "effects.contact.exponent": "1", "effects.contact.damping": "s/m",
    "effects.motor.kp": "N m s", "effects.motor.ki": "N m", "effects.motor.speed": "m/s",
    "effects.motor.torque_limit": "N m",
    "effects.tensioner.stiffness": "N/m", "effects.tensioner.preload": "N", "effects.tensioner.mass": "kg",
    "effects.rolling_resistance.coefficient": "1",
}

# scene outputs that give more than one dataset variable
_PRODUCES = {"flank_force": ("drive_flank_force", "back_flank_force"),
             "energy": ("kinetic_energy", "potential_energy", "contact_energy", "spring_energy")}


class SweepError(ValueError):
    """A sweep that cannot be planned or stored; the message names the key, value or path."""


# ------------------------------------------------------------------------------------------------ the plan


@dataclasses.dataclass(frozen=True)
class Axis:
    """One varied key: its values (a grid axis, or the choices of a Monte Carlo draw) or a range."""

    key: str
    spec: str                      # as the user wrote it (for messages and the stored definition)
    values: tuple | None = None    # explicit values (A:B:N expanded, or a,b,c)
    low: float | None = None       # Monte Carlo range A:B
    high: float | None = None


def parse_vary(text: str) -> tuple[str, str]:
    """Split ``KEY=SPEC`` (the CLI's ``--vary``) and check the spec's syntax.

    ``SPEC`` is ``A:B:N`` (N values from A to B, both included), ``A:B`` (a range, for Monte
    Carlo draws) or ``a,b,c`` (a list; a single value is a list of one).

    Raises
    ------
    ValueError
        The text is not ``KEY=SPEC`` or the spec is malformed (the message shows the text).
    """
    if "=" not in text:
        raise ValueError(f"expected KEY=A:B:N or KEY=a,b,c (e.g. chain.link_pitch=0.1333:0.1373:9), got {text!r}")
    key, spec = (s.strip() for s in text.split("=", 1))
    if not key or any(c.isspace() for c in key):
        raise ValueError(f"expected a dotted scene key before '=' (e.g. effects.contact.stiffness), got {text!r}")
    _split_spec(key, spec)
    return key, spec


def _split_spec(key, spec):
    """('range', (a, b, n or None)) or ('list', [str, ...]); syntax only."""
    spec = spec.strip()
    if not spec:
        raise ValueError(f"{key}: empty value list (expected A:B:N or a,b,c)")
    if ":" in spec:
        parts = [p.strip() for p in spec.split(":")]
        if len(parts) not in (2, 3) or not all(parts):
            raise ValueError(f"{key}={spec}: expected A:B:N (linspace) or A:B (a Monte Carlo range)")
        try:
            a, b = float(parts[0]), float(parts[1])
        except ValueError:
            raise ValueError(f"{key}={spec}: A and B of A:B:N must be numbers") from None
        if not (math.isfinite(a) and math.isfinite(b)):
            raise ValueError(f"{key}={spec}: A and B must be finite")
        n = None
        if len(parts) == 3:
            try:
                n = int(parts[2])
            except ValueError:
                raise ValueError(f"{key}={spec}: N of A:B:N must be a whole number of values") from None
            if n < 1:
                raise ValueError(f"{key}={spec}: N of A:B:N must be >= 1")
            if n > 1 and a == b:
                raise ValueError(f"{key}={spec}: A equals B, so the {n} values would all be the same")
        return "range", (a, b, n)
    items = [s.strip() for s in spec.split(",")]
    if not all(items):
        raise ValueError(f"{key}={spec}: an empty entry in the list a,b,c")
    return "list", items


def _scene_schema():
    from ..model.scene import EFFECTS, SECTIONS

    return SECTIONS, EFFECTS


def _key_type(key: str, base_data: dict, source: str):
    """The type(s) the scene loader expects for ``key``; SweepError naming the key if it has none."""
    SECTIONS, EFFECTS = _scene_schema()
    parts = key.split(".")
    if parts[0] == "effects":
        if len(parts) != 3 or parts[1] not in EFFECTS or parts[2] not in EFFECTS[parts[1]]:
            known = ", ".join(f"effects.{e}.{k}" for e, opts in EFFECTS.items() for k, t in opts.items()
                              if t is not list)
            raise SweepError(f"{source}: cannot vary unknown scene key '{key}' (effect keys: {known})")
        typ = EFFECTS[parts[1]][parts[2]]
        eff = base_data.get("effects", {}).get(parts[1])
        if eff is None or eff is False or (isinstance(eff, dict) and eff.get("enabled", True) is False):
            raise SweepError(f"{source}: cannot vary '{key}': the scene does not switch on effects.{parts[1]} "
                             f"(add it to the scene's [effects] first)")
    else:
        if len(parts) != 2 or parts[0] not in SECTIONS or parts[1] not in SECTIONS[parts[0]]:
            if len(parts) == 2 and parts[0] in SECTIONS:
                known = ", ".join(f"{parts[0]}.{k}" for k in SECTIONS[parts[0]])
                raise SweepError(f"{source}: cannot vary unknown scene key '{key}' "
                                 f"(known keys of [{parts[0]}]: {known})")
            raise SweepError(f"{source}: cannot vary unknown scene key '{key}' (keys are dotted like chain.link_pitch, "
                             f"effects.contact.stiffness; sections: {', '.join(SECTIONS)}, effects)")
        typ = SECTIONS[parts[0]][parts[1]]
        if parts[0] in ("scene", "outputs"):
            raise SweepError(f"{source}: '{key}' cannot be varied (it says what the scene is, not a parameter)")
    types = typ if isinstance(typ, tuple) else (typ,)
    if list in types:
        raise SweepError(f"{source}: '{key}' is a list and cannot be varied as one value")
    return types


def _convert(key, text_or_value, types):
    """A value of the type the loader expects (ints stay ints, "sprocket" stays a string ...)."""
    v = text_or_value
    if isinstance(v, str):
        s = v.strip()
        if bool in types:
            if s.lower() in ("true", "false"):
                return s.lower() == "true"
            raise SweepError(f"{key}: expected true or false, got {v!r}")
        try:
            num = float(s)
        except ValueError:
            if str in types:
                return s
            raise SweepError(f"{key}: expected a number, got {v!r}") from None
        v = int(num) if (int in types and float not in types and num.is_integer()) else num
        if int in types and float not in types and isinstance(v, float):
            raise SweepError(f"{key}: expected a whole number, got {s!r}")
        if isinstance(v, float) and not math.isfinite(v):
            raise SweepError(f"{key}: expected a finite number, got {s!r}")
        return v
    if isinstance(v, bool):
        if bool not in types:
            raise SweepError(f"{key}: expected a number, got {v!r}")
        return v
    if hasattr(v, "item"):  # numpy scalar
        v = v.item()
    if isinstance(v, (int, float)):
        if int in types and float not in types:
            if float(v).is_integer():
                return int(v)
            raise SweepError(f"{key}: expected a whole number, got {v!r}")
        if float in types:
            v = float(v)
            if not math.isfinite(v):
                raise SweepError(f"{key}: expected a finite number, got {v!r}")
            return v
        raise SweepError(f"{key}: expected {'/'.join(t.__name__ for t in types)}, got {v!r}")
    if isinstance(v, str) or str in types:
        return v
    raise SweepError(f"{key}: expected {'/'.join(t.__name__ for t in types)}, got {v!r}")


def _axis(key, spec, types, samples):
    if isinstance(spec, str):
        kind, parsed = _split_spec(key, spec)
        if kind == "range":
            a, b, n = parsed
            if samples is None:
                if n is None:
                    raise SweepError(f"{key}={spec}: a grid needs A:B:N (N values); A:B alone is a Monte Carlo range "
                                     f"(give samples / --samples)")
                if not (int in types or float in types) or bool in types:
                    raise SweepError(f"{key}={spec}: A:B:N needs a numeric key")
                import numpy as np

                vals = np.linspace(a, b, n) if n > 1 else np.array([a])
                if int in types and float not in types:
                    ints = np.round(vals)
                    if not np.allclose(vals, ints, rtol=0, atol=1e-9):
                        raise SweepError(f"{key}={spec}: '{key}' takes whole numbers and A:B:N gives fractions "
                                         f"(use a list a,b,c)")
                    vals = ints
                values = tuple(_convert(key, float(v), types) for v in vals)
                return Axis(key=key, spec=spec, values=values)
            if n is not None:
                raise SweepError(f"{key}={spec}: with samples, give a range A:B (the number of draws is samples)")
            if not a < b:
                raise SweepError(f"{key}={spec}: a Monte Carlo range A:B needs A < B")
            if not (int in types or float in types) or bool in types:
                raise SweepError(f"{key}={spec}: a range needs a numeric key")
            return Axis(key=key, spec=spec, low=a, high=b)
        values = tuple(_convert(key, s, types) for s in parsed)
    else:
        try:
            seq = list(spec)
        except TypeError:
            seq = [spec]
        if not seq:
            raise SweepError(f"{key}: empty value list")
        values = tuple(_convert(key, v, types) for v in seq)
        spec = ",".join(repr(v) if isinstance(v, float) else str(v) for v in values)
    if samples is None and len(set(values)) != len(values):
        raise SweepError(f"{key}={spec}: values repeat (each value of a grid axis must be different)")
    return Axis(key=key, spec=spec, values=values)


@dataclasses.dataclass(frozen=True)
class SweepPlan:
    """A planned sweep: the base scene, the axes and every run's values, validated.

    Attributes
    ----------
    text, source : str
        The base scene's TOML text and where it came from.
    axes : tuple of Axis
    samples, seed : int or None
        Monte Carlo draws and the seed of the generator (``None`` for a grid).
    points : tuple of dict
        Run index -> {key: value}, grid runs in C order over ``axes``.
    shape : tuple of int
        Grid shape (``(samples,)`` for Monte Carlo).
    keep : tuple of str
        Outputs whose time series are kept.
    settle : float or None
        Start-up excluded from the summaries [s] (``None``: a quarter of a forward run; none otherwise).
    duration : float or None
        Duration override passed to :func:`vibkit.simulate` [s] (kinematics: [m]).
    """

    text: str
    source: str
    analysis: str
    axes: tuple
    samples: int | None
    seed: int | None
    points: tuple
    shape: tuple
    keep: tuple
    settle: float | None
    duration: float | None

    @property
    def dims(self):
        return ("sample",) if self.samples is not None else tuple(a.key for a in self.axes)

    def definition(self) -> dict:
        """What identifies the sweep (compared on resume; stored in the root group's attrs)."""
        return {"schema": f"vibkit.sweep/{SCHEMA}", "scene": self.text,
                "axes": [{"key": a.key, "spec": a.spec} for a in self.axes],
                "samples": self.samples, "seed": self.seed,
                "points": [[_jsonval(p[a.key]) for a in self.axes] for p in self.points],
                "keep": list(self.keep), "settle": self.settle, "duration": self.duration}


def _jsonval(v):
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


def _set_key(data: dict, key: str, value):
    parts = key.split(".")
    d = data
    for i, p in enumerate(parts[:-1]):
        nxt = d.get(p)
        if not isinstance(nxt, dict):
            nxt = {} if nxt in (None, True) else nxt
            if not isinstance(nxt, dict):  # pragma: no cover - excluded by _key_type
                raise SweepError(f"cannot set '{key}': '{'.'.join(parts[:i + 1])}' is not a table")
            d[p] = nxt
        d = nxt
    d[parts[-1]] = value


def _toml_key(k):
    return k if k and all(c.isalnum() or c in "_-" for c in k) else json.dumps(k)


def _toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v) if math.isfinite(v) else ("nan" if math.isnan(v) else ("inf" if v > 0 else "-inf"))
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_toml_key(k)} = {_toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"cannot write {type(v).__name__} {v!r} as TOML")  # pragma: no cover - scenes hold no dates


def to_toml(data: dict) -> str:
    """TOML text of a parsed scene (tables, numbers, strings, booleans, lists): ``tomllib`` reads it back equal."""
    lines = []

    def emit(prefix, table):
        scalars = {k: v for k, v in table.items() if not isinstance(v, dict)}
        subs = {k: v for k, v in table.items() if isinstance(v, dict)}
        if prefix and (scalars or not subs):
            lines.append(f"[{prefix}]")
        for k, v in scalars.items():
            lines.append(f"{_toml_key(k)} = {_toml_value(v)}")
        if scalars:
            lines.append("")
        for k, v in subs.items():
            emit(f"{prefix}.{_toml_key(k)}" if prefix else _toml_key(k), v)

    emit("", data)
    return "\n".join(lines).rstrip() + "\n"


def varied_text(base_text: str, values: dict) -> str:
    """The base scene's TOML with ``values`` ({dotted key: value}) set (comments are not kept)."""
    import copy
    import tomllib

    data = copy.deepcopy(tomllib.loads(base_text))
    for key, value in values.items():
        _set_key(data, key, value)
    return to_toml(data)


def _source_of(source, values):
    return f"{source} [{', '.join(f'{k}={v!r}' for k, v in values.items())}]"


def plan_sweep(scene, vary: dict, *, samples: int | None = None, seed: int | None = None, keep=(),
               settle: float | None = None, duration: float | None = None) -> SweepPlan:
    """Check and expand a sweep's definition (no run is started); see :func:`sweep`."""
    import tomllib

    from ..model.scene import OUTPUTS, Scene, load_scene

    base = scene if isinstance(scene, Scene) else load_scene(scene)
    text, source = base.text, base.source
    if not text:
        raise SweepError("the scene has no TOML text to vary (give the scene file, or a Scene from load_scene)")
    if not isinstance(vary, dict) or not vary:
        raise SweepError("vary must be a non-empty mapping {dotted scene key: values}")
    if samples is not None:
        if isinstance(samples, bool) or int(samples) != samples or samples < 1:
            raise SweepError(f"samples must be a positive whole number, got {samples!r}")
        samples = int(samples)
        seed = 0 if seed is None else seed
        if isinstance(seed, bool) or int(seed) != seed or seed < 0:
            raise SweepError(f"seed must be a whole number >= 0, got {seed!r}")
        seed = int(seed)
    elif seed is not None:
        raise SweepError("seed is for Monte Carlo sweeps: give samples too")
    if settle is not None and not (math.isfinite(settle) and settle >= 0):
        raise SweepError(f"settle must be a time >= 0 [s], got {settle!r}")
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        raise SweepError(f"duration must be positive, got {duration!r}")
    data = tomllib.loads(text)
    axes = []
    for key, spec in vary.items():
        key = str(key).strip()
        types = _key_type(key, data, source)
        axes.append(_axis(key, spec, types, samples))
    if len({a.key for a in axes}) != len(axes):
        raise SweepError("a key is varied twice")
    # outputs to keep: dataset variables of outputs the scene asks for
    keep = tuple(dict.fromkeys(str(k) for k in (keep or ())))
    asked = set(base.outputs["variables"])
    for name in keep:
        parent = next((o for o, kids in _PRODUCES.items() if name in kids), name)
        if parent not in OUTPUTS[base.analysis]:
            raise SweepError(f"keep: unknown output {name!r} for a {base.analysis} scene "
                             f"(available: {', '.join(sorted(OUTPUTS[base.analysis]))})")
        if parent not in asked:
            raise SweepError(f"keep: the scene does not output {parent!r}; add it to its [outputs] variables")
    # every run's values
    import numpy as np

    if samples is None:
        shape = tuple(len(a.values) for a in axes)
        points = tuple({a.key: a.values[i] for a, i in zip(axes, idx)} for idx in np.ndindex(*shape))
    else:
        shape = (samples,)
        rng = np.random.default_rng(seed)
        cols = []
        for a, types in zip(axes, (_key_type(a.key, data, source) for a in axes)):
            if a.values is not None:
                pick = rng.integers(0, len(a.values), samples)
                cols.append([a.values[i] for i in pick])
            elif int in types and float not in types:
                lo, hi = math.ceil(a.low), math.floor(a.high)
                if lo > hi:
                    raise SweepError(f"{a.key}={a.spec}: no whole number in the range")
                cols.append([int(v) for v in rng.integers(lo, hi + 1, samples)])
            else:
                cols.append([float(v) for v in rng.uniform(a.low, a.high, samples)])
        points = tuple({a.key: cols[j][i] for j, a in enumerate(axes)} for i in range(samples))
    plan = SweepPlan(text=text, source=source, analysis=base.analysis, axes=tuple(axes), samples=samples, seed=seed,
                     points=points, shape=shape, keep=keep, settle=settle, duration=duration)
    return plan


# ------------------------------------------------------------------------------------------------ one run


def _settle_time(scene, t):
    if scene.analysis != "forward" or t.size < 2:
        return 0.0
    return 0.25 * float(t[-1] - t[0])


def summarize(ds, scene, *, settle: float | None = None) -> dict:
    """Per-run summaries of a :func:`vibkit.simulate` result (NaN where the outputs do not allow one).

    Parameters
    ----------
    ds : xarray.Dataset
        The run's result.
    scene : Scene
        The scene that gave it.
    settle : float, optional
        Start-up left out of the link-pass frequency, delta mean and ripple [s] (default: a
        quarter of a forward run, nothing for an inverse run or a kinematic sweep).

    Returns
    -------
    dict
        Names and units in :data:`SUMMARIES` (``wall_time`` excepted, measured by the caller).

    Notes
    -----
    Link-pass frequency f = (s(T) - s(t_s)) / (T - t_s) / L_mean: roller 1's advance along the
    deformed guide after the start-up (its arc length s from s0 and delta, loops counted), over the
    mean link pitch (one loop of the chain is one pass of every link). Roller 1's coordinate s0 on
    the undeformed guide alone would not do over short windows: on the telescopic runs its rate
    differs from the roller's speed by up to about delta / Lt (8 %). A contact episode is one
    interval in which a tooth carries force, counted per tooth; the back-flank episodes likewise,
    on the sum of the back-flank forces.
    """
    import numpy as np

    nan = float("nan")
    out = {k: nan for k in SUMMARIES if k != "wall_time"}
    mean_pitch = float(np.mean(scene.chain.pitches()))
    axis = "time" if "time" in ds.dims else "advance"
    t = np.asarray(ds[axis].values, dtype=float)
    ts = _settle_time(scene, t) if settle is None else float(settle)
    steady = t >= (t[0] + ts) if axis == "time" else np.ones(t.size, bool)
    if steady.sum() < 2:
        steady = np.ones(t.size, bool)
    if scene.analysis == "forward" and "s0" in ds and "delta" in ds:
        from ..model.guide import Guide

        s0 = np.asarray(ds["s0"].values)[steady]
        d = np.asarray(ds["delta"].values)[steady]
        tt = t[steady]
        g = Guide(scene.guide)
        loops = math.floor(s0[-1] / g.p0) - math.floor(s0[0] / g.p0)
        advance = float(g.s0_to_s(s0[-1], d[-1]) - g.s0_to_s(s0[0], d[0])) + loops * g.perimeter(0.5 * (d[0] + d[-1]))
        out["link_pass_frequency"] = abs(advance) / (tt[-1] - tt[0]) / mean_pitch
    elif scene.analysis == "inverse":
        out["link_pass_frequency"] = abs(float(scene.section("motion")["speed"])) / mean_pitch
    if "delta" in ds:
        d = np.asarray(ds["delta"].values)[steady]
        out["delta_mean"] = float(d.mean())
        out["delta_ripple"] = float(d.max() - d.min())
    if "link_tension" in ds:
        out["peak_link_tension"] = float(np.nanmax(ds["link_tension"].values))
    if "contact_force" in ds:
        on = np.asarray(ds["contact_force"].values) > 0.0            # (time, tooth)
        starts = on[0].sum() + np.count_nonzero(on[1:] & ~on[:-1])
        out["contact_episodes"] = float(starts)
        any_on = on.any(axis=1)
        out["last_contact_time"] = float(t[np.nonzero(any_on)[0][-1]]) if any_on.any() else nan
    if "back_flank_force" in ds:
        on = np.asarray(ds["back_flank_force"].values) > 0.0
        out["back_flank_episodes"] = float(int(on[0]) + np.count_nonzero(on[1:] & ~on[:-1]))
        out["last_back_flank_time"] = float(t[np.nonzero(on)[0][-1]]) if on.any() else nan
    if "closure_residual" in ds:
        out["closure_residual_max"] = float(np.max(ds["closure_residual"].values))
    elif "closure_residual_max" in ds.attrs:
        out["closure_residual_max"] = float(ds.attrs["closure_residual_max"])
    if "solver_steps" in ds.attrs:
        out["solver_steps"] = float(ds.attrs["solver_steps"])
    return out


def _simulate(scene, duration):
    """One run (a module-level name, so that tests can count the calls in a threaded cluster)."""
    from ..analyses.simulation import simulate

    return simulate(scene, duration=duration, progress=False)


def _run_one(task: dict) -> dict:
    """Worker side: simulate one varied scene, summarise it, return plain numbers (never raises)."""
    t0 = time.perf_counter()
    rec = {"index": task["index"], "status": STATUS["ok"], "error": "", "summary": {}, "kept": {}, "pid": os.getpid()}
    try:
        from ..analyses.integrate import IntegrationError
        from ..model.scene import OUTPUTS, SceneError, parse_scene

        try:
            scene = parse_scene(task["text"], task["source"])
        except SceneError as exc:
            rec.update(status=STATUS["invalid"], error=" ".join(str(exc).split()))
            return rec
        # roller 1's advance and delta are cheap (never change which outputs need the forces)
        extra = [v for v in ("delta", "s0") if v in OUTPUTS[scene.analysis] and v not in scene.outputs["variables"]]
        if extra:
            scene = dataclasses.replace(scene, outputs={**scene.outputs,
                                                        "variables": scene.outputs["variables"] + tuple(extra)})
        try:
            ds = _simulate(scene, task["duration"])
        except (IntegrationError, ValueError, ArithmeticError) as exc:
            rec.update(status=STATUS["failed"], error=f"{type(exc).__name__}: {' '.join(str(exc).split())}")
            return rec
        rec["summary"] = summarize(ds, scene, settle=task["settle"])
        for name in task["keep"]:
            for var in _PRODUCES.get(name, (name,)):
                if var in ds:
                    da = ds[var]
                    rec["kept"][var] = {"dims": list(da.dims), "values": da.values,
                                        "coords": {d: ds[d].values for d in da.dims if d in ds.coords},
                                        "coord_attrs": {d: dict(ds[d].attrs) for d in da.dims if d in ds.coords},
                                        "attrs": dict(da.attrs)}
    except Exception as exc:  # noqa: BLE001 - a run's failure is data, not the sweep's end
        tb = traceback.extract_tb(exc.__traceback__)
        where = f" ({tb[-1].filename.rsplit(os.sep, 1)[-1]}:{tb[-1].lineno})" if tb else ""
        rec.update(status=STATUS["failed"], error=f"{type(exc).__name__}: {' '.join(str(exc).split())}{where}",
                   summary={}, kept={})
    finally:
        rec["wall_time"] = time.perf_counter() - t0
    return rec


def _failed_record(index, status, error, wall=float("nan")):
    return {"index": index, "status": status, "error": error, "summary": {}, "kept": {}, "wall_time": wall,
            "pid": 0}


# ------------------------------------------------------------------------------------------------ the store


def _zkw():
    import zarr

    return {"zarr_format": 2} if int(zarr.__version__.split(".")[0]) >= 3 else {}


def _run_group(i):
    return f"runs/r{i:06d}"


class _Store:
    """A sweep's Zarr directory: definition in the root attrs, one group per finished run."""

    def __init__(self, path, plan, *, force):
        import zarr

        self.path = Path(path)
        self.plan = plan
        definition = plan.definition()
        self.complete = False
        if self.path.exists():
            existing = self._definition()
            if existing is None:
                raise SweepError(f"{self.path}: exists and is not a vibkit sweep store; choose another output "
                                 f"(nothing was changed)")
            if existing != definition:
                if not force:
                    raise SweepError(f"{self.path}: holds a different sweep ({_differences(existing, definition)}); "
                                     f"give a new output, or force=True (--force) to discard it")
                shutil.rmtree(self.path)
        if not self.path.exists():
            self.path.parent.mkdir(parents=True, exist_ok=True)
            tmp = self.path.with_name(self.path.name + f".{os.getpid()}.partial")
            if tmp.exists():
                shutil.rmtree(tmp)
            root = zarr.open_group(str(tmp), mode="w", **_zkw())
            root.attrs.update({"vibkit_sweep": json.dumps(definition), "vibkit_sweep_state": "running"})
            os.replace(tmp, self.path)  # the store appears whole, with its definition
        self.complete = self._state() == "complete"

    def _attrs(self):
        import zarr

        try:
            return dict(zarr.open_group(str(self.path), mode="r", **_zkw()).attrs)
        except Exception:  # noqa: BLE001 - anything unreadable is "not a sweep store"
            return None

    def _definition(self):
        attrs = self._attrs()
        if not attrs or "vibkit_sweep" not in attrs:
            return None
        try:
            return json.loads(attrs["vibkit_sweep"])
        except (TypeError, ValueError):
            return None

    def _state(self):
        return (self._attrs() or {}).get("vibkit_sweep_state")

    def done_runs(self) -> dict:
        """Run index -> record, for every run whose done flag is on disk."""
        import numpy as np
        import zarr

        out = {}
        runs = self.path / "runs"
        if not runs.is_dir():
            return out
        for d in sorted(runs.iterdir()):
            if not (d.is_dir() and d.name.startswith("r") and d.name[1:].isdigit()):
                continue
            try:
                g = zarr.open_group(str(self.path), path=f"runs/{d.name}", mode="r", **_zkw())
                attrs = dict(g.attrs)
            except Exception:  # noqa: BLE001 - a half-written run is redone
                continue
            if attrs.get("done") is not True:
                continue
            rec = _failed_record(int(d.name[1:]), int(attrs["status"]), attrs.get("error", ""),
                                 _num(attrs.get("wall_time")))
            rec["summary"] = {k: _num(v) for k, v in attrs.get("summary", {}).items()}
            rec["pid"] = attrs.get("pid", 0)
            for var in attrs.get("kept", []):
                arr = g[var]
                dims = json.loads(attrs["kept_dims"])[var]
                coords = {c: np.asarray(g[f"coord_{c}"][...]) for c in dims if f"coord_{c}" in g}
                rec["kept"][var] = {"dims": dims, "values": np.asarray(arr[...]), "coords": coords,
                                    "coord_attrs": json.loads(attrs["kept_coord_attrs"]).get(var, {}),
                                    "attrs": json.loads(attrs["kept_attrs"])[var]}
            out[rec["index"]] = rec
        return out

    def write_run(self, rec):
        """Kept series, then the summaries and the done flag in one atomic attrs write."""
        import numpy as np
        import zarr

        path = self.path / _run_group(rec["index"])
        if path.exists():
            shutil.rmtree(path)
        g = zarr.open_group(str(self.path), path=_run_group(rec["index"]), mode="w", **_zkw())
        coords_written = set()
        for var, k in rec["kept"].items():
            g.create_array(var, data=np.asarray(k["values"])) if hasattr(g, "create_array") else \
                g.create_dataset(var, data=np.asarray(k["values"]))
            for c, vals in k["coords"].items():
                if c not in coords_written:
                    coords_written.add(c)
                    g.create_array(f"coord_{c}", data=np.asarray(vals)) if hasattr(g, "create_array") else \
                        g.create_dataset(f"coord_{c}", data=np.asarray(vals))
        g.attrs.update({
            "index": rec["index"], "status": rec["status"], "error": rec["error"],
            "summary": {k: _jsonval(v) for k, v in rec["summary"].items()},
            "wall_time": _jsonval(rec["wall_time"]), "pid": rec.get("pid", 0),
            "kept": list(rec["kept"]),
            "kept_dims": json.dumps({v: k["dims"] for v, k in rec["kept"].items()}),
            "kept_attrs": json.dumps({v: k["attrs"] for v, k in rec["kept"].items()}),
            "kept_coord_attrs": json.dumps({v: k["coord_attrs"] for v, k in rec["kept"].items()}),
            "done": True,
        })

    def finish(self, ds):
        """Consolidate: the whole result in the root group, then the state, then drop the run groups."""
        import zarr

        ds = ds.copy()
        ds.attrs["vibkit_sweep"] = json.dumps(self.plan.definition())
        ds.attrs["vibkit_sweep_state"] = "consolidating"
        ds.to_zarr(str(self.path), mode="a", consolidated=False, **_zkw())
        zarr.open_group(str(self.path), mode="r+", **_zkw()).attrs.update({"vibkit_sweep_state": "complete"})
        self.complete = True
        self.tidy()

    def tidy(self):
        import zarr

        if (self.path / "runs").exists():
            shutil.rmtree(self.path / "runs")
        zarr.consolidate_metadata(str(self.path))

    def open(self):
        import xarray as xr

        return xr.open_zarr(str(self.path), chunks=None)


def _num(v):
    return float("nan") if v is None else float(v)


def _differences(a, b):
    keys = [k for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)]
    return "differs in: " + ", ".join(keys) if keys else "differs"


# ------------------------------------------------------------------------------------------------ the result


def _assemble(plan, records, *, complete):
    """One Dataset: dims are the varied keys (or ``sample``); summaries, status, error, kept series."""
    import numpy as np
    import xarray as xr

    from .. import __version__

    n = len(plan.points)
    dims = plan.dims
    shape = plan.shape
    coords = {}
    if plan.samples is None:
        for a in plan.axes:
            coords[a.key] = xr.Variable((a.key,), np.asarray(a.values),
                                        attrs={"units": KEY_UNITS.get(a.key, ""), "long_name": f"scene key {a.key}"})
    else:
        coords["sample"] = xr.Variable(("sample",), np.arange(n), attrs={"units": "1", "long_name": "draw number"})
        for a in plan.axes:
            coords[a.key] = xr.Variable(("sample",), np.asarray([p[a.key] for p in plan.points]),
                                        attrs={"units": KEY_UNITS.get(a.key, ""),
                                               "long_name": f"scene key {a.key} (drawn)"})
    status = np.full(n, PENDING, dtype=np.int8)
    error = np.full(n, "", dtype=object)
    summ = {k: np.full(n, np.nan) for k in SUMMARIES}
    for i, rec in records.items():
        status[i] = rec["status"]
        error[i] = rec["error"]
        for k in SUMMARIES:
            v = rec["wall_time"] if k == "wall_time" else rec["summary"].get(k, np.nan)
            summ[k][i] = np.nan if v is None else v
    data = {}
    for k, (units, long_name) in SUMMARIES.items():
        data[k] = xr.Variable(dims, summ[k].reshape(shape), attrs={"units": units, "long_name": long_name})
    meanings = {v: k for k, v in STATUS.items()}
    if not complete:
        meanings[PENDING] = "pending"
    flags = sorted(meanings)
    data["status"] = xr.Variable(dims, status.reshape(shape), attrs={
        "long_name": "run status", "flag_values": np.array(flags, dtype=np.int8),
        "flag_meanings": " ".join(meanings[f] for f in flags)})
    data["error"] = xr.Variable(dims, error.reshape(shape).astype(str).astype(object),
                                attrs={"long_name": "why the run failed (empty when it did not)"})
    ds = xr.Dataset(data, coords=coords)
    # kept time series: outer join over the runs' own coordinates, NaN where a run has none
    names = list(dict.fromkeys(v for rec in records.values() for v in rec["kept"]))
    for var in names:
        per = [(i, rec["kept"][var]) for i, rec in sorted(records.items()) if var in rec["kept"]]
        das = [xr.DataArray(np.asarray(k["values"], dtype=float), dims=k["dims"],
                            coords={c: v for c, v in k["coords"].items()}) for _, k in per]
        joined = xr.align(*das, join="outer", fill_value=np.nan) if len(das) > 1 else das
        first = joined[0]
        full = np.full((n,) + first.shape, np.nan)
        for (i, _), da in zip(per, joined):
            full[i] = da.values
        k0 = per[0][1]
        ds[var] = xr.Variable(dims + tuple(first.dims), full.reshape(shape + first.shape), attrs=k0["attrs"])
        for c in first.dims:
            if c in first.coords and c not in ds.coords:
                ds = ds.assign_coords({c: xr.Variable((c,), first[c].values, attrs=k0["coord_attrs"].get(c, {}))})
    counts = {name: int(np.count_nonzero(status == code)) for name, code in STATUS.items()}
    ds.attrs.update({
        "vibkit_version": __version__,
        "scene": plan.text,
        "scene_source": plan.source,
        "analysis": plan.analysis,
        "sweep": "monte-carlo" if plan.samples is not None else "grid",
        "varied_keys": ", ".join(a.key for a in plan.axes),
        "vary": "; ".join(f"{a.key}={a.spec}" for a in plan.axes),
        "runs": n,
        "runs_ok": counts["ok"], "runs_failed": counts["failed"], "runs_invalid": counts["invalid"],
        "runs_pending": int(np.count_nonzero(status == PENDING)),
        "start_up_excluded": ("a quarter of each forward run" if plan.settle is None
                              else f"the first {plan.settle:g} s of each run"),
        "history": f"swept by vibkit {__version__}",
    })
    if plan.samples is not None:
        ds.attrs["seed"] = int(plan.seed)
        ds.attrs["samples"] = int(plan.samples)
    if plan.duration is not None:
        ds.attrs["duration_override"] = float(plan.duration)
    return ds


# ------------------------------------------------------------------------------------------------ progress


class _Report:
    """A bar on a terminal; a line every ``every`` seconds otherwise; nothing when disabled."""

    def __init__(self, total, done0, *, enabled, stream=None, every=5.0):
        from ..runtime.progress import Progress

        self.stream = stream or sys.stderr
        self.total, self.done0, self.done, self.failed = total, done0, done0, 0
        self.enabled = bool(enabled)
        self.tty = self.enabled and hasattr(self.stream, "isatty") and self.stream.isatty()
        self.bar = Progress(total, "sweep", enabled=self.tty, stream=self.stream) if self.tty else None
        self.every = every
        self.t0 = self._last = time.perf_counter()

    def line(self, text):
        if self.enabled:
            if self.tty:
                self.stream.write("\n")
            self.stream.write(text + "\n")
            self.stream.flush()

    def update(self, rec=None):
        if rec is not None:
            self.done += 1
            self.failed += rec["status"] != STATUS["ok"]
        if not self.enabled:
            return
        if self.bar is not None:
            self.bar.update(self.done)
            return
        now = time.perf_counter()
        if now - self._last >= self.every or (rec is not None and self.done == self.total):
            self._last = now
            new = self.done - self.done0
            rate = new / max(now - self.t0, 1e-9)
            left = (self.total - self.done) / rate if rate > 0 else float("nan")
            eta = f", about {left:.0f} s left" if math.isfinite(left) and self.done < self.total else ""
            self.stream.write(f"sweep: {self.done}/{self.total} runs done ({self.failed} failed), "
                              f"{rate:.2f} runs/s{eta}\n")
            self.stream.flush()

    def close(self):
        if self.bar is not None:
            self.bar.close()


# ------------------------------------------------------------------------------------------------ sweep()


def sweep(scene, vary: dict, *, output=None, samples: int | None = None, seed: int | None = None, keep=(),
          settle: float | None = None, duration: float | None = None, scheduler: str | None = None,
          n_workers: int | None = None, client=None, force: bool = False, progress: bool = True,
          max_runs: int | None = None):
    """Run a scene over a grid (or Monte Carlo draws) of its keys on Dask.

    Parameters
    ----------
    scene : Scene or str or Path
        The base scene (a TOML file or a :class:`~vibkit.model.scene.Scene` from ``load_scene``).
    vary : dict
        Dotted scene key -> values: ``"A:B:N"`` (N values from A to B), ``"a,b,c"`` or a sequence
        of values; with ``samples``, ``"A:B"`` (drawn uniformly) or a list (drawn among).
    output : str or Path, optional
        Zarr directory the runs are streamed to (resumable); without it the results stay in memory.
    samples : int, optional
        Monte Carlo: number of scenes drawn; the dimension is then ``sample``.
    seed : int, optional
        Seed of the draws (default 0): the same scene, vary and seed give the same values.
    keep : sequence of str
        Outputs whose full series are kept (e.g. ``["delta"]``); the scene must output them.
    settle : float, optional
        Start-up left out of the summaries [s] (default: a quarter of a forward run).
    duration : float, optional
        Overrides every run's duration [s] (kinematics: range of advance [m]).
    scheduler : str, optional
        Address of a running Dask scheduler; default: Dask's configuration, else a local cluster.
    n_workers : int, optional
        Worker processes of the local cluster (default: one per core).
    client : distributed.Client, optional
        An existing client to submit to (then ``scheduler`` and ``n_workers`` are not used).
    force : bool
        Discard a store at ``output`` that holds a different sweep.
    progress : bool
        A bar on a terminal, a line every 5 s otherwise (on stderr); nothing when False.
    max_runs : int, optional
        Compute at most this many runs in this call and stop (the store stays resumable).

    Returns
    -------
    xarray.Dataset
        Dimensions: the varied keys (grid) or ``sample``. Variables: the :data:`SUMMARIES`,
        ``status`` (0 ok, 1 failed, 2 invalid; -1 pending when stopped early), ``error``, and the
        kept series. Attrs: the scene, the sweep's definition, the counts of runs, and
        ``runs_computed`` (by this call) and ``runs_reused`` (read back from the store).

    Raises
    ------
    SweepError
        A key the scene loader does not know, a malformed value list, an output to keep that the
        scene does not give, or a store that holds another sweep (without ``force``).

    Notes
    -----
    The local cluster's workers are separate processes that import the calling script again: a
    script that calls ``sweep`` needs the usual ``if __name__ == "__main__":`` guard. A remote
    cluster's workers need vibkit installed; they only receive scene texts and return numbers (the
    driver writes the store). Each worker loads the compiled kernels on its first run (a few
    seconds; that run's ``wall_time`` includes it).

    Examples
    --------
    >>> ds = vibkit.sweep("sim/thesis-forward.toml",                        # doctest: +SKIP
    ...                   {"chain.link_pitch": "0.1333:0.1373:9", "effects.contact.stiffness": "1e5,1e6,1e7"},
    ...                   duration=10.0, keep=["delta"], output="sweep.zarr")
    >>> ds.delta_ripple.plot(x="chain.link_pitch", hue="effects.contact.stiffness")  # doctest: +SKIP
    """
    plan = plan_sweep(scene, vary, samples=samples, seed=seed, keep=keep, settle=settle, duration=duration)
    if max_runs is not None and (isinstance(max_runs, bool) or int(max_runs) != max_runs or max_runs < 0):
        raise SweepError(f"max_runs must be a whole number >= 0, got {max_runs!r}")
    if n_workers is not None and (isinstance(n_workers, bool) or int(n_workers) != n_workers or n_workers < 1):
        raise SweepError(f"n_workers must be a whole number >= 1, got {n_workers!r}")
    store = _Store(output, plan, force=force) if output is not None else None
    if store is not None and store.complete:
        if (store.path / "runs").exists() or not (store.path / ".zmetadata").exists():
            store.tidy()  # a consolidation interrupted after its data were written
        ds = store.open()
        ds.attrs.update(runs_computed=0, runs_reused=int(ds.attrs.get("runs", len(plan.points))))
        return ds
    records = store.done_runs() if store is not None else {}
    reused = len(records)
    todo = [i for i in range(len(plan.points)) if i not in records]
    # validate every varied scene now: a value the loader refuses is that run's result
    from ..model.scene import SceneError, parse_scene

    tasks = []
    for i in todo:
        p = plan.points[i]
        text, src = varied_text(plan.text, p), _source_of(plan.source, p)
        try:
            parse_scene(text, src)
        except SceneError as exc:
            rec = _failed_record(i, STATUS["invalid"], " ".join(str(exc).split()), 0.0)
            records[i] = rec
            if store is not None:
                store.write_run(rec)
            continue
        tasks.append({"index": i, "text": text, "source": src, "duration": plan.duration, "settle": plan.settle,
                      "keep": plan.keep})
    if max_runs is not None:
        tasks = tasks[:int(max_runs)]
    report = _Report(len(plan.points), len(records), enabled=progress)
    report.failed = sum(r["status"] != STATUS["ok"] for r in records.values())
    if reused:
        report.line(f"sweep: resuming {output}: {reused} of {len(plan.points)} runs already done")
    computed = 0
    if tasks:
        import contextlib

        from ..runtime.cluster import dask_client

        ctx = contextlib.nullcontext(client) if client is not None else dask_client(scheduler, n_workers=n_workers)
        try:
            with ctx as cl:
                computed = _submit(cl, tasks, records, store, report)
        except KeyboardInterrupt:
            report.close()
            if store is not None:
                report.line(f"sweep: interrupted; {len(records)} of {len(plan.points)} runs are stored in "
                            f"{store.path}: run the same sweep again to resume")
            raise
    report.close()
    complete = len(records) == len(plan.points)
    ds = _assemble(plan, records, complete=complete)
    if store is not None and complete:
        store.finish(ds)
        ds = store.open()
    ds.attrs.update(runs_computed=computed, runs_reused=reused)
    return ds


def _submit(client, tasks, records, store, report):
    """Submit the runs, write each as it finishes; returns how many were computed."""
    from distributed import as_completed

    token = f"vibkit-sweep-{os.getpid()}-{time.time_ns()}"
    futures = {}
    for t in tasks:
        fut = client.submit(_run_one, t, key=f"{token}-{t['index']}", pure=False)
        futures[fut] = t["index"]
    computed = 0
    try:
        for fut in as_completed(list(futures)):
            i = futures[fut]
            try:
                rec = fut.result()
            except Exception as exc:  # noqa: BLE001 - e.g. KilledWorker: the run is recorded as failed
                rec = _failed_record(i, STATUS["failed"], f"{type(exc).__name__}: {' '.join(str(exc).split())}")
            fut.release()
            records[i] = rec
            if store is not None:
                store.write_run(rec)
            computed += 1
            report.update(rec)
    finally:
        for fut in futures:
            if not fut.done():
                fut.cancel()
    return computed
