"""Sweep plans: parsing ``--vary``, the varied keys (axes) and their types, every run's values, and the
TOML text of each varied scene.

:func:`plan_sweep` checks and expands a sweep's definition before any run starts: a key the scene
loader does not know, or an effect the scene does not switch on, is a :class:`SweepError` naming the
key. :func:`varied_text` writes a varied scene back as TOML (:func:`to_toml`). Imports only the
standard library at load time (numpy and the scene loader inside the functions).
"""

from __future__ import annotations

import dataclasses
import json
import math
import re

from .errors import SweepError
from .limits import check_key_used, check_settle, check_size

__all__ = ["parse_vary", "plan_sweep", "SweepPlan", "SweepError", "to_toml", "varied_text"]

SCHEMA = 1

# scene outputs that give more than one dataset variable
_PRODUCES = {
    "flank_force": ("drive_flank_force", "back_flank_force"),
    "energy": ("kinetic_energy", "potential_energy", "contact_energy", "spring_energy"),
}


# numbers as a person writes them: no digit separators (float("0_5") is 5.0), no hex, no "nan"/"inf"
_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_WHOLE = re.compile(r"\+?[0-9]+")


def _number(text: str) -> float:
    """``float(text)`` for plain decimal numbers only; ValueError otherwise (``0_5``, ``0x10``, ``nan``)."""
    s = text.strip()
    if not _NUMBER.fullmatch(s):
        raise ValueError(text)
    return float(s)


class _Lazy:
    """A read-only sequence of ``n`` items computed on demand by ``_item(i)`` (0 <= i < n)."""

    __slots__ = ()

    def __len__(self):
        return self.n

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(self.n))]
        if i < 0:
            i += self.n
        if not 0 <= i < self.n:
            raise IndexError(i)
        return self._item(i)

    def __iter__(self):
        return (self._item(i) for i in range(self.n))


class _Linspace(_Lazy):
    """The N values of ``A:B:N`` without storing them: value i is ``A + i (B - A) / (N - 1)`` (B exactly last),
    the same floats as :func:`numpy.linspace`."""

    __slots__ = ("a", "b", "n", "whole")

    def __init__(self, a: float, b: float, n: int, whole: bool = False):
        self.a, self.b, self.n, self.whole = a, b, n, whole

    def _item(self, i):
        if self.n > 1 and i == self.n - 1:
            v = self.b
        else:
            v = i * ((self.b - self.a) / (self.n - 1)) + self.a if self.n > 1 else self.a
        return int(round(v)) if self.whole else float(v)

    def __array__(self, dtype=None, copy=None):
        import numpy as np

        vals = np.linspace(self.a, self.b, self.n) if self.n > 1 else np.array([self.a])
        vals = np.round(vals).astype(np.int64) if self.whole else vals
        return vals if dtype is None else vals.astype(dtype)

    def __eq__(self, other):
        if isinstance(other, _Linspace):
            return (self.a, self.b, self.n, self.whole) == (other.a, other.b, other.n, other.whole)
        return NotImplemented

    def __hash__(self):
        return hash((self.a, self.b, self.n, self.whole))

    def __repr__(self):
        return f"linspace({self.a!r}, {self.b!r}, {self.n})"


class _Points(_Lazy):
    """Run index -> {key: value}, computed on demand (grid runs in C order over the axes; Monte Carlo draws
    from their columns): a plan of a billion runs holds no billion dicts."""

    def __init__(self, axes, shape, columns=None):
        self.axes, self.shape, self.columns = tuple(axes), tuple(shape), columns
        n = 1
        for s in self.shape:
            n *= s
        self.n = n

    def _item(self, i):
        if self.columns is not None:
            return {a.key: col[i] for a, col in zip(self.axes, self.columns)}
        idx = []
        for s in reversed(self.shape):
            i, r = divmod(i, s)
            idx.append(r)
        return {a.key: a.values[j] for a, j in zip(self.axes, reversed(idx))}

    def __eq__(self, other):
        try:
            return len(self) == len(other) and all(p == q for p, q in zip(self, other))
        except TypeError:
            return NotImplemented

    __hash__ = None


# ------------------------------------------------------------------------------------------------ the plan


@dataclasses.dataclass(frozen=True)
class Axis:
    """One varied key: its values (a grid axis, or the choices of a Monte Carlo draw) or a range."""

    key: str
    spec: str  # as the user wrote it (for messages and the stored definition)
    values: tuple | None = None  # explicit values (A:B:N expanded, or a,b,c)
    low: float | None = None  # Monte Carlo range A:B
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
            a, b = _number(parts[0]), _number(parts[1])
        except ValueError:
            raise ValueError(f"{key}={spec}: A and B of A:B:N must be numbers") from None
        if not (math.isfinite(a) and math.isfinite(b)):
            raise ValueError(f"{key}={spec}: A and B must be finite")
        n = None
        if len(parts) == 3:
            try:
                if not _WHOLE.fullmatch(parts[2]):
                    raise ValueError(parts[2])
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
            known = ", ".join(
                f"effects.{e}.{k}" for e, opts in EFFECTS.items() for k, t in opts.items() if t is not list
            )
            raise SweepError(f"{source}: cannot vary unknown scene key '{key}' (effect keys: {known})")
        typ = EFFECTS[parts[1]][parts[2]]
        eff = base_data.get("effects", {}).get(parts[1])
        if eff is None or eff is False or (isinstance(eff, dict) and eff.get("enabled", True) is False):
            raise SweepError(
                f"{source}: cannot vary '{key}': the scene does not switch on effects.{parts[1]} "
                f"(add it to the scene's [effects] first)"
            )
    else:
        if len(parts) != 2 or parts[0] not in SECTIONS or parts[1] not in SECTIONS[parts[0]]:
            if len(parts) == 2 and parts[0] in SECTIONS:
                known = ", ".join(f"{parts[0]}.{k}" for k in SECTIONS[parts[0]])
                raise SweepError(
                    f"{source}: cannot vary unknown scene key '{key}' (known keys of [{parts[0]}]: {known})"
                )
            raise SweepError(
                f"{source}: cannot vary unknown scene key '{key}' (keys are dotted like chain.link_pitch, "
                f"effects.contact.stiffness; sections: {', '.join(SECTIONS)}, effects)"
            )
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
            num = _number(s)
        except ValueError:
            if str in types:
                return s
            raise SweepError(f"{key}: expected a number such as 0.5 or 1e6 (no '_' separators), got {v!r}") from None
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
                    raise SweepError(
                        f"{key}={spec}: a grid needs A:B:N (N values); A:B alone is a Monte Carlo range "
                        f"(give samples / --samples)"
                    )
                if not (int in types or float in types) or bool in types:
                    raise SweepError(f"{key}={spec}: A:B:N needs a numeric key")
                whole = int in types and float not in types
                if whole:
                    step = (b - a) / (n - 1) if n > 1 else 0.0
                    if any(abs(v - round(v)) > 1e-9 for v in (a, b, step)):
                        raise SweepError(
                            f"{key}={spec}: '{key}' takes whole numbers and A:B:N gives fractions (use a list a,b,c)"
                        )
                values = _Linspace(a, b, n, whole)
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
    points : sequence of dict
        Run index -> {key: value}, grid runs in C order over ``axes`` (computed on demand).
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
        return {
            "schema": f"vibkit.sweep/{SCHEMA}",
            "scene": self.text,
            "axes": [{"key": a.key, "spec": a.spec} for a in self.axes],
            "samples": self.samples,
            "seed": self.seed,
            "points": [[_jsonval(p[a.key]) for a in self.axes] for p in self.points],
            "keep": list(self.keep),
            "settle": self.settle,
            "duration": self.duration,
        }


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
                raise SweepError(f"cannot set '{key}': '{'.'.join(parts[: i + 1])}' is not a table")
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


def plan_sweep(
    scene,
    vary: dict,
    *,
    samples: int | None = None,
    seed: int | None = None,
    keep=(),
    settle: float | None = None,
    duration: float | None = None,
    max_result_bytes=None,
) -> SweepPlan:
    """Check and expand a sweep's definition (no run is started); see :func:`sweep`.

    Every check is made on numbers before anything the size of the sweep is allocated: the keys
    (known, switched on, read by the scene's analysis: :func:`vibkit.sweep.limits.check_key_used`),
    the values, ``settle`` and the size of the result (:func:`vibkit.sweep.limits.check_size`,
    raising :class:`vibkit.runtime.budget.BudgetError`).  Grid axes and points are computed on
    demand, so planning costs the same for ten runs or a billion.
    """
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
    check_settle(base, settle, duration, source)
    data = tomllib.loads(text)
    axes, key_types = [], []
    for key, spec in vary.items():
        key = str(key).strip()
        types = _key_type(key, data, source)
        check_key_used(key, base.analysis, source, duration=duration)
        axes.append(_axis(key, spec, types, samples))
        key_types.append(types)
    if len({a.key for a in axes}) != len(axes):
        raise SweepError("a key is varied twice")
    # outputs to keep: dataset variables of outputs the scene asks for
    keep = tuple(dict.fromkeys(str(k) for k in (keep or ())))
    asked = set(base.outputs["variables"])
    for name in keep:
        parent = next((o for o, kids in _PRODUCES.items() if name in kids), name)
        if parent not in OUTPUTS[base.analysis]:
            raise SweepError(
                f"keep: unknown output {name!r} for {'an' if base.analysis == 'inverse' else 'a'} {base.analysis} scene "
                f"(available: {', '.join(sorted(OUTPUTS[base.analysis]))})"
            )
        if parent not in asked:
            raise SweepError(f"keep: the scene does not output {parent!r}; add it to its [outputs] variables")
    shape = tuple(len(a.values) for a in axes) if samples is None else (samples,)
    runs = 1
    for s in shape:
        runs *= s
    check_size(base, runs, keep=keep, duration=duration, limit_bytes=max_result_bytes, source=source)
    # every run's values: a grid's on demand, Monte Carlo draws now (within the budget just checked)
    if samples is None:
        points = _Points(axes, shape)
    else:
        import numpy as np

        rng = np.random.default_rng(seed)
        cols = []
        for a, types in zip(axes, key_types):
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
        points = _Points(axes, shape, columns=cols)
    plan = SweepPlan(
        text=text,
        source=source,
        analysis=base.analysis,
        axes=tuple(axes),
        samples=samples,
        seed=seed,
        points=points,
        shape=shape,
        keep=keep,
        settle=settle,
        duration=duration,
    )
    return plan
