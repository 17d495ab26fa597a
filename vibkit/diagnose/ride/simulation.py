"""A scene simulated for its ride: the step accelerometer's roller motion added to the scene's outputs,
the ride assessed over the step's ride on the incline, up or (a negative speed) down
(:mod:`vibkit.diagnose.ride`)."""

from __future__ import annotations

import dataclasses
import math
import os

from ...model.scene import Scene, load_scene
from ...signal.ride import NoIncline
from ..speed import scene_speed
from .quality import RideQuality, _naming, ride_quality_from_simulation

__all__ = ["simulate_ride", "with_ride_outputs"]


def _scene_source(scene, *args, **kwargs):
    return os.fspath(scene) if isinstance(scene, (str, os.PathLike)) else getattr(scene, "source", "")


@_naming(_scene_source)
def simulate_ride(scene, *, duration=None, segment=None, weightings=None, progress=False) -> RideQuality:
    """Simulate a scene with its step accelerometer's roller motion as outputs, then assess the ride.

    Parameters
    ----------
    scene : str, os.PathLike or Scene
        An inverse or forward scene with ``outputs.step_accelerometer``.
    duration : float, optional
        Simulated time [s]. Default: the scene's, and where the step does not ride the incline in it, the
        scene's plus one loop of the chain (said in the notes).
    segment, weightings
        As :func:`ride_quality`.
    progress : bool

    Returns
    -------
    RideQuality

    Raises
    ------
    SceneError, ValueError
        A kinematics scene, or no ``outputs.step_accelerometer``.
    """
    sc = scene if isinstance(scene, Scene) else load_scene(scene)
    if sc.analysis not in ("inverse", "forward"):
        raise ValueError(f"{sc.source}: ride quality needs an inverse or forward scene, not {sc.analysis}")
    if sc.outputs.get("step_accelerometer") is None:
        raise ValueError(f"{sc.source}: the scene names no step ('outputs.step_accelerometer'); add one")
    # the model (numba and its kernels) loaded only here: the report, which imports this package, keeps its run
    from ..fresh_simulation import simulate_fresh as simulate

    ds = simulate(with_ride_outputs(sc), duration=duration, progress=progress)
    try:
        return ride_quality_from_simulation(ds, segment=segment, weightings=weightings, source=sc.source)
    except NoIncline:
        speed = scene_speed(sc)
        if duration is not None or not speed:
            raise
    own = float(ds.time.values[-1] - ds.time.values[0])
    longer = math.ceil(own + sc.chain.n_rollers * sc.chain.link_pitch / abs(speed))  # plus one loop
    ds = simulate(with_ride_outputs(sc), duration=longer, progress=progress)
    rq = ride_quality_from_simulation(ds, segment=segment, weightings=weightings, source=sc.source)
    step = sc.outputs["step_accelerometer"]
    if sc.guide.incline_angle == 0.0:  # a level moving walk: its ride is the top run
        rq.notes.append(f"simulated {longer} s: in the scene's {own:g} s pallet {step} does not ride the top run")
    else:
        way = "down" if speed < 0 else "up"
        rq.notes.append(f"simulated {longer} s: in the scene's {own:g} s step {step} does not ride {way} the incline")
    return rq


def with_ride_outputs(sc):
    """The scene with its step's roller (``outputs.step_accelerometer``) acceleration and velocity added
    to its outputs: what the ride figure of a simulation is computed from, by ``vibkit ride SCENE``
    and by the report alike (the scene unchanged when it names no step or is a kinematics scene)."""
    step = sc.outputs.get("step_accelerometer")
    if step is None or sc.analysis not in ("inverse", "forward"):
        return sc
    roller = sc.chain.links_per_step * (int(step) - 1) + 2  # the step's middle roller (1-based), 3 or 4 a step
    out = dict(sc.outputs)
    out["variables"] = tuple(dict.fromkeys(tuple(out["variables"]) + ("roller_acceleration", "roller_velocity")))
    out["rollers"] = tuple(dict.fromkeys(tuple(out["rollers"]) + (roller,)))
    return dataclasses.replace(sc, outputs=out)
