"""The scene keys of a worn chain, checked in one place: links of another pitch, rollers of another
radius or mass, rollers worn flat, and where an elongated chain seats on its sprocket.

``[chain] worn_links = [[link, pitch_m], ...]`` (and the one-link shorthand ``worn_link`` with
``worn_link_pitch``), ``[chain] roller_radius_by_roller``, ``roller_mass_by_roller`` and ``roller_flat_by_roller`` are lists of
[number, value] pairs; ``[chain] elongation_percent`` and ``[sprocket] pitch`` are read by
:mod:`vibkit.model.scene`. Every error is a :class:`~vibkit.model.schema.SceneError` naming the file and the key.
"""

from __future__ import annotations

import math

from .schema import SceneError

__all__ = ["pairs", "by_roller", "worn_links", "check_seat", "check_flat_speed"]


def _positive(src, where, value):
    if not value > 0:
        raise SceneError(f"{src}: '{where}' must be positive, got {value!r}")


def pairs(src, c, key, n, what, unit, kind):
    """A list of [number, value] pairs of ``chain.key``: numbers 1..n, each once, positive values."""
    raw = c.get(key, ())
    out = []
    seen = set()
    for entry in raw:
        if not (isinstance(entry, (list, tuple)) and len(entry) == 2):
            raise SceneError(f"{src}: 'chain.{key}' entries must be pairs [{kind}, {what} {unit}], got {entry!r}")
        number, value = entry
        if isinstance(number, bool) or not isinstance(number, int) or not 1 <= number <= n:
            raise SceneError(f"{src}: 'chain.{key}': {kind} number must be an integer 1..{n}, got {number!r}")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise SceneError(
                f"{src}: 'chain.{key}': {what} of {kind} {number} must be a number [{unit}], got "
                f"{type(value).__name__} {value!r}"
            )
        if not math.isfinite(value) or value <= 0:
            raise SceneError(
                f"{src}: 'chain.{key}': {what} of {kind} {number} must be positive [{unit}], got {value!r}"
            )
        if number in seen:
            raise SceneError(f"{src}: 'chain.{key}': {kind} {number} is given twice")
        seen.add(number)
        out.append((number, float(value)))
    return tuple(out)


def by_roller(src, c, key, n, what, unit):
    return pairs(src, c, key, n, what, unit, "roller")


def worn_links(src, c, n, nominal):
    """The links of another pitch: ``chain.worn_links`` and the one-link shorthand ``worn_link``/``worn_link_pitch``."""
    if ("worn_link" in c) != ("worn_link_pitch" in c):
        raise SceneError(f"{src}: 'chain.worn_link' and 'chain.worn_link_pitch' go together (link number, pitch [m])")
    worn = list(pairs(src, c, "worn_links", n, "pitch", "m", "link"))
    if "worn_link" in c:
        if not 1 <= c["worn_link"] <= n:
            raise SceneError(f"{src}: 'chain.worn_link' must be a link number 1..{n}, got {c['worn_link']!r}")
        _positive(src, "chain.worn_link_pitch", c["worn_link_pitch"])
        if any(link == c["worn_link"] for link, _ in worn):
            raise SceneError(f"{src}: link {c['worn_link']} is in both 'chain.worn_link' and 'chain.worn_links'")
        worn.append((c["worn_link"], float(c["worn_link_pitch"])))
    for link, p in worn:
        if not 0.5 * nominal < p < 1.5 * nominal:
            raise SceneError(
                f"{src}: 'chain.worn_links': pitch {p:g} m of link {link} is not plausible for a chain of "
                f"link_pitch {nominal:g} m (expected within 50 %)"
            )
    return tuple(worn)


def check_seat(src, guide, sprocket, chain) -> None:
    """An elongated chain rides up the teeth; one whose rollers would seat above the tooth tips has
    jumped the teeth (it must be replaced, not simulated)."""
    cut = sprocket.cut_pitch(chain.link_pitch)
    root = sprocket.pitch_radius(cut) - chain.roller_radius
    tip = root + sprocket.tooth_height
    if not guide.head_radius < tip:
        raise SceneError(
            f"{src}: the rollers would seat at radius {guide.head_radius:.4g} m on the sprocket, above its tooth tips "
            f"({tip:.4g} m; teeth cut for 'sprocket.pitch' = {cut:g} m): the chain ({chain.link_pitch:.6g} m links, "
            "'chain.elongation_percent' or 'chain.link_pitch') has jumped the teeth"
        )


def check_flat_speed(src, chain, guide, analysis, effects, sections) -> None:
    """A flat roller's model holds while the step's weight keeps it on the flat's edges
    (:func:`vibkit.model.flat_roller.flat_speed_limit`); a scene that runs faster is refused."""
    if not chain.roller_flats:
        return
    from .flat_roller import flat_speed_limit

    if analysis == "forward":
        speed = effects["motor"].speed if "motor" in effects else sections["run"].get("initial_speed", 0.0)
    elif analysis == "inverse":
        speed = sections["motion"].get("speed", 0.0)
    else:
        return
    speed = abs(speed)
    radii = chain.radii()
    for roller, _ in chain.roller_flats:
        r = float(radii[roller - 1])
        limit = flat_speed_limit(r, guide.incline_angle, guide.transition_radius)
        if speed > limit:
            raise SceneError(
                f"{src}: 'chain.roller_flat_by_roller': at {speed:g} m/s the flat roller {roller} ({r * 1e3:.3g} mm) "
                f"would fly over its flat: the step's weight keeps it on the flat's edges up to {limit:.3g} m/s on "
                f"this {math.degrees(guide.incline_angle):.3g} deg incline (v^2 (1/r + 1/r_t) = g cos(alpha)), and "
                "a roller in flight is not modelled"
            )
