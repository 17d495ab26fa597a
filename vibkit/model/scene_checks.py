"""Checks of a parsed scene that relate its values to each other or to the plausible ranges: passengers on
the chain's steps, the ranges of the schema, a tooth that fits the chain it drives, start positions within
reach of the guide. Called by :func:`vibkit.model.scene.parse_scene`; each error names the file and the key."""

from __future__ import annotations

import dataclasses
import math
import tomllib

from .schema import RANGES, SceneError


def _validate_passenger_numbers(src, o, chain) -> None:
    """Passengers' masses finite and positive, steps whole numbers on the chain (1 .. n_rollers // links_per_step)."""
    if not o:
        return
    n_steps = chain.n_rollers // chain.links_per_step
    for i, m in enumerate(o.mass):
        if isinstance(m, bool) or not isinstance(m, (int, float)) or not math.isfinite(m) or m <= 0:
            raise SceneError(f"{src}: 'effects.passengers.mass[{i}]' must be a finite positive mass [kg], got {m!r}")
    for i, st in enumerate(o.step):
        if isinstance(st, bool) or not isinstance(st, int) or not 1 <= st <= n_steps:
            raise SceneError(
                f"{src}: 'effects.passengers.step[{i}]' must be a step number 1..{n_steps} "
                f"(the chain has {chain.n_rollers} rollers, {chain.links_per_step} per step), got {st!r}"
            )


def _check_ranges(src, sec, effects) -> None:
    values = {}
    for name, opts in effects.items():
        for f in dataclasses.fields(opts):
            values[f"effects.{name}.{f.name}"] = getattr(opts, f.name)
    for name in ("solver", "motion", "run", "chain"):
        for key, v in sec[name].items():
            values[f"{name}.{key}"] = v
    for key, (lo, hi, unit) in RANGES.items():
        v = values.get(key)
        # a default that means "none" (torque_limit = inf) is not a number a typo can make absurd
        if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and not lo <= v <= hi:
            raise SceneError(f"{src}: '{key}' = {v!r} is outside the plausible range [{lo:g}, {hi:g}] {unit}".rstrip())


def check_chain_first(src, sec) -> None:
    """The chain's keys as given, before the guide and the chain are built from them (a pitch in mm, rollers that
    overlap, would otherwise fail later under another key's name): their plausible ranges, and rollers less than
    half a pitch in radius."""
    _check_ranges(src, {name: sec[name] if name == "chain" else {} for name in sec}, {})
    chain = sec["chain"]
    pitch = chain.get("link_pitch")
    r = chain.get("roller_radius")  # (a roller's own radius, roller_radius_by_roller, is checked with the chain)
    if isinstance(pitch, (int, float)) and isinstance(r, (int, float)) and 2.0 * r >= pitch:
        raise SceneError(
            f"{src}: 'chain.roller_radius' = {r:g} m: neighbouring rollers overlap on links of {pitch:g} m (expected "
            f"less than half the pitch, {pitch / 2:g} m)"
        )


def _check_sprocket_geometry(src, given, sprocket, chain) -> None:
    """The tooth must fit the chain it drives: shorter than a link, narrower than a link, tip <= base."""
    pitch = sprocket.cut_pitch(chain.link_pitch)
    r = sprocket.pitch_radius(pitch)
    if sprocket.tooth_height >= min(pitch, r):
        raise SceneError(
            f"{src}: 'sprocket.tooth_height' = {sprocket.tooth_height:g} m is not plausible for a "
            f"sprocket of pitch radius {r:.4g} m driving links of {pitch:g} m (expected less than "
            f"{min(pitch, r):.4g} m)"
        )
    if sprocket.base_width >= pitch:
        raise SceneError(
            f"{src}: 'sprocket.base_width' = {sprocket.base_width:g} m must be less than the link "
            f"pitch {pitch:g} m (a tooth sits between two rollers)"
        )
    if sprocket.tip_width > sprocket.base_width:
        raise SceneError(
            f"{src}: 'sprocket.tip_width' = {sprocket.tip_width:g} m must not exceed "
            f"'sprocket.base_width' = {sprocket.base_width:g} m (a trapezoidal tooth)"
        )


#: starting positions beyond this many guide perimeters are refused (kinematics) [-]
MAX_START_LOOPS = 100


def _reduce_start(src, sec, analysis, guide) -> None:
    """Bring a start position to within one loop of the guide (the same configuration, full accuracy).

    ``run.start`` and ``motion.start`` are reduced modulo the guide's perimeter; a kinematic sweep's
    ``start``/``stop`` (its output coordinate) must lie within :data:`MAX_START_LOOPS` perimeters.
    """
    perimeter = guide.perimeter
    for name in ("run", "motion"):
        if "start" in sec[name]:
            sec[name]["start"] = math.fmod(sec[name]["start"], perimeter)
    if analysis == "kinematics":
        bound = MAX_START_LOOPS * perimeter
        for key in ("start", "stop"):
            v = sec["kinematics"].get(key)
            if v is not None and abs(v) > bound:
                raise SceneError(
                    f"{src}: 'kinematics.{key}' = {v:g} m is more than {MAX_START_LOOPS} loops of "
                    f"the guide ({bound:.6g} m): positions that far lose accuracy; give the advance "
                    f"within one loop (perimeter {perimeter:.6g} m)"
                )


def _a(analysis):
    """``a kinematics`` / ``an inverse`` / ``a forward``."""
    return f"an {analysis}" if analysis[0] in "aeiou" else f"a {analysis}"


def check_sections_belong(src, sec, analysis, name) -> None:
    """Another analysis' run section (``[run]`` in an inverse scene), or solver keys in a scene that integrates
    nothing (all but ``solver.max_result_bytes``), is refused: read by nothing, it said what the run did not do.
    ``name`` is the analysis' own run section."""
    for other in ("kinematics", "motion", "run"):
        if other != name and sec[other]:
            raise SceneError(
                f"{src}: [{other}] has no meaning in {_a(analysis)} scene, whose run is [{name}] (got "
                f"{', '.join(f'{other}.{k}' for k in sec[other])}): remove it, or set scene.analysis"
            )
    if analysis != "forward":
        unused = [k for k in sec["solver"] if k != "max_result_bytes"]
        if unused:
            raise SceneError(
                f"{src}: {', '.join(f'solver.{k}' for k in unused)} {'has' if len(unused) == 1 else 'have'} no "
                f"meaning in {_a(analysis)} scene, which integrates nothing (only solver.max_result_bytes applies)"
            )


def _toml_depth(text: str) -> int:
    """The deepest nesting of arrays and inline tables in TOML ``text``, outside strings and comments (a
    linear scan: what the parser, which recurses per level, is spared)."""
    depth = deepest = 0
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if c == "#":
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif c in "\"'":
            q3 = c * 3
            if text.startswith(q3, i):
                j = text.find(q3, i + 3)
                i = n if j < 0 else j + 3
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if (c == '"' and text[j] == "\\") else 1
            i = j
        elif c in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif c in "]}":
            depth = max(depth - 1, 0)
        i += 1
    return deepest


#: arrays and inline tables nested deeper than this are refused before parsing (a scene nests 3 at most)
MAX_TOML_DEPTH = 32


def toml_loads(text: str, src, what: str = "scene") -> dict:
    """``tomllib.loads`` bounded: nesting deeper than :data:`MAX_TOML_DEPTH` is refused before the parser
    recurses into it; every parse error is one :class:`SceneError` line naming ``src``."""
    if _toml_depth(text) > MAX_TOML_DEPTH:
        raise SceneError(
            f"{src}: arrays or tables nested more than {MAX_TOML_DEPTH} deep; a {what} nests 3 at most "
            "(check the brackets)"
        )
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{src}: not valid TOML: {exc}") from None
    except RecursionError:
        raise SceneError(f"{src}: nested too deep to parse; a {what} nests 3 at most (check the brackets)") from None
