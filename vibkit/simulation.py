"""``simulate(scene) -> xarray.Dataset``: the one orchestrator of the three analyses."""

from __future__ import annotations

from .model import EscalatorModel
from .scene import Scene, load_scene

__all__ = ["simulate"]


def simulate(scene, *, duration: float | None = None, progress: bool = True):
    """Run a scene.

    Parameters
    ----------
    scene : Scene or str or Path
        A scene, or the path of a TOML scene file.
    duration : float, optional
        Overrides the scene's length: the time span of an inverse or forward run [s], or the range
        of advance of a kinematic sweep [m].
    progress : bool
        Draw a progress bar on a terminal (never when stderr is not a terminal).

    Returns
    -------
    xarray.Dataset
        Kinematics: dimension ``advance`` [m]; inverse and forward dynamics: dimension ``time`` [s].
        Every variable carries ``units`` and ``long_name``; attrs carry the scene text and version.
    """
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    if duration is not None and not duration > 0:
        raise ValueError(f"duration must be positive, got {duration!r}")
    model = EscalatorModel(scene)
    outputs = scene.outputs["variables"]
    rollers = scene.outputs["rollers"]
    if scene.analysis == "kinematics":
        from .kinematics import kinematic_sweep

        k = scene.section("kinematics")
        stop = k["stop"] if duration is None else k["start"] + duration
        return kinematic_sweep(model, k["start"], stop, k["step"], rollers=rollers, outputs=outputs)
    if scene.analysis == "inverse":
        from .inverse import inverse_dynamics

        m = scene.section("motion")
        return inverse_dynamics(model, speed=m["speed"], duration=duration or m["duration"], step=m["step"],
                                start=m.get("start", 0.0), effects=scene.effects, outputs=outputs,
                                rollers=rollers, progress=progress)
    from .forward import forward_dynamics

    return forward_dynamics(model, duration=duration, progress=progress)
