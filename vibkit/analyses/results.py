"""Building result datasets: every variable carries ``units`` and ``long_name``."""

from __future__ import annotations

import datetime as _dt
import math

import numpy as np
import xarray as xr

from .. import __version__

__all__ = ["VARIABLES", "make_dataset", "output_times", "counted_speed"]

# name -> (units, long_name)
VARIABLES = {
    "delta": ("m", "tensioner displacement delta"),
    "delta_dot": ("m/s", "tensioner velocity"),
    "delta_ddot": ("m/s^2", "tensioner acceleration"),
    "s1": ("m", "roller 1 arc length on the deformed guide"),
    "s0": ("m", "roller 1 coordinate on the undeformed guide (unwrapped)"),
    "closure_residual": ("m", "max over links of | |r_i+1 - r_i| - L |"),
    "link_tension": ("N", "link tension (2 lambda L)"),
    "drive_force": ("N", "force along the guide that drags roller 1"),
    "chain_speed": ("m/s", "roller 1 speed"),
    "sprocket_angle": ("rad", "sprocket angle theta"),
    "sprocket_speed": ("rad/s", "sprocket angular speed"),
    "motor_torque": ("N m", "motor torque on the sprocket"),
    "drive_flank_force": ("N", "sum of roller normal forces on the driving flanks (CD)"),
    "back_flank_force": ("N", "sum of roller normal forces on the back flanks (AB)"),
    "indentation": ("m", "largest roller indentation on each tooth"),
    "contact_force": ("N", "sum of roller normal forces on each tooth"),
    "roller_position": ("m", "roller centre position"),
    "roller_velocity": ("m/s", "roller velocity"),
    "roller_acceleration": ("m/s^2", "roller acceleration"),
    "tensioner_displacement": ("m", "carriage displacement sensor (delta minus its mean)"),
    "accel_step": ("m/s^2", "accelerometer on a step, along the guide tangent"),
    "kinetic_energy": ("J", "kinetic energy of chain, carriage and sprocket"),
    "potential_energy": ("J", "gravitational potential energy of the rollers"),
    "contact_energy": ("J", "elastic energy stored in roller-tooth contacts"),
    "spring_energy": ("J", "elastic energy of the tensioner spring"),
}


def counted_speed(model, t, s0_1, nominal: float, *, from_rest: bool = False, speed_hint=None):
    """The chain speed [m/s] and link-pass frequency [Hz] a simulated record states: measured, not set.

    The links that passed a fixed point over the record (roller 1 at undeformed coordinates ``s0_1`` at the
    times ``t``; :meth:`vibkit.model.escalator.EscalatorModel.links_passed`; ``speed_hint`` [m/s], the chain's
    speed to within half a loop over the record, default roller 1's), over its duration, and that times the
    chain's mean link pitch; over the record's second half for a run that starts ``from_rest``. (Not
    :func:`vibkit.cli.options.run_speed`, the speed a command resolves from its flags.) A drive whose speed
    controller droops under load, or an inverse run that holds roller 1's speed along the guide (the chain on
    the straight runs slower while roller 1 rides a head), runs at other than the set ``nominal`` speed, and a
    pitch read from the record with the set speed would be off by as much. A record of fewer than three
    samples, or one whose chain does not move, states the ``nominal`` speed and its link pass. Returns (speed,
    link pass, the time the count starts [s])."""
    t = np.asarray(t, dtype=float)
    first = t.size // 2 if from_rest else 0
    if t.size >= 3 and t[-1] > t[first]:
        a, b = float(s0_1[first]), float(s0_1[-1])
        links = abs(model.links_passed(a, b, b - a if speed_hint is None else speed_hint * (t[-1] - t[first])))
        f_lp = links / (t[-1] - t[first])
        if f_lp > 0.0:
            return float(f_lp * model.mean_pitch), float(f_lp), float(t[first])
    return float(nominal), float(abs(nominal) / model.mean_pitch), float(t[0]) if t.size else 0.0


def make_dataset(coords: dict, data: dict, attrs: dict, scene) -> xr.Dataset:
    """Dataset from ``data`` (name -> (dims, array)) with units/long_name from :data:`VARIABLES`."""
    # built in one call (setting the variables one by one aligns them one by one: 10 ms of a 0.2 s run)
    variables = {}
    for name, (dims, arr) in data.items():
        units, long_name = VARIABLES.get(name, ("1", name))
        variables[name] = xr.Variable(dims, np.asarray(arr), attrs={"units": units, "long_name": long_name})
    ds = xr.Dataset(coords=coords).assign(variables)
    for name, (units, long_name) in {
        "time": ("s", "time"),
        "advance": ("m", "roller 1 coordinate s0 on the undeformed guide"),
        "link": ("1", "link number (link j joins roller j and j+1)"),
        "roller": ("1", "roller number"),
        "tooth": ("1", "tooth number"),
        "axis": ("1", "component"),
    }.items():
        if name in ds.coords:
            ds[name].attrs.update({"units": units, "long_name": long_name})
    base = {
        "vibkit_version": __version__,
        "scene_name": scene.name,
        "scene_source": scene.source,
        "scene": scene.text,
        "analysis": scene.analysis,
        "link_pitch_m": scene.chain.link_pitch,
        "n_rollers": scene.chain.n_rollers,
        "sprocket_teeth": scene.sprocket.teeth,
        "links_per_step": int(scene.chain.links_per_step),
        # the guide's incline [deg]: 0 is a level moving walk (its ride is the top run: no climb to find)
        "incline_deg": math.degrees(scene.guide.incline_angle),
        "history": f"simulated by vibkit {__version__}",
    }
    base.update(attrs)
    ds.attrs.update(base)
    return ds


def utc_now() -> str:
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")


def output_times(duration, step, key="run.output_step"):
    """The output times 0, step, 2 step, ... up to ``duration`` (never past it). [s]

    Raises
    ------
    ValueError
        A step longer than the run (one sample: nothing to analyse); ``key`` names the scene's key.
    """
    duration, step = float(duration), float(step)
    if step > duration:
        raise ValueError(
            f"the output step {step:g} s ('{key}') is longer than the run, {duration:g} s: the result would hold "
            "one sample; shorten the step or lengthen the run"
        )
    n = int(np.floor(duration / step * (1.0 + 1e-12) + 1e-9))
    return np.arange(n + 1) * step
