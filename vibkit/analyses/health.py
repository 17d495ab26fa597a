"""Warnings about the physics of a run that a user should not miss: links in compression, a stalled motor,
a speed that droops.

:func:`physics_warnings` reads a result (the outputs the scene asked for) and returns one line per
finding; :func:`vibkit.simulate` stores them in ``attrs["warnings"]`` (newline-separated) and ``vibkit
simulate`` prints them on stderr. A check whose output the scene did not ask for is skipped (the
compression check needs ``link_tension``; the motor checks ``sprocket_speed`` or ``chain_speed``, and
``motor_torque`` for the torque limit): :func:`unchecked_physics` says which, and ``vibkit simulate`` prints
those as notes (``attrs["unchecked"]``).
"""

from __future__ import annotations

import math

import numpy as np

from ..model.schema import effect_options

__all__ = [
    "COAST_TORQUE_N_M",
    "DROOP_FRACTION",
    "DROOP_WINDOW_S",
    "physics_notes",
    "physics_warnings",
    "unchecked_physics",
]

#: a speed more than this fraction below the set speed, averaged over DROOP_WINDOW_S, is a droop
DROOP_FRACTION = 0.02
#: the averaging window of the droop check [s]
DROOP_WINDOW_S = 1.0
#: a motor torque below this [N m] over the second half of a run is none: the sprocket turns untouched
COAST_TORQUE_N_M = 1e-6
#: a link in compression by less than this [N] is rounding, not physics
COMPRESSION_TOLERANCE_N = 1.0


def physics_warnings(ds, scene, model) -> list[str]:
    """One line per finding of the result ``ds`` of ``scene`` (links in compression, motor stall or droop)."""
    effects = effect_options(scene.effects)  # typed (tests and benchmarks pass plain tables)
    out = []
    if "link_tension" in ds:
        out += _compression(ds, effects["tensioner"].preload if "tensioner" in effects else 0.0)
    if scene.analysis == "forward" and "motor" in effects:
        out += _motor(ds, effects["motor"], model)
    out += _unseen_flats(scene)
    return out


def physics_notes(ds, scene) -> list[str]:
    """One line per fact of the result ``ds`` worth knowing that is no fault: a forward run whose drive does no
    work over its second half (motor torque under :data:`COAST_TORQUE_N_M`): the teeth carry no load, and the
    chain coasts, as a chain without friction or passengers does at steady speed (gravity on a closed loop does
    no net work), so its signals hold the chain's geometry alone, no tooth mesh."""
    if scene.analysis != "forward" or "motor" not in effect_options(scene.effects) or "motor_torque" not in ds:
        return []
    torque = np.abs(np.asarray(ds["motor_torque"].values, dtype=float))
    half = torque.size // 2
    if torque.size < 4 or torque[half:].max() >= COAST_TORQUE_N_M:
        return []
    busy = np.flatnonzero(torque >= COAST_TORQUE_N_M)
    since = float(ds.time.values[busy[-1] + 1]) if busy.size else float(ds.time.values[0])
    return [
        f"the chain coasts from {since:.3g} s on: the motor does no work (torque 0) and the teeth carry no load, "
        "as a chain without friction or passengers does at steady speed; its signals show the chain's geometry, "
        "not the tooth mesh (add [effects] rolling_resistance or passengers for a loaded drive)"
    ]


def unchecked_physics(ds, scene) -> list[str]:
    """One line per check of :func:`physics_warnings` that the result ``ds`` of ``scene`` could not make: the
    output it needs was not asked for (asking for it costs the outputs' time)."""
    if scene.analysis not in ("inverse", "forward"):
        return []
    out = []
    if "link_tension" not in ds:
        out.append("links in compression: not checked (add link_tension to [outputs] variables)")
    if (
        scene.analysis == "forward"
        and "motor" in effect_options(scene.effects)
        and not {"sprocket_speed", "chain_speed"} & set(ds.data_vars)
    ):
        out.append("a stalled motor or a drooping speed: not checked (add sprocket_speed to [outputs] variables)")
    return out


def _unseen_flats(scene) -> list[str]:
    """A roller worn flat moves only itself (:mod:`vibkit.model.flat_roller`): said when no output shows it."""
    flats = [roller for roller, _ in scene.chain.roller_flats]
    if not flats:
        return []
    if scene.analysis == "kinematics":
        return [f"roller(s) {', '.join(map(str, flats))} worn flat: a kinematics scene places the chain alone, no flat"]
    shown = (
        set(scene.outputs.get("rollers", ()))
        if {"roller_position", "roller_velocity", "roller_acceleration"} & set(scene.outputs.get("variables", ()))
        else set()
    )
    unseen = [r for r in flats if r not in shown]
    if not unseen:
        return []
    return [
        f"roller(s) {', '.join(map(str, unseen))} worn flat, but no output shows them: a flat moves its own roller "
        "only (add them to [outputs] rollers with roller_acceleration; `vibkit ride` does that for its step)"
    ]


def _compression(ds, preload=0.0) -> list[str]:
    """Links in compression, and the preload that would keep them in tension: the scene's ``preload`` [N] plus
    twice the deepest compression, rounded up to one significant digit."""
    tension = np.asarray(ds["link_tension"].values, dtype=float)
    low = tension.min(axis=0)  # per link, over the run
    bad = np.flatnonzero(low < -COMPRESSION_TOLERANCE_N)
    if bad.size == 0:
        return []
    worst = int(np.argmin(low))
    it = int(np.argmin(tension[:, worst]))
    need = float(preload) + 2.0 * -float(low[worst])
    need = math.ceil(need / 10 ** math.floor(math.log10(need))) * 10 ** math.floor(math.log10(need))
    now = f"now {preload:.0f} N, " if preload > 0 else ""
    return [
        f"{bad.size} of {tension.shape[1]} links go into compression (down to {low[worst]:.0f} N, link "
        f"{worst + 1} at t = {float(ds.time.values[it]):.3g} s): a roller chain cannot push; give the "
        f"tensioner a {'larger ' if preload > 0 else ''}preload ([effects.tensioner] preload, {now}about {need:.0f} N "
        "or more)"
    ]


def _chain_speed(ds, model):
    if "sprocket_speed" in ds:
        return np.abs(np.asarray(ds["sprocket_speed"].values)) * model.sprocket.teeth * model.pitch / (2 * math.pi)
    if "chain_speed" in ds:
        return np.abs(np.asarray(ds["chain_speed"].values))
    return None


def _motor(ds, motor, model) -> list[str]:
    out = []
    t = np.asarray(ds.time.values, dtype=float)
    if t.size < 2:
        return out
    dt = float(t[1] - t[0])
    if "motor_torque" in ds and math.isfinite(motor.torque_limit):
        at_limit = np.abs(np.asarray(ds["motor_torque"].values)) >= 0.999 * motor.torque_limit
        if at_limit.any():
            frac = at_limit.mean()
            out.append(
                f"the motor is at its torque limit ({motor.torque_limit:g} N m) for {100 * frac:.0f} % of the run "
                f"(first at t = {t[np.argmax(at_limit)]:.3g} s): it cannot hold the set speed under this load"
            )
    v = _chain_speed(ds, model)
    set_speed = abs(motor.speed)
    if v is None or set_speed == 0:
        return out
    w = max(1, int(round(DROOP_WINDOW_S / dt)))
    if v.size < w:
        return out
    mean = np.convolve(v, np.ones(w) / w, mode="valid")  # windows of DROOP_WINDOW_S
    floor = (1.0 - DROOP_FRACTION) * set_speed
    reached = np.flatnonzero(mean >= floor)  # up to speed: the first window whose mean is
    if reached.size == 0:
        out.append(
            f"the chain never reaches {100 * (1 - DROOP_FRACTION):g} % of the set speed {set_speed:g} m/s "
            f"(at most {mean.max():.3g} m/s over {DROOP_WINDOW_S:g} s): the motor stalls (kp = {motor.kp:g} N m s"
            + (f", torque limit {motor.torque_limit:g} N m" if math.isfinite(motor.torque_limit) else "")
            + "); raise kp, add ki or lower the load"
        )
        return out
    after = mean[reached[0] :]  # once up to speed
    if after.size and after.min() < floor:
        j = reached[0] + int(np.argmin(after))
        out.append(
            f"the speed droops {100 * (1 - after.min() / set_speed):.1f} % below the set {set_speed:g} m/s "
            f"(mean over {DROOP_WINDOW_S:g} s from t = {t[j]:.3g} s; more than {100 * DROOP_FRACTION:g} %): "
            f"the motor (kp = {motor.kp:g} N m s, ki = {motor.ki:g} N m) cannot hold the speed under this load; "
            "raise kp or add ki"
        )
    return out
